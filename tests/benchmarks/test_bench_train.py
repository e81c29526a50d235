"""``poc-env bench train`` (poc_env.agents.benchmarks.train): it runs and reports what it
measured."""

from __future__ import annotations

import subprocess
import sys


def test_bench_train_smoke(capsys):
    from poc_env.agents.benchmarks.train import main

    r = main(["--scenario", "small", "--n-envs", "2", "--iterations", "1"])
    assert r["transitions_per_s"] > 0 and r["transitions"] == 256 * 6
    out = capsys.readouterr().out
    assert "PPO shared on small" in out and "agent transitions/s" in out and "time shares" in out


def test_poc_env_bench_train_runs_the_benchmark_module():
    done = subprocess.run(
        [sys.executable, "-m", "poc_env.cli", "bench", "train", "--help"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "usage: poc-env bench train" in done.stdout
