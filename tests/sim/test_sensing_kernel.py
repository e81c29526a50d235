"""The fused sensing kernel (search_theory.sweep_segments) against the numpy path.

The numpy path is sweep_windows (segment_pod on fixed windows) + apply_windows, one segment
after another; the kernel must give the same belief and the same POS per segment, for every
law, at the grid's edges and for zero-length steps, conserve mass, and credit a point swept by
two UAVs in one step to the first.
"""

import math

import numpy as np
import pytest

from poc_env._kernels.sensing import one_minus_exp_neg
from poc_env.theory.detection import LAW_NAMES
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import (
    apply_windows,
    segment_exponent,
    segment_pod,
    sweep_segments,
    sweep_windows,
)

LAWS = list(LAW_NAMES)  # every law of the table
GRID = Grid(9, 7, 1000.0, origin_m=(-2500.0, 1300.0))  # an origin off the cell lattice
S = 3


def _belief(rng, n_env):
    b = rng.random((n_env, GRID.ny * S, GRID.nx * S))
    return b / b.sum(axis=(1, 2), keepdims=True)


def _segments(rng, n_env, n_agent):
    """Random steps over and around the grid: crossing its edges, outside it, zero-length."""
    x0, y0, x1, y1 = GRID.bounds
    a = np.stack(
        [
            rng.uniform(x0 - 1500, x1 + 1500, (n_env, n_agent)),
            rng.uniform(y0 - 1500, y1 + 1500, (n_env, n_agent)),
        ],
        axis=-1,
    )
    ang = rng.uniform(-np.pi, np.pi, (n_env, n_agent))
    length = rng.uniform(0.0, 1500.0, (n_env, n_agent))
    b = a + length[..., None] * np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    b[:, 0] = a[:, 0]  # zero-length steps
    a[0, 1] = (x0 + 10.0, y0 + 10.0)  # along the south-west corner, on the edge
    b[0, 1] = (x0 + 10.0, y0 + 1210.0)
    a[-1, -1] = (x1 - 100.0, y1 + 200.0)  # just outside the north-east corner
    b[-1, -1] = (x1 + 900.0, y1 - 300.0)
    return a, b


def _reference(belief, a, b, w, law, cutoff):
    """The numpy path: each env's segments in agent order, windows from sweep_windows."""
    belief = belief.copy()
    found = np.zeros(a.shape[:2])
    for e in range(len(a)):
        for i in range(a.shape[1]):  # one at a time: the overlap rule
            win = sweep_windows(GRID, S, a[e, i : i + 1], b[e, i : i + 1], w, law, cutoff)
            found[e, i] = apply_windows(belief[e], win)[0]
    return belief, found


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("cutoff", [1800.0, np.inf])
def test_kernel_equals_numpy_path(law, cutoff):
    rng = np.random.default_rng(7)
    n_env, n_agent = 4, 5
    a, b = _segments(rng, n_env, n_agent)
    belief = _belief(rng, n_env)
    w = 700.0
    ref_belief, ref_found = _reference(belief, a, b, w, law, cutoff)
    got = belief.copy()
    found = sweep_segments(got, GRID, S, a, b, w, law, cutoff)
    np.testing.assert_allclose(got, ref_belief, rtol=0, atol=1e-12)
    np.testing.assert_allclose(found, ref_found, rtol=0, atol=1e-12)
    assert np.all(found[:, 0] == 0.0)  # zero-length steps find nothing
    assert found.max() > 0.01  # the test is not vacuous


@pytest.mark.parametrize("law", LAWS)
def test_mass_conservation_and_bounds(law):
    rng = np.random.default_rng(11)
    belief = _belief(rng, 3)
    total = belief.sum()
    posc = 0.0
    for _ in range(20):
        a, b = _segments(rng, 3, 4)
        posc += sweep_segments(belief, GRID, S, a, b, 900.0, law, 2500.0).sum()
        assert np.all(belief >= 0)
    assert posc + belief.sum() == pytest.approx(total, abs=1e-12)
    assert posc > 0


