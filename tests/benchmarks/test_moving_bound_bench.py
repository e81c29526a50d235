"""``poc-env bench moving-bound`` (poc_env.agents.benchmarks.moving_bound): it runs, reports
every motion's bound and time, and the uniform drift's bound is the earlier adjoint's."""

from __future__ import annotations


def test_bench_moving_bound_smoke(capsys):
    from poc_env.agents.benchmarks.moving_bound import MOTIONS, main

    r = main(["--scenario", "small", "--runs", "1", "--swirl", "2", "--steps", "20"])
    for m in MOTIONS:
        assert 0.0 < r[f"{m}_pos"] <= r[f"{m}_upper"] <= 1.0
        assert r[f"{m}_s"] > 0
    assert r["reversal_diff"] < 1e-12
    assert r["varying_upper"] != r["uniform_upper"]  # the field reaches the bound
    out = capsys.readouterr().out
    assert "varying_upper" in out and "time_ratio" in out
