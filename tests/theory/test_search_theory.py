"""Search theory (eq. 7-16) and the step-wise detection law against hand-computed values."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import (
    coverage_factor,
    cutoff_error,
    effective_sweep_area,
    lateral_range,
    parallel_coverage,
    pod_from_coverage,
    pod_parallel,
    pos,
    posc,
    segment_exponent,
    segment_pod,
    swarm_pos,
    sweep_track,
    update_poc,
)


def test_coverage_equations_7_to_9():
    assert coverage_factor(50.0, 200.0) == pytest.approx(0.25)  # eq. 7
    assert effective_sweep_area(50.0, 3600.0, 5000.0) == pytest.approx(9.0e8)  # eq. 8
    assert parallel_coverage(5000.0, 2500.0) == pytest.approx(2.0)  # eq. 9


def test_pod_eq10_hand_values():
    assert pod_parallel(5000.0, 5000.0) == pytest.approx(math.erf(math.sqrt(math.pi) / 2))
    assert pod_parallel(1.0, 1.0) == pytest.approx(0.78991, abs=5e-6)


@pytest.mark.parametrize(
    ("spacing_km", "table4_pod"),
    [(12, 0.9784), (11, 0.9878), (8.5, 0.9988), (16, 0.9152), (8.6, 0.9987)],
)
def test_table4_pod_column_is_eq10_with_w_22km(spacing_km, table4_pod):
    assert pod_parallel(22.0, spacing_km) == pytest.approx(table4_pod, abs=6e-5)


def test_pod_laws_as_functions_of_coverage():
    c = np.array([0.0, 0.5, 1.0, 2.0])
    np.testing.assert_allclose(pod_from_coverage(c, "exponential"), 1 - np.exp(-c))
    np.testing.assert_allclose(pod_from_coverage(c, "definite_range"), [0, 0.5, 1, 1])
    np.testing.assert_allclose(
        pod_from_coverage(c, "inverse_cube"), [math.erf(math.sqrt(math.pi) / 2 * x) for x in c]
    )
    with pytest.raises(ConfigError, match="law"):
        pod_from_coverage(c, "magic")


def test_lateral_range_integrates_to_sweep_width():
    w = 5000.0
    half, _ = quad(lambda x: float(lateral_range(x, w)), 0, np.inf, limit=200)
    assert 2 * half == pytest.approx(w, rel=1e-6)


def test_segment_exponent_limits_and_additivity():
    w, x = 5000.0, 1300.0
    long = segment_exponent(x, -1e9, 1e9, w)
    assert long == pytest.approx(w * w / (4 * math.pi * x * x), rel=1e-9)
    # consecutive pieces add up to the whole segment, on either side of the foot
    for y in ([-3000, -500, 2000], [500, 1200, 9000], [-9000, -4000, -100]):
        whole = segment_exponent(x, y[0], y[2], w)
        parts = segment_exponent(x, y[0], y[1], w) + segment_exponent(x, y[1], y[2], w)
        assert parts == pytest.approx(whole, rel=1e-12)
    # mirror symmetry and the finite x -> 0 limit when both ends are on one side
    assert segment_exponent(x, 500, 1200, w) == pytest.approx(segment_exponent(x, -1200, -500, w))
    lim = w * w / (16 * math.pi) * (1 / 500**2 - 1 / 1200**2)
    assert segment_exponent(1e-9, 500, 1200, w) == pytest.approx(lim, rel=1e-9)
    assert np.isinf(segment_exponent(0.0, -10, 10, w))
    assert segment_exponent(x, 7, 7, w) == 0.0


def test_segment_pod_other_laws():
    pts = np.array([[0.0, 1.0], [0.0, 3.0], [5.0, 1.0]])
    hit = segment_pod(pts, np.array([-10.0, 0.0]), np.array([10.0, 0.0]), 4.0, "definite_range")
    assert hit.tolist() == [True, False, True]
    # exponential: effort W L in the cell spread over the cell area
    p = segment_pod(
        np.array([[5.0, 5.0]]),
        np.array([0.0, 5.0]),
        np.array([10.0, 5.0]),
        2.0,
        "exponential",
        cell_m=10.0,
    )
    assert p[0] == pytest.approx(1 - math.exp(-2.0 * 10.0 / 100.0))


def test_pos_posc_and_poc_update_eq12_to_14():
    poc = np.array([0.2, 0.5, 0.3])
    pod = np.array([0.5, 0.1, 0.0])
    np.testing.assert_allclose(pos(poc, pod), [0.1, 0.05, 0.0])
    assert posc(pos(poc, pod)) == pytest.approx(0.15)
    np.testing.assert_allclose(update_poc(poc, pod), [0.1, 0.45, 0.3])


def test_swarm_pos_overlap_rule():
    prior = np.array([[0.5, 0.5]])
    m = np.array([[[1.0, 0.0]], [[1.0, 1.0]]])  # UAV 2's region contains UAV 1's
    poc_i, pos_i, j = swarm_pos(m, np.array([0.8, 0.5]), prior)
    np.testing.assert_allclose(poc_i, [0.5, 0.5])  # the shared cell counts once
    np.testing.assert_allclose(pos_i, [0.4, 0.25])
    assert j == pytest.approx(0.65)
    # regions splitting a cell between them are each credited with their own share
    split = np.array([[[0.3, 0.0]], [[0.7, 1.0]]])
    poc_s, _, _ = swarm_pos(split, np.array([1.0, 1.0]), prior)
    np.testing.assert_allclose(poc_s, [0.15, 0.85])
    # batched over a population axis
    poc_b, _, j_b = swarm_pos(np.stack([m, m[::-1]]), np.array([[0.8, 0.5], [0.5, 0.8]]), prior)
    np.testing.assert_allclose(poc_b, [[0.5, 0.5], [1.0, 0.0]])
    np.testing.assert_allclose(j_b, [0.65, 0.5])


def _lawnmower(spacing, lo, hi, y_lo, y_hi):
    wps = []
    for k, x in enumerate(np.arange(lo + spacing / 2, hi, spacing)):
        ys = (y_lo, y_hi) if k % 2 == 0 else (y_hi, y_lo)
        wps += [(x, ys[0]), (x, ys[1])]
    return np.array(wps)


@pytest.mark.parametrize("ratio", [0.6, 1.0, 2.0])
def test_composition_identity_segments_reproduce_eq10(ratio):
    """Parallel tracks flown as many short segments give eq. 10's mean POD within 1 %."""
    w = 5000.0
    s = 4
    grid = Grid(20, 20, 5000.0)
    fine = np.full((20 * s, 20 * s), 1.0 / (400 * s * s))
    belief = fine.copy()
    track = _lawnmower(ratio * w, 0.0, 100_000.0, -40_000.0, 140_000.0)
    sweep_track(belief, grid, s, track, w, "inverse_cube", cutoff_m=np.inf, step_m=4000.0)
    pod = grid.coarsen(1.0 - belief / fine, s) / (s * s)
    inner = pod[5:15, 5:15].mean()  # cells inside the swept area, away from its edges
    assert inner == pytest.approx(float(pod_parallel(w, ratio * w)), rel=0.01)


