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


def test_random_zones_lie_inside_the_area_and_follow_the_seed():
    import numpy as np
    import shapely

    from poc_env.agents.benchmarks.plan_scale import random_zones

    zones = random_zones(200.0, 150.0, 12, np.random.default_rng(3))
    assert len(zones) == 12
    assert zones == random_zones(200.0, 150.0, 12, np.random.default_rng(3))
    area = shapely.box(0, 0, 200, 150)
    for z in zones:
        poly = shapely.Polygon(z)
        assert poly.is_valid and area.contains(poly)
        assert 0.06 * 150 <= max(np.ptp(np.array(z), axis=0)) <= 0.15 * 150
    assert {len(z) for z in zones} >= {3, 4, 6, 8}  # triangles, rectangles, Ls and Us


def test_zones_part_plans_with_and_without_the_zones(capsys):
    from poc_env.agents.benchmarks import plan_scale

    out = plan_scale.timing_zones(1, 2, seed=5, cases={"small": ("small", {}, None)})
    assert out["small_zones_ratio"] == pytest.approx(
        out["small_zones_plan_s"] / out["small_plain_plan_s"]
    )
    # the zones reach the planner: the planned POS changes (zone-interior mass discounted)
    assert out["small_zones_posc"] != out["small_plain_posc"]
    assert "small plan_s +2 zones" in capsys.readouterr().out
