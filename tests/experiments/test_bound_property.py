"""Issue 12: nothing the project ships beats the bounds it prints.

Property (hypothesis, random episodes of ``small``: random prior, seed, fleet size and split
over two airfields, endurance, detection law, optionally a short horizon): every shipped
policy flown in the environment (``random``, ``lawnmower``, ``greedy_bayes``, ``de_plan`` and
``allocation_plan``, the planners at quick settings) scores a POSC no higher than the
episode's honest plain bound and its reach-aware bound, as
:func:`poc_env.agents.experiments.evaluate.run_episode` reports them (the bounds ``poc-env
evaluate`` prints and normalises by); and every plan (``make_plan`` with a random optimiser,
``make_allocation_plan``) predicts a POS_C no higher than its own plan.json ``bounds`` and
``upper_bound``. Tolerance :data:`TOL` (float rounding only: the reach-aware bound may exceed
the plain one by ~1e-15).

The property is not vacuous: :func:`test_halved_bounds_are_caught` halves each bound at its
source (``poc_env.theory.bound``, and the names the allocation planner imported) and expects the
same checks to report violations on a fixed episode.
"""

from __future__ import annotations

import dataclasses
import itertools

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from poc_env.agents.experiments.evaluate import episode_prior, run_episode
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.agents.planning.planner import make_plan
from poc_env.config import Scenario, load_scenario

#: Float tolerance of every comparison with a bound.
TOL = 1e-9
#: The shipped policies flown in every episode.
POLICIES = ("random", "lawnmower", "greedy_bayes", "de_plan", "allocation_plan")
#: Optimisers whose plans are checked (one drawn per example).
OPTIMIZERS = ("adaptive_de", "classic_de", "chaotic_abc", "grouped_pso", "scipy_de", "cmaes")
#: Detection laws drawn (the environment's and the bounds').
LAWS = ("inverse_cube", "exponential", "definite_range")
#: Quick planner budget (``de_plan`` reads the scenario's planner section).
QUICK = {"planner.population": 12, "planner.generations": 8}


def scenario(
    counts: tuple[int, int], endurance_h: float, horizon: int | None, law: str = "inverse_cube"
) -> Scenario:
    """``small`` with ``counts`` UAVs from airfields A and B, the endurance, the horizon and
    the detection law."""
    fleet = [{"takeoff": "A", "count": counts[0]}]
    if counts[1]:
        fleet.append({"takeoff": "B", "count": counts[1], "landing": "A"})
    overrides = {
        **QUICK,
        "airfields": [
            {"name": "A", "position_km": [20, -5]},
            {"name": "B", "position_km": [-4, 30]},
        ],
        "fleet": fleet,
        "uav.endurance_h": endurance_h,
        "sensor.law": law,
        "comms.min_neighbours": 0,
    }
    if horizon is not None:
        overrides["episode.horizon_steps"] = horizon
    return load_scenario("small", overrides)


