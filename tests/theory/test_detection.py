"""The table of detection laws: one entry per law, consistent with the compiled branches."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import erf

from poc_env._kernels.sensing import LAW_CODES
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.bound import physical_optimum
from poc_env.theory.detection import LAW_NAMES, LAWS, detection_law
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import (
    pod_derivative,
    pod_from_coverage,
    pod_parallel,
    segment_pod,
    sweep_segments,
)

C = np.linspace(0.0, 4.0, 401)


def test_table_covers_exactly_the_compiled_branches():
    assert set(LAWS) == set(LAW_CODES)
    assert tuple(LAWS) == LAW_NAMES
    for name, law in LAWS.items():
        assert law.name == name
        assert law.code == LAW_CODES[name]
    assert len({law.code for law in LAWS.values()}) == len(LAWS)


def test_config_accepts_the_table_names_and_only_them():
    for name in LAW_NAMES:
        assert load_scenario("small", {"sensor.law": name}).sensor.law == name
    with pytest.raises(ConfigError, match="'inverse_cube', 'exponential', 'definite_range'"):
        load_scenario("small", {"sensor.law": "cookie"})
    with pytest.raises(ConfigError):
        detection_law("cookie")


def test_pod_of_coverage_per_law():
    """Eq. 10 for the inverse-cube law; random search and cookie cutter for the others."""
    np.testing.assert_allclose(pod_from_coverage(C), erf(np.sqrt(np.pi) / 2 * C), rtol=1e-15)
    np.testing.assert_allclose(pod_from_coverage(C, "exponential"), 1 - np.exp(-C), rtol=1e-12)
    np.testing.assert_array_equal(pod_from_coverage(C, "definite_range"), np.minimum(C, 1))
    assert pod_parallel(5.0, 5.0) == pytest.approx(0.78991, abs=1e-5)
    np.testing.assert_allclose(pod_parallel(5.0, 5.0 / C[1:]), pod_from_coverage(C[1:]), rtol=1e-15)
    for name in LAW_NAMES:
        assert float(pod_from_coverage(-1.0, name)) == 0.0  # negative coverage counts as 0


@pytest.mark.parametrize("name", LAW_NAMES)
def test_slope_is_the_derivative_of_pod(name):
    h = 1e-6
    c = C[(C > 0.01) & (np.abs(C - 1.0) > 0.01)]
    numeric = (pod_from_coverage(c + h, name) - pod_from_coverage(c - h, name)) / (2 * h)
    np.testing.assert_allclose(pod_derivative(c, name), numeric, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("name", [n for n, law in LAWS.items() if law.optimal_coverage])
def test_optimal_coverage_equalises_the_marginal_return(name):
    """KKT: density x POD'(C(g)) = lambda where g = ln(density / lambda) > 0."""
    law = LAWS[name]
    g = np.linspace(0.01, 5.0, 50)
    density_over_lambda = np.exp(g)
    np.testing.assert_allclose(
        density_over_lambda * law.pod_slope(law.optimal_coverage(g)), 1.0, rtol=1e-12
    )


@pytest.mark.parametrize("name", LAW_NAMES)
def test_nothing_is_detected_beyond_the_reach(name):
    """The step-wise form: points beyond the law's reach of a step get POD 0."""
    w, cutoff, cell = 800.0, 3000.0, 1000.0
    reach = LAWS[name].reach(w, cutoff, cell)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-8000, 8000, (4000, 2))
    a, b = np.array([0.0, 0.0]), np.array([700.0, 300.0])
    pod = np.asarray(segment_pod(pts, a, b, w, name, cutoff, cell), dtype=float)
    from poc_env.theory.search_theory import distance_to_segment

    far = distance_to_segment(pts, a, b) > reach * (1 + 1e-9)
    assert np.all(pod[far] == 0.0)
    assert np.any(pod[~far] > 0.0)
    assert (np.asarray(segment_pod(pts, a, b, w, name, cutoff, cell)).dtype == bool) == LAWS[
        name
    ].indicator


@pytest.mark.parametrize("name", LAW_NAMES)
def test_bound_is_at_least_the_pod_of_an_even_spread(name):
    """The bound (its optimal_coverage or greedy fill) beats spreading the effort evenly."""
    rng = np.random.default_rng(1)
    prior = rng.random((6, 7))
    prior /= prior.sum()
    area = 1e6
    effort = 0.8 * area * prior.size
    bound = physical_optimum(prior, area, effort, name)
    even = float(np.sum(prior * pod_from_coverage(effort / (area * prior.size), name)))
    assert bound.pos >= even - 1e-12
    assert float(np.sum(bound.coverage * area)) == pytest.approx(effort, rel=1e-9)


def test_exponential_step_is_random_search_in_the_cell():
    """Step-wise exponential form: POD 1 - exp(-W L / A) over the cell the step is in."""
    grid = Grid(3, 3, 1000.0)
    belief = np.ones((1, 3, 3))
    sweep_segments(belief, grid, 1, [[[1200.0, 1500.0]]], [[[1800.0, 1500.0]]], 400.0,
                   "exponential")  # fmt: skip
    np.testing.assert_allclose(belief[0, 1, 1], np.exp(-400.0 * 600.0 / 1e6), rtol=1e-12)
    assert np.count_nonzero(belief[0] < 1.0) == 1
