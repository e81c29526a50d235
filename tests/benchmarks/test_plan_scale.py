"""`poc-env bench plan --scale`: the parts run on request and every episode is recorded."""

import json

import pytest

from poc_env.agents.benchmarks import plan as bench_plan


def test_scale_quality_records_every_episode(tmp_path, capsys):
    out = tmp_path / "scale.json"
    summary = bench_plan.main(
        ["--scale", "--episodes", "1", "--seed0", "1", "--scale-maps", "small",
         "--scale-parts", "quality", "--scale-out", str(out)]
    )  # fmt: skip
    data = json.loads(out.read_text())
    eps = data["episodes"]
    assert [(e["seed"], e["policy"]) for e in eps] == [
        (1, "allocation_plan"),
        (1, "greedy_rectangles"),
    ]
    a, g = (e["posc"] / e["rule_bound"] for e in eps)
    assert summary["small_allocation_plan_rule"] == pytest.approx(a)
    assert summary["small_lead"] == pytest.approx(a - g)
    assert data["summary"] == pytest.approx(summary)
    assert all(0 < e["posc"] <= e["rule_bound"] * 1.05 for e in eps)
    printed = capsys.readouterr().out
    assert "small seed 1 greedy_rectangles" in printed
    assert "cells" not in printed  # only the part asked for


def test_scale_tight_puts_lone_uavs_against_both_bounds(capsys):
    """``--scale-parts tight``: each airfield's UAV alone over its rule-aware and its
    tour-charged bound (never above the rule-aware one, so the share over it is at least the
    share over the rule-aware bound), in both detection models."""
    summary = bench_plan.main(
        ["--scale", "--episodes", "1", "--seed0", "1", "--scale-maps", "small",
         "--scale-parts", "tight"]
    )  # fmt: skip
    assert 0 < summary["small_alone_rule"] <= summary["small_alone_tour"] <= 1.0 + 1e-9
    assert 0 < summary["small_alone_rule0"] <= summary["small_alone_tour0"] <= 1.0 + 1e-9
    printed = capsys.readouterr().out
    assert "small field A seed 1: planned" in printed
    assert "quality" not in printed and "greedy_rectangles:" not in printed
