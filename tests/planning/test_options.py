"""The allocation planner's options as a value (``PlanOptions``) and its effort levels."""

import dataclasses
import json

import numpy as np
import pytest

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.coverage_boxes import box_routes
from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
from poc_env.agents.planning.options import EFFORTS, STANDARD, THOROUGH, PlanOptions
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.core import takeoff_heading
from poc_env.theory.probability_map import Grid, build_prior


def _routes(plan):
    return [u["waypoints_m"] for u in plan["uavs"]]


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"levels": ()}, "options.levels"),
        ({"levels": (3, 0)}, "options.levels"),
        ({"levels": (3.5,)}, "options.levels"),
        ({"etas": (0.3, 1.5)}, "options.etas"),
        ({"refine": -1}, "options.refine"),
        ({"refine": 2.5}, "options.refine"),
        ({"refine_starts": 0}, "options.refine_starts"),
        ({"spacings": (1.0, -2.0)}, "options.spacings"),
        ({"max_cells": 4}, "options.max_cells"),
        ({"chain": (0.35, 1.2)}, "options.chain"),
        ({"angles": (0.0,)}, "options.angles"),
        ({"angles": (45.0, 180.0)}, "options.angles"),
        ({"angles": (45.0, float("nan"))}, "options.angles"),
        ({"graded": "yes"}, "options.graded"),
        ({"sampled": 1}, "options.sampled"),
        ({"excursion_top": 0}, "options.excursion_top"),
        ({"margin": 0.05}, "options.margin"),
    ],
)
def test_bad_options_name_the_field_the_value_and_what_is_allowed(change, field):
    with pytest.raises(ConfigError) as err:
        PlanOptions(**change)
    assert err.value.field == field
    assert err.value.value == next(iter(change.values())) or field == "options.angles"
    assert "allowed: " in str(err.value)
    # the same check on a copy changed with dataclasses.replace
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        dataclasses.replace(PlanOptions(), **change)


def test_presets():
    assert PlanOptions.preset() == PlanOptions() == PlanOptions.preset("default")
    thorough = PlanOptions.preset("thorough")
    assert thorough.changed() == THOROUGH and PlanOptions().changed() == {}
    assert set(EFFORTS) == {"default", "standard", "thorough"}
    assert PlanOptions.preset("standard").changed() == STANDARD
    with pytest.raises(
        ConfigError, match="effort: got 'fast'; allowed: one of default, standard, thorough"
    ):
        PlanOptions.preset("fast")
    with pytest.raises(ConfigError, match="options"):
        make_allocation_plan("small", options={"refine": 1})


def test_default_options_plan_as_the_keywords_and_defaults_do():
    """Three ways to the same plan: no options at all; the options given whole; the planner's
    keywords given over options that differ (the keywords win). And the thorough preset with
    its changed fields set back to the defaults' plans the default plan: the preset differs
    in those fields only. ``small``'s own prior and a random prior of ``paper_6_2``."""
    sc = load_scenario("small")
    base = make_allocation_plan(sc)
    same = make_allocation_plan(sc, options=PlanOptions())
    assert _routes(same) == _routes(base) and same["posc"] == base["posc"]
    back = dataclasses.replace(
        PlanOptions.preset("thorough"), **{k: getattr(PlanOptions(), k) for k in THOROUGH}
    )
    assert _routes(make_allocation_plan(sc, options=back)) == _routes(base)
    one = make_allocation_plan(sc, refine=1, levels=(4,))
    over = make_allocation_plan(sc, refine=1, levels=(4,), options=PlanOptions(refine=3))
    assert _routes(over) == _routes(one)
    assert _routes(make_allocation_plan(sc, options=PlanOptions(refine=1, levels=(4,)))) == (
        _routes(one)
    )
    assert _routes(one) != _routes(base)  # the keywords do change the plan
    p62 = load_scenario("paper_6_2")
    prior = episode_prior(p62, 3)
    kw = {"refine": 1, "greedy_start": False}
    assert _routes(make_allocation_plan(p62, prior=prior, **kw)) == _routes(
        make_allocation_plan(p62, prior=prior, options=PlanOptions(refine=1, greedy_start=False))
    )