def test_cutoff_error_is_small_and_shrinks():
    errs = [cutoff_error(c, 1.0) for c in (2, 4, 8)]
    assert errs[0] > errs[1] > errs[2] > 0
    # the default 4 W cut-off with the env's 3 km steps at W = 5 km: ~1.6 % of eq. 10 at S = W
    assert cutoff_error(4.0, 1.0, 0.6) < 0.017
    assert cutoff_error(4.0, 1.0, 0.6) < cutoff_error(4.0, 1.0, 0.0)  # longer steps keep more


def test_cutoff_error_matches_a_stepwise_sweep():
    """The documented cut-off error is what the step-wise sweep actually loses."""
    w, s = 5000.0, 4
    grid = Grid(40, 40, 5000.0)  # 200 km: the measured middle is 75 km from the pattern's edges
    track = _lawnmower(w, 0.0, 200_000.0, -40_000.0, 240_000.0)
    pods = []
    for cut in (np.inf, 4 * w):
        fine = np.full((40 * s, 40 * s), 1.0)
        sweep_track(fine, grid, s, track, w, "inverse_cube", cutoff_m=cut, step_m=4000.0)
        pods.append(1.0 - fine[60:100, 60:100].mean())
    # infinitely many uncut tracks at the 4 x 4 sample points (1/8, 3/8, 5/8, 7/8 of S):
    # sum_k 1 / (x - kS)^2 = (pi / S)^2 / sin^2(pi x / S)
    phase = (np.arange(4) + 0.5) / 4
    uncut = np.mean(1 - np.exp(-np.pi / (4 * np.sin(np.pi * phase) ** 2)))
    assert pods[0] == pytest.approx(uncut, rel=0.01)  # (the pattern is 200 km, not infinite)
    # with the cut-off no track farther than 4 W counts, so the finite pattern is exact here
    expected = uncut * (1 - cutoff_error(4.0, 1.0, step_sweep_widths=0.8, n=4))
    assert pods[1] == pytest.approx(expected, rel=5e-4)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    law=st.sampled_from(["inverse_cube", "exponential", "definite_range"]),
    n=st.integers(1, 12),
)
def test_mass_conservation_after_any_searches(seed, law, n):
    rng = np.random.default_rng(seed)
    grid = Grid(6, 5, 1000.0)
    s = 3
    prior = rng.dirichlet(np.ones(30)).reshape(5, 6)
    belief = grid.refine(prior, s)
    total = 0.0
    for _ in range(n):
        wps = rng.uniform(-500, 6500, size=(int(rng.integers(2, 6)), 2))
        total += sweep_track(belief, grid, s, wps, float(rng.uniform(100, 3000)), law, 2500.0)
        assert np.all(belief >= 0) and np.all(belief <= 1)
    assert total + belief.sum() == pytest.approx(1.0, abs=1e-9)
