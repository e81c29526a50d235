"""The physical optimum: exact against SLSQP, and never beaten by a plan the code can score."""

import numpy as np
import pytest
from scipy.optimize import minimize

from poc_env.agents.planning.survey import RegionPlan, RegionSpec, run_survey
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import physical_optimum
from poc_env.theory.probability_map import build_prior
from poc_env.theory.search_theory import pod_from_coverage


def _slsqp_best(m, a, z, law, rng, starts=12):
    best = -np.inf
    cons = [{"type": "eq", "fun": lambda c: a @ c - z}]
    for _ in range(starts):
        x0 = rng.dirichlet(np.ones(len(m))) * z / a
        r = minimize(
            lambda c: -np.sum(m * pod_from_coverage(c, law)),
            x0,
            method="SLSQP",
            bounds=[(0, None)] * len(m),
            constraints=cons,
            options={"ftol": 1e-15, "maxiter": 1000},
        )
        if r.success or abs(a @ r.x - z) < 1e-9:
            best = max(best, -r.fun)
    return best


@pytest.mark.parametrize("law", ["inverse_cube", "exponential", "definite_range"])
def test_bound_equals_best_slsqp(law):
    rng = np.random.default_rng(7)
    for _ in range(5):
        n = int(rng.integers(3, 8))
        m = rng.dirichlet(np.ones(n))
        a = rng.uniform(0.5, 2.0, n)
        z = float(rng.uniform(0.3, 6.0))
        b = physical_optimum(m, a, z, law)
        spent = min(z, a.sum()) if law == "definite_range" else z  # C > 1 adds nothing there
        assert np.sum(a * b.coverage) == pytest.approx(spent, rel=1e-9)
        assert b.pos == pytest.approx(_slsqp_best(m, a, z, law, rng), abs=1e-6)
        assert b.pos >= _slsqp_best(m, a, z, law, rng) - 1e-9


def test_bound_properties():
    m = np.array([0.5, 0.3, 0.2])
    assert physical_optimum(m, 1.0, 0.0).pos == 0.0
    values = [physical_optimum(m, 1.0, z).pos for z in (0.5, 1, 2, 4, 50)]
    assert np.all(np.diff(values) > 0)
    assert values[-1] == pytest.approx(1.0, abs=1e-6)
    # the densest cell gets the most coverage
    cov = physical_optimum(m, 1.0, 1.0).coverage
    assert cov[0] > cov[1] > cov[2]
    with pytest.raises(ConfigError, match="effort_m2"):
        physical_optimum(m, 1.0, -1.0)
    with pytest.raises(ConfigError, match="prior"):
        physical_optimum(np.array([0.5, np.nan]), 1.0, 1.0)


def test_no_scored_plan_beats_the_bound():
    """Random rectangle plans on `small`: eq. 10 scoring <= bound; flown POS <= ceiling."""
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    w = sc.sensor.sweep_width_m
    rng = np.random.default_rng(3)
    for trial in range(12):
        specs = []
        for k in range(sc.n_uavs):
            cx, cy = rng.uniform(5e3, 35e3, 2)
            hl, hw = rng.uniform(2e3, 12e3, 2)
            t = rng.uniform(0, np.pi)
            c, s = np.cos(t), np.sin(t)
            corners = [
                (cx + c * u - s * v, cy + s * u + c * v)
                for u, v in ((-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw))
            ]
            specs.append(
                RegionSpec(
                    id=k + 1,
                    vertices_m=tuple(corners),
                    spacing_m=float(rng.uniform(0.5, 3.0) * w),
                    direction_rad=float(rng.uniform(0, np.pi)),
                )
            )
        res = run_survey(sc, RegionPlan(name=f"random{trial}", regions=tuple(specs)), prior=prior)
        assert res.posc <= res.bound + 1e-12
        assert res.posc_flown <= res.ceiling + 1e-12
        assert res.bound <= res.ceiling + 1e-12


@pytest.mark.parametrize("law", ["inverse_cube", "exponential"])
@pytest.mark.parametrize("effort", [1e-6, 1e-2, 1.0, 1e6, 1e12])
def test_tiny_and_huge_efforts_with_tied_densest_cells_spend_exactly_the_effort(law, effort):
    """The multiplier's root bracket holds even when several cells share the largest density
    and the effort is below what a rounding of the multiplier would spend there (the planner's
    nested subproblems hit this)."""
    prior = np.array([0.3, 0.3, 0.2, 0.0, 0.2])
    b = physical_optimum(prior, 25e6, effort, law)
    assert np.sum(b.coverage * 25e6) == pytest.approx(effort, rel=1e-9)
    assert 0.0 <= b.pos <= prior.sum()
    assert b.coverage[0] == pytest.approx(b.coverage[1], rel=1e-9)  # ties get equal coverage