def test_box_routes_without_options_are_the_default_options_routes():
    sc = load_scenario("paper_6_2")
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map)
    to = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    la = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    args = (prior, grid, sc.sensor.sweep_width_m, sc.sensor.law, plan_speeds(sc), to, la,
            sc.uav.usable_endurance_s, sc.uav.max_turn_rate_rad_s, reserve_s(sc),
            takeoff_heading(grid.bounds, to))  # fmt: skip
    plain = box_routes(*args, rounds=0, chain=())
    assert box_routes(*args, rounds=0, chain=(), options=PlanOptions()) == plain
    # an option is read from the value passed down: fewer spacings, other routes
    assert box_routes(*args, rounds=0, chain=(), options=PlanOptions(spacings=(4.0,))) != plain


def test_thorough_plans_at_least_the_default_pos():
    """On ``small`` (its own prior and a random one) the thorough effort level plans at least
    the default's POS (the environment's model, less nothing: no violation in either)."""
    sc = load_scenario("small")
    for prior in (None, episode_prior(sc, 2)):
        default = make_allocation_plan(sc, prior=prior)
        thorough = make_allocation_plan(sc, prior=prior, options=PlanOptions.preset("thorough"))
        assert thorough["posc"] >= default["posc"] - 1e-12
        assert thorough["optimizer"]["settings"]["options"] == THOROUGH
        assert "options" not in default["optimizer"]["settings"]


def test_cli_plan_effort(tmp_path, capsys):
    from poc_env.cli import main

    args = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    out = tmp_path / "plan.json"
    assert main([*args, "--effort", "thorough", "--out", str(out)]) == 0
    plan = json.loads(out.read_text())
    assert plan["optimizer"]["settings"]["options"] == json.loads(json.dumps(THOROUGH))
    capsys.readouterr()
    bad = tmp_path / "bad.json"
    assert main([*args, "--effort", "max", "--out", str(bad)]) == 2
    assert "effort: got 'max'; allowed: one of default, standard, thorough" in (
        capsys.readouterr().err
    )
    assert main(["plan", "--scenario", "small", "--effort", "thorough", "--out", str(bad)]) == 2
    assert "effort: got 'thorough'; allowed: only with planner allocation" in (
        capsys.readouterr().err
    )
    assert not bad.exists()


def test_thorough_policy_is_registered():
    from poc_env.agents.policies.allocation import AllocationPlanPolicy
    from poc_env.agents.policies.registry import make_policy, registered

    assert "allocation_plan_thorough" in registered()
    pol = make_policy("allocation_plan_thorough")
    assert isinstance(pol, AllocationPlanPolicy)
    assert pol.options == PlanOptions.preset("thorough")
    assert pol.name == "allocation_plan_thorough"
    assert make_policy("allocation_plan").options == PlanOptions()


def test_also_default_keeps_the_default_plan_when_it_scores_more():
    """Options that plan worse (the boxes' lines four sweep widths apart only, on a random
    prior of ``paper_6_2`` where the boxes win) with ``also_default``: the default plan is kept
    (its routes, its POS, and ``kept`` says so); without it the worse plan is returned."""
    sc = load_scenario("paper_6_2")
    prior = episode_prior(sc, 4)
    worse = PlanOptions(spacings=(4.0,), dense_spacings=(), refine=1)
    default = make_allocation_plan(sc, prior=prior, refine=1)
    alone = make_allocation_plan(sc, prior=prior, options=worse)
    assert alone["posc"] < default["posc"]
    both = make_allocation_plan(
        sc, prior=prior, options=dataclasses.replace(worse, also_default=True)
    )
    assert both["optimizer"]["settings"]["kept"] == "default"
    assert both["posc"] == default["posc"] and _routes(both) == _routes(default)


def test_the_default_plan_keeps_every_polish_option_but_its_starts():
    """``also_default``'s default plan is polished as ``opt``'s is: every ``polish*`` field of
    ``opt`` (a field added later included) and the keyword-level ones carry over, everything
    else is the default's; ``polish_starts`` stays 1 (the recorded runs polished the default
    plan's own start only)."""
    from poc_env.agents.planning.allocation import default_options

    opt = PlanOptions.preset("thorough")
    opt = dataclasses.replace(
        opt, polish_starts=2, polish_radii=(0.5,), refine=3, spacings=(4.0,), levels=(2,)
    )
    base = default_options(opt)
    for f in dataclasses.fields(PlanOptions):
        if f.name.startswith("polish") and f.name != "polish_starts":
            assert getattr(base, f.name) == getattr(opt, f.name), f.name
    assert base.polish_starts == 1 and base.refine == 3 and base.levels == (2,)
    assert base.spacings == PlanOptions().spacings and base.also_default is False
