"""``poc-env bench learning``: held-out curves of every checkpoint, the first to reach the
reference, the spread over runs, and one complete set of outputs."""

from __future__ import annotations

import csv

import pytest

from poc_env.agents.benchmarks import learning
from poc_env.agents.experiments.evaluate import evaluate
from poc_env.agents.rl.args import TrainArgs
from poc_env.agents.rl.train import train
from poc_env.errors import ConfigError

TASK = "UAVSearch-Small-Random-Heading-v0"


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("learning")
    out = []
    for seed in (0, 1):
        args = TrainArgs(
            task=TASK,
            total_timesteps=576,
            n_steps=32,
            batch_size=96,
            n_envs=2,
            seed=seed,
            checkpoint_every=128,
            keep_checkpoints=0,
            run_dir=str(base / f"s{seed}"),
            progress=False,
        )
        out.append(train(args))
    return out


def test_curves_and_the_steps_to_reach_the_reference(runs, tmp_path):
    out = tmp_path / "out"
    recipe = "h=" + ",".join(str(r) for r in runs)
    argv = ["--recipe", recipe, "--reference", "random", "--episodes", "2", "--quiet"]
    summary = learning.main([*argv, "--out", str(out)])
    rows = list(csv.DictReader((out / "learning.csv").open()))
    assert (out / "learning.png").read_bytes()[:4] == b"\x89PNG"
    for r in runs:
        mine = [x for x in rows if x["run"] == str(r)]
        steps = [int(x["step"]) for x in mine]
        assert steps == [s for s, _ in learning.checkpoints(r)] and len(steps) >= 3
        # each row is the checkpoint's own held-out evaluation
        ck = learning.checkpoints(r)[0][1]
        ev = evaluate("small", [f"ppo:{ck}"], episodes=2, seed0=5000, random_priors=True)
        assert float(mine[0]["posc_mean"]) == pytest.approx(ev.rows()[0]["posc_mean"])
    ref = evaluate("small", ["random"], episodes=2, seed0=5000, random_priors=True)
    bar = ref.rows()[0]["posc_mean"]
    for s in summary[:2]:
        mine = [x for x in rows if x["run"] == s["run"]]
        hit = next((int(x["step"]) for x in mine if float(x["posc_mean"]) >= bar), None)
        assert s["steps_to_reference"] == hit
        assert s["final_posc"] == pytest.approx(float(mine[-1]["posc_mean"]))
    assert summary[2]["run"] == "mean [min, max] of 2 runs"
    # a bar between the checkpoints' scores: the first checkpoint at or above it is reported
    mine = [{**x, "posc_mean": float(x["posc_mean"])} for x in rows if x["run"] == str(runs[1])]
    vals = sorted({x["posc_mean"] for x in mine})
    assert len(vals) >= 2
    mid = (vals[0] + vals[-1]) / 2
    first = next(x for x in mine if x["posc_mean"] >= mid)
    row = learning.run_summary(mine, mid)
    assert row["steps_to_reference"] == first["step"] and row["wall_s_to_reference"] is not None
    assert learning.run_summary(mine, vals[-1] + 1e-9)["steps_to_reference"] is None
    assert f"{bar:.4f}" in (out / "learning.md").read_text()


def test_bad_input_writes_nothing(runs, tmp_path):
    out = tmp_path / "none"
    with pytest.raises(ConfigError, match="recipe"):
        learning.main(["--recipe", "h", "--out", str(out)])
    with pytest.raises(ConfigError, match="recipe"):
        learning.main(["--recipe", f"h={tmp_path}", "--out", str(out)])
    with pytest.raises(ConfigError, match="polic"):
        learning.main(["--recipe", f"h={runs[0]}", "--reference", "nope", "--out", str(out)])
    assert not out.exists()


@pytest.mark.parametrize(
    "task", ["UAVSearch-Wide-N3-Random-Set-Heading-v1", "UAVSearch-Small-Drift-Heading-v1"]
)
def test_the_curve_flies_the_runs_task(tmp_path, monkeypatch, task):
    """Audit (i28-audit): the checkpoints and the reference were flown on the task's scenario
    by name, so a ``Wide-N3`` run was scored with the scenario's 12 UAVs and a ``Drift`` run
    on a standing target. They fly ``Task.load_scenario()``, the task itself."""
    import json
    import types

    from poc_env import tasks
    from poc_env.agents.experiments import evaluate as evaluate_mod

    run = tmp_path / "run"
    (run / "checkpoints").mkdir(parents=True)
    (run / "checkpoints" / "step_64.zip").write_bytes(b"")
    (run / "config.json").write_text(json.dumps({"task": task}))
    flown = []

    def fake(scenario, policies, **kw):  # what the curve is made of: one row per policy
        flown.append(scenario)
        row = {"posc_mean": 0.5, "posc_ci95": 0.0, "normalised": 0.5, "rule_normalised": 0.5}
        return types.SimpleNamespace(rows=lambda: [dict(row, policy=p) for p in policies])

    monkeypatch.setattr(evaluate_mod, "evaluate", fake)
    argv = ["--recipe", f"r={run}", "--reference", "random", "--episodes", "1", "--quiet"]
    learning.main([*argv, "--out", str(tmp_path / "out")])
    want = tasks.get_task(task).load_scenario()
    assert flown and all(sc == want for sc in flown)
