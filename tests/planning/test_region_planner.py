"""§6.1 region planning: each region's spacing and direction optimised within 0.85 T."""

import dataclasses

import pytest

from poc_env.agents.planning.region_planner import _time, optimise_regions
from poc_env.agents.planning.survey import _airfields_for, load_regions, run_survey
from poc_env.cli import main
from poc_env.config import load_scenario
from poc_env.errors import ConfigError


@pytest.fixture(scope="module")
def optimised():
    return optimise_regions("paper_6_1", step_deg=30)


def test_optimised_plan_is_feasible_and_beats_table3(optimised):
    res = run_survey("paper_6_1", optimised)
    assert all(r.feasible for r in res.rows)
    table3 = run_survey("paper_6_1")
    assert res.posc > table3.posc
    assert res.posc <= res.bound


def test_each_spacing_is_the_smallest_that_fits(optimised):
    sc = load_scenario("paper_6_1")
    takeoffs, landings = _airfields_for(sc, optimised)
    limit = sc.uav.usable_endurance_s
    for spec, t0, t1 in zip(optimised.regions, takeoffs, landings):
        assert _time(spec, sc, t0, t1) <= limit
        tighter = dataclasses.replace(spec, spacing_m=spec.spacing_m - 1e-2)
        assert _time(tighter, sc, t0, t1) > limit


def test_mixed_partition_uses_circle_patterns():
    plan = load_regions("paper_6_1_mixed")
    res = run_survey("paper_6_1", plan)
    assert [r.pattern for r in res.rows][2::2] == ["sector", "expanding_square"]
    assert not res.rows[2].feasible  # Table 5's 2,511 km sector needs ~14 h, more than 0.85 T
    opt = optimise_regions("paper_6_1", plan, step_deg=45)
    assert all(r.feasible for r in run_survey("paper_6_1", opt).rows)


def test_region_that_cannot_fit_is_a_clear_error():
    sc = load_scenario("paper_6_1", {"uav.endurance_h": 1})
    with pytest.raises(ConfigError, match=r"regions\[1\]"):
        optimise_regions(sc, "paper_6_1_polygons", step_deg=90)


def test_cli_survey_optimise(capsys):
    assert main(["survey", "--optimise"]) == 0
    out = capsys.readouterr().out
    assert "Table 3 analog" in out and "POS_C" in out