@pytest.mark.parametrize("law", LAWS)
def test_agent_order_credits_the_first(law):
    """Two UAVs flying the same step: the second finds exactly what the first left."""
    rng = np.random.default_rng(3)
    belief = _belief(rng, 1)
    seg_a = np.array([[[0.0, 3000.0]] * 2])
    seg_b = np.array([[[1200.0, 3900.0]] * 2])
    w = 800.0
    once = belief.copy()
    first = sweep_segments(once, GRID, S, seg_a[:, :1], seg_b[:, :1], w, law, 3000.0)
    twice = once.copy()
    second = sweep_segments(twice, GRID, S, seg_a[:, :1], seg_b[:, :1], w, law, 3000.0)
    both = belief.copy()
    found = sweep_segments(both, GRID, S, seg_a, seg_b, w, law, 3000.0)
    np.testing.assert_array_equal(found[0], [first[0, 0], second[0, 0]])
    np.testing.assert_array_equal(both, twice)
    # the second is credited with (1 - p) of the first's share, point by point
    win = sweep_windows(GRID, S, seg_a[0, :1], seg_b[0, :1], w, law, 3000.0)
    ky, kx = win.pod.shape[-2:]
    view = belief[0, win.j0[0] : win.j0[0] + ky, win.i0[0] : win.i0[0] + kx]
    p = win.pod[0]
    assert found[0, 1] == pytest.approx(np.sum(view * (1 - p) * p), abs=1e-14)
    if law == "definite_range":
        assert found[0, 1] == 0.0


def test_kernel_is_deterministic_and_batched_equals_single():
    rng = np.random.default_rng(5)
    a, b = _segments(rng, 3, 4)
    belief = _belief(rng, 3)
    one, two = belief.copy(), belief.copy()
    f1 = sweep_segments(one, GRID, S, a, b, 600.0, "inverse_cube", 2000.0)
    f2 = sweep_segments(two, GRID, S, a, b, 600.0, "inverse_cube", 2000.0)
    np.testing.assert_array_equal(one, two)
    np.testing.assert_array_equal(f1, f2)
    for e in range(3):
        single = np.ascontiguousarray(belief[e : e + 1])
        fe = sweep_segments(
            single, GRID, S, a[e : e + 1], b[e : e + 1], 600.0, "inverse_cube", 2000.0
        )
        np.testing.assert_array_equal(single[0], one[e])
        np.testing.assert_array_equal(fe[0], f1[e])


def test_shared_exponent_matches_the_design_formula():
    """segment_exponent (the kernel's scalar) against the segment formula written plainly."""
    rng = np.random.default_rng(0)
    w = 5000.0
    x = rng.uniform(50.0, 20_000.0, 5000) * rng.choice([-1, 1], 5000)
    y1 = rng.uniform(-20_000.0, 20_000.0, 5000)
    y2 = y1 + rng.uniform(100.0, 5000.0, 5000)
    plain = w * w / (8 * np.pi * x * x) * (y2 / np.hypot(x, y2) - y1 / np.hypot(x, y1))
    np.testing.assert_allclose(segment_exponent(x, y1, y2, w), plain, rtol=1e-8)
    # and segment_pod is 1 - exp(-F) of it, for a point in the segment's frame
    pts = np.stack([np.zeros_like(x), x], axis=-1)  # segment on the x axis, point at (0, x)
    a = np.stack([y1, np.zeros_like(y1)], axis=-1)
    b = np.stack([y2, np.zeros_like(y2)], axis=-1)
    pod = segment_pod(pts, a, b, w)
    np.testing.assert_allclose(pod, -np.expm1(-segment_exponent(x, y1, y2, w)), rtol=1e-12)


def testone_minus_exp_neg_is_expm1_to_two_ulp():
    f = np.concatenate(
        [np.geomspace(1e-300, 1e-3, 400), np.linspace(0.0, 60.0, 4001), [0.3466, 0.3467, 1e300]]
    )
    got = np.array([one_minus_exp_neg(v) for v in f])
    ref = -np.expm1(-f)
    assert np.all(np.abs(got - ref) <= 2 * np.spacing(ref))
    assert one_minus_exp_neg(math.inf) == 1.0
    assert one_minus_exp_neg(0.0) == 0.0


def test_exponential_cells_are_aligned_on_the_grid_origin():
    """Random search spreads a step's effort over the grid cell it is in, wherever the grid is."""
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.search_theory import sweep_segments

    grid = Grid(4, 4, 1000.0, origin_m=(1300.0, 700.0))
    s = 2
    belief = np.ones((1, 8, 8))
    a = np.array([[[2400.0, 2200.0]]])  # inside cell (row 1, col 1) of this grid
    b = np.array([[[2600.0, 2200.0]]])
    sweep_segments(belief, grid, s, a, b, 500.0, "exponential", np.inf)
    hit = belief[0] < 1.0
    assert hit[2:4, 2:4].all() and hit.sum() == 4  # exactly that cell's 2 x 2 samples
    np.testing.assert_allclose(belief[0][2:4, 2:4], np.exp(-500.0 * 200.0 / 1e6))
