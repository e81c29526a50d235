"""The Gaussian-mixture prior's fast arithmetic against its plain numpy form, bit for bit.

:func:`~poc_env.theory.probability_map.gaussian_mixture` forms the offsets once per axis and
sums sub-cells with strided adds (:func:`~poc_env.theory.probability_map._coarsen_in_order`);
every random-prior reset draws one, so both must give exactly what the stacked sub-cell points
and :meth:`Grid.coarsen` give (equal floats, not close ones: recorded episodes and the
``make_vec``-vs-sync tests compare the priors' consequences exactly).
"""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.config import GaussianComponent
from poc_env.theory import probability_map as pm
from poc_env.theory.probability_map import Grid

GRIDS = [
    Grid(40, 30, 5000.0),
    Grid(8, 8, 5000.0),
    Grid(23, 9, 3000.0, (1000.0, -2000.0)),
    Grid(2, 1, 1000.0),
    Grid(1, 5, 3000.0),  # one column: numpy's own sum
]


def _reference(grid, components, background=0.0, oversample=6):
    """The mixture on the stacked sub-cell points with numpy's two-axis sum (the formulation
    the fast one replaces)."""
    pts = grid.sample_points(oversample)
    mass = np.zeros(grid.shape)
    weights = np.array([c.weight for c in components], dtype=float)
    weights = weights / weights.max()
    weights = weights / weights.sum()
    for w, comp in zip(weights, components, strict=True):
        d = pts - np.asarray(comp.mean_m)
        c, s = np.cos(comp.rotation_rad), np.sin(comp.rotation_rad)
        u = (c * d[..., 0] + s * d[..., 1]) / comp.sigma_m[0]
        v = (-s * d[..., 0] + c * d[..., 1]) / comp.sigma_m[1]
        part = grid.coarsen(np.exp(-0.5 * (u * u + v * v)), oversample)
        if part.sum() > 0:
            mass += w * part / part.sum()
    total = mass.sum()
    if total > 0:
        mass = mass / total * (1.0 - background)
    else:
        background = 1.0
    mass = mass + background / (grid.nx * grid.ny)
    return mass / mass.sum()


@pytest.mark.parametrize("grid", GRIDS, ids=str)
@pytest.mark.parametrize("s", [1, 2, 3, 4, 6, 7, 8])
def test_coarsen_in_order_is_grid_coarsen(grid, s):
    rng = np.random.default_rng(s)
    for trial in range(20):
        fine = rng.exponential(10.0 ** rng.uniform(-300, 300), (grid.ny * s, grid.nx * s))
        if trial % 4 == 1:  # zeros of both signs, infinities, NaN
            flat = fine.reshape(-1)
            k = rng.integers(0, flat.size, 8)
            flat[k] = rng.choice([0.0, -0.0, np.inf, np.nan, -np.inf, 1e308, 5e-324], 8)
        if trial % 4 == 2:
            fine = rng.uniform(-1.0, 1.0, fine.shape)
        with np.errstate(all="ignore"):  # the infinities and NaN
            got = pm._coarsen_in_order(grid, fine, s)
            want = grid.coarsen(fine, s)
        assert got.dtype == want.dtype and got.shape == want.shape
        assert np.array_equal(got, want, equal_nan=True), (grid, s, trial)
        assert np.array_equal(np.signbit(got), np.signbit(want))


@pytest.mark.parametrize("grid", GRIDS, ids=str)
def test_gaussian_mixture_is_the_stacked_points_formula(grid):
    rng = np.random.default_rng(11)
    x0, y0, x1, y1 = grid.bounds
    for trial in range(25):
        k = int(rng.integers(1, 5))
        comps = [
            GaussianComponent(
                mean_m=(rng.uniform(x0 - 5e3, x1 + 5e3), rng.uniform(y0 - 5e3, y1 + 5e3)),
                sigma_m=tuple(rng.uniform(0.02, 0.5, 2) * grid.width_m),
                weight=float(rng.uniform(0.1, 2.0)),
                rotation_rad=float(rng.uniform(-np.pi, np.pi)),
            )
            for _ in range(k)
        ]
        background = float(rng.uniform(0.0, 0.1))
        oversample = int(rng.choice([6, 4, 3, 9]))
        got = pm.gaussian_mixture(grid, comps, background, oversample)
        want = _reference(grid, comps, background, oversample)
        assert np.array_equal(got, want), (grid, trial)


def test_random_prior_draws_are_the_stacked_points_formula():
    """What a random-prior reset draws (:func:`random_gaussian_mixture`) is unchanged."""
    grid = Grid(40, 30, 5000.0)
    for seed in range(10):
        got = pm.random_gaussian_mixture(grid, np.random.default_rng(seed))
        real = pm.gaussian_mixture
        try:
            pm.gaussian_mixture = _reference
            want = pm.random_gaussian_mixture(grid, np.random.default_rng(seed))
        finally:
            pm.gaussian_mixture = real
        assert np.array_equal(got, want), seed


def test_sample_axes_are_the_sample_points():
    grid = Grid(23, 9, 3000.0, (1000.0, -2000.0))
    xs, ys = pm._sample_axes(grid, 6)
    pts = grid.sample_points(6)
    assert np.array_equal(pts[..., 0], np.broadcast_to(xs, pts.shape[:2]))
    assert np.array_equal(pts[..., 1], np.broadcast_to(ys[:, None], pts.shape[:2]))
    assert not xs.flags.writeable and not ys.flags.writeable


@pytest.mark.parametrize("sigma_m", [1e-3, 1.0])
def test_a_component_narrower_than_the_samples_keeps_its_mass_in_its_cell(sigma_m):
    """A component far narrower than the sub-cell spacing falls between the sample points
    (every density underflows to 0): it was dropped as if it lay off the grid, so the prior
    was the background alone (config-audit). Its mass belongs to the cell holding its mean."""
    grid = Grid(8, 8, 5000.0)
    comp = GaussianComponent(mean_m=(12_000.0, 25_000.0), sigma_m=(sigma_m, sigma_m))
    prior = pm.gaussian_mixture(grid, [comp], background=0.05)
    j, i = grid.cell_of(np.array(comp.mean_m))
    assert prior[j, i] == pytest.approx(0.95 + 0.05 / 64, rel=1e-12)
    assert prior.sum() == pytest.approx(1.0, rel=1e-12)
    alone = pm.gaussian_mixture(grid, [comp])  # no background: refused before the fix
    assert alone[j, i] == 1.0