def violations(sc: Scenario, seed: int, optimizer: str, plans: bool = True) -> list[str]:
    """Every way the flights and plans of episode ``seed`` beat a bound (empty: none)."""
    out = []
    for policy in POLICIES:
        e = run_episode(sc, policy, seed, random_priors=True)
        assert e.bound is not None and e.bound_reach is not None
        for name, bound in (("honest", e.bound), ("reach", e.bound_reach)):
            if e.posc > bound + TOL:
                out.append(f"{policy} flown POSC {e.posc:.6f} > {name} bound {bound:.6f}")
    if not plans:
        return out
    prior = episode_prior(sc, seed)
    de = make_plan(sc, prior=prior, seed=seed, optimizer=optimizer, popsize=12, maxiter=8)
    alloc = make_allocation_plan(sc, prior=prior, seed=seed)
    for label, plan in ((optimizer, de), ("allocation", alloc)):
        bounds = {**plan["bounds"], "upper_bound": plan["upper_bound"]}
        for name, bound in bounds.items():
            if plan["posc"] > bound + TOL:
                out.append(f"{label} plan POS_C {plan['posc']:.6f} > its {name} {bound:.6f}")
    return out


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    counts=st.tuples(st.integers(1, 3), st.integers(0, 2)),
    endurance_h=st.floats(0.3, 0.8),
    seed=st.integers(0, 10_000),
    optimizer=st.sampled_from(OPTIMIZERS),
    law=st.sampled_from(LAWS),
)
def test_no_policy_or_plan_beats_the_bounds(counts, endurance_h, seed, optimizer, law):
    """Full horizon: flights and plans (their predicted POS_C) stay below every bound."""
    sc = scenario(counts, endurance_h, None, law)
    assert violations(sc, seed, optimizer) == []


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    counts=st.tuples(st.integers(1, 3), st.integers(0, 2)),
    horizon=st.integers(6, 30),
    seed=st.integers(0, 10_000),
    law=st.sampled_from(LAWS),
)
def test_no_policy_beats_the_bounds_on_a_short_horizon(counts, horizon, seed, law):
    """A horizon of 3-15 minutes, where the transit from the airfields binds: flights only.
    A plan's predicted POS_C assumes its whole endurance and ignores the horizon, so on such an
    episode it can exceed the plan.json bounds, which are the environment's (measured: an
    allocation plan predicting 0.666 against a reach-aware bound of 0.484 at 18 steps); the
    flown POSC cannot."""
    sc = scenario(counts, 0.6667, horizon, law)
    assert violations(sc, seed, "adaptive_de", plans=False) == []


def _halve(monkeypatch, which: str) -> None:
    """Halve the ``which`` bound (``honest`` or ``reach``) wherever it is computed (the
    planners take both from :func:`poc_env.agents.planning.geography.plan_geography`, which
    reads them from the bound module at call time)."""
    import poc_env.theory.bound as bound

    if which == "honest":
        orig_h = bound.honest_optimum

        def honest(*a, **k):
            b = orig_h(*a, **k)
            return dataclasses.replace(b, pos=0.5 * b.pos)

        monkeypatch.setattr(bound, "honest_optimum", honest)
    else:
        orig_r = bound.reach_bound

        def reach(*a, **k):
            b = orig_r(*a, **k)
            return dataclasses.replace(b, pos=0.5 * b.pos, upper=0.5 * b.upper)

        monkeypatch.setattr(bound, "reach_bound", reach)


@pytest.mark.parametrize("which", ["honest", "reach"])
def test_halved_bounds_are_caught(monkeypatch, which):
    """The checks above find violations when a bound is half its value (fixed episode)."""
    sc = scenario((3, 0), 0.6667, None)
    assert violations(sc, 3, "adaptive_de") == []
    _halve(monkeypatch, which)
    found = violations(sc, 3, "adaptive_de")
    flown = [v for v in found if "flown" in v and f"{which} bound" in v]
    planned = [v for v in found if "plan POS_C" in v and f"its {which}" in v]
    assert flown and planned, found
    assert all(which in v for v in found)


def test_table8_reports_each_fleets_reach_bound_and_stays_below_it(tmp_path):
    """``experiment table8``: the reach-aware bound beside every fleet size is the one
    ``evaluate`` and ``table7`` use (:func:`reach_effort_bound`) for that many UAVs, grows with
    the fleet, and no plan's POS_C beats it."""
    from poc_env.agents.experiments.evaluate import reach_effort_bound
    from poc_env.agents.experiments.paper import run_experiment

    res = run_experiment("table8", quick=True, out=tmp_path, echo=None)[0]
    sc = load_scenario("paper_6_2")
    reach = [r["bound_reach"] for r in res.rows]
    for r in res.rows:
        assert r["bound_reach"] == reach_effort_bound(sc.with_uavs(r["uavs"]))
        assert r["best_posc"] <= r["bound_reach"] + TOL
        assert r["best_over_reach"] == pytest.approx(r["best_posc"] / r["bound_reach"])
        assert r["mean_over_reach"] == pytest.approx(r["posc_mean"] / r["bound_reach"])
    assert all(b > a for a, b in itertools.pairwise(reach))
    assert "reach bound" in res.table and "best/reach" in res.table
    assert "bound_reach" in (tmp_path / "table8" / "table8.csv").read_text().splitlines()[0]
