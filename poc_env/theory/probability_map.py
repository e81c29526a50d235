"""The grid and the prior probability-of-containment (POC) map.

Array convention: a map is ``(ny, nx)``; row ``j`` is the ``j``-th cell from the south edge,
column ``i`` the ``i``-th from the west edge; cell ``(j, i)`` covers
``[x0 + i c, x0 + (i + 1) c] x [y0 + j c, y0 + (j + 1) c]``.

The paper's maps (Figs. 15 and 20) are not published. The built-in scenarios build seeded,
documented Gaussian-mixture priors that resemble them (a few elongated high-POC clusters over a
low background); :func:`random_gaussian_mixture` draws fresh ones for RL generalisation; a
user's map is read by :func:`load_map` from ``.npy`` or ``.csv``.
"""

from __future__ import annotations

import contextlib
import functools
import os
import warnings
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
from shapely.geometry import box

import poc_env._kernels.priors as _priors
from poc_env.config import GaussianComponent, MapConfig, PriorConfig
from poc_env.errors import ConfigError, MapFileError


@dataclass(frozen=True)
class Grid:
    """A regular grid of square cells of side ``cell_m`` with its south-west corner at origin."""

    nx: int
    ny: int
    cell_m: float
    origin_m: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def from_config(cls, cfg: MapConfig) -> Grid:
        return cls(cfg.nx, cfg.ny, cfg.cell_m, tuple(cfg.origin_m))  # type: ignore[arg-type]

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @property
    def width_m(self) -> float:
        return self.nx * self.cell_m

    @property
    def height_m(self) -> float:
        return self.ny * self.cell_m

    @property
    def cell_area_m2(self) -> float:
        return self.cell_m**2

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of the whole grid."""
        x0, y0 = self.origin_m
        return (x0, y0, x0 + self.width_m, y0 + self.height_m)

    def polygon(self):
        """The grid's outline as a shapely box."""
        return box(*self.bounds)

    @cached_property
    def centers(self) -> np.ndarray:
        """Cell centres, shape ``(ny, nx, 2)``."""
        return self.sample_points(1)

    def sample_points(self, s: int) -> np.ndarray:
        """Centres of the ``s x s`` sub-cells of every cell, shape ``(ny * s, nx * s, 2)``.

        Sub-cell ``(J, I)`` belongs to cell ``(J // s, I // s)``: a fine grid of pitch ``c / s``.
        """
        x0, y0 = self.origin_m
        h = self.cell_m / s
        xs = x0 + (np.arange(self.nx * s) + 0.5) * h
        ys = y0 + (np.arange(self.ny * s) + 0.5) * h
        gx, gy = np.meshgrid(xs, ys)
        return np.stack([gx, gy], axis=-1)

    def cell_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Row and column of the cell holding each point (clipped to the grid)."""
        p = np.asarray(xy, dtype=float)
        i = np.floor((p[..., 0] - self.origin_m[0]) / self.cell_m).astype(int)
        j = np.floor((p[..., 1] - self.origin_m[1]) / self.cell_m).astype(int)
        return np.clip(j, 0, self.ny - 1), np.clip(i, 0, self.nx - 1)

    def contains(self, xy: np.ndarray) -> np.ndarray:
        """Boolean mask of points inside the grid's rectangle (boundary included)."""
        p = np.asarray(xy, dtype=float)
        x0, y0, x1, y1 = self.bounds
        return (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] >= y0) & (p[..., 1] <= y1)

    def cell_boxes(self) -> list:
        """Shapely boxes of all cells in row-major order (``j * nx + i``)."""
        x0, y0 = self.origin_m
        c = self.cell_m
        return [
            box(x0 + i * c, y0 + j * c, x0 + (i + 1) * c, y0 + (j + 1) * c)
            for j in range(self.ny)
            for i in range(self.nx)
        ]

    def refine(self, values: np.ndarray, s: int) -> np.ndarray:
        """Spread each cell's mass evenly over its ``s x s`` sub-cells: ``(ny s, nx s)``."""
        v = np.asarray(values, dtype=float)
        return np.repeat(np.repeat(v, s, axis=0), s, axis=1) / (s * s)

    def coarsen(self, fine: np.ndarray, s: int) -> np.ndarray:
        """Sum sub-cell mass back into cells: ``(..., ny s, nx s) -> (..., ny, nx)``."""
        f = np.asarray(fine)
        lead = f.shape[:-2]
        return f.reshape(*lead, self.ny, s, self.nx, s).sum(axis=(-3, -1))


# --------------------------------------------------------------------------- priors


@functools.lru_cache(maxsize=64)
def _sample_axes(grid: Grid, s: int) -> tuple[np.ndarray, np.ndarray]:
    """The x (``nx * s``) and y (``ny * s``) coordinates of :meth:`Grid.sample_points`' grid
    (``sample_points(s)[j, i] == (xs[i], ys[j])``), read-only, once per grid."""
    x0, y0 = grid.origin_m
    h = grid.cell_m / s
    xs = x0 + (np.arange(grid.nx * s) + 0.5) * h
    ys = y0 + (np.arange(grid.ny * s) + 0.5) * h
    xs.flags.writeable = False
    ys.flags.writeable = False
    return xs, ys


def _coarsen_in_order(grid: Grid, fine: np.ndarray, s: int) -> np.ndarray:
    """:meth:`Grid.coarsen` of a C-contiguous float64 ``(ny s, nx s)`` array, bit for bit, in
    one compiled pass (:func:`poc_env._kernels.priors.coarsen`): numpy's two-axis sum adds each
    cell's sub-rows in order to 0, each sub-row summed from its first value in order (its
    pairwise sum below 8 values), which the kernel spells out for ``1 < s < 8`` and ``nx > 1``
    (else numpy's own sum: a single column or longer sub-rows sum otherwise).
    ``tests/theory/test_probability_map.py`` pins it."""
    f = np.asarray(fine)
    if not (1 < s < 8 and grid.nx > 1 and f.dtype == np.float64 and f.flags.c_contiguous):
        return grid.coarsen(f, s)
    if f.shape != (grid.ny * s, grid.nx * s):
        raise ValueError(f"fine array of shape {f.shape} for {grid.ny} x {grid.nx} cells of {s}")
    out = np.empty(grid.shape)
    _priors.coarsen(f, s, out)
    return out


def gaussian_mixture(
    grid: Grid,
    components: tuple[GaussianComponent, ...] | list[GaussianComponent],
    background: float = 0.0,
    oversample: int = 6,
) -> np.ndarray:
    """Cell masses of a Gaussian mixture plus a uniform background, summing to 1.

    Each component's density is averaged over every cell on an ``oversample x oversample``
    sub-grid (the target is uniform within a cell, so a cell's POC is the integral of the
    density over the cell, not its value at the centre) and normalised on the grid, so a
    component's ``weight`` (relative to the others) is exactly its share of the mass on the map.
    ``background`` is the share of mass spread uniformly.

    Per component, on the sub-cell centres ``(x, y)`` (:meth:`Grid.sample_points`) with
    ``(dx, dy)`` their offsets from the mean: ``u = (c dx + s dy) / sigma_x``,
    ``v = (-s dx + c dy) / sigma_y`` (``c, s``: cosine and sine of the rotation), density
    ``exp(-0.5 (u^2 + v^2))``, summed per cell (:meth:`Grid.coarsen`); a component so narrow
    that every sample's density underflows puts its mass in the cell holding its mean (the
    limit of the cell integral), and one wholly off the grid contributes nothing. The exponent
    and the sums are compiled passes over the sub-cell axes (:mod:`poc_env._kernels.priors`:
    the same floating-point operations, in the same order, as numpy on the stacked points;
    numpy's ``exp`` between them), so a reset draws a random prior in a fraction of the time.
    """
    xs, ys = _sample_axes(grid, oversample)
    mass = np.zeros(grid.shape)
    weights = np.array([c.weight for c in components], dtype=float)
    if len(components):
        weights = weights / weights.max()  # first: a sum of weights near 1e308 overflows
        weights = weights / weights.sum()
    q = np.empty((len(ys), len(xs)))
    for w, comp in zip(weights, components):
        mx, my = (float(m) for m in comp.mean_m)
        c, s = np.cos(comp.rotation_rad), np.sin(comp.rotation_rad)
        sx, sy = (float(sd) for sd in comp.sigma_m)
        _priors.mixture_exponent(xs, ys, mx, my, float(c), float(s), sx, sy, q)
        np.exp(q, out=q)
        part = _coarsen_in_order(grid, q, oversample)
        if part.sum() > 0:
            mass += w * part / part.sum()
        elif grid.contains(np.array((mx, my))):  # narrower than the sub-cell spacing: every
            mass[grid.cell_of(np.array((mx, my)))] += w  # sample underflowed; its cell holds it
        # (a component wholly off the grid contributes nothing)
    total = mass.sum()
    if total > 0:
        mass = mass / total * (1.0 - background)
    elif background <= 0:  # every component wholly off the grid (config-audit)
        x0, y0, x1, y1 = grid.bounds
        raise ConfigError(
            "map.prior.components", [{"mean_km": [m / 1e3 for m in c.mean_m]} for c in components],
            f"components with mass on the {grid.nx} x {grid.ny} grid (x {x0 / 1e3:g} to "
            f"{x1 / 1e3:g} km, y {y0 / 1e3:g} to {y1 / 1e3:g} km), or map.prior.background > 0",
        )  # fmt: skip
    else:
        background = 1.0
    mass = mass + background / (grid.nx * grid.ny)
    return mass / mass.sum()


def random_gaussian_mixture(
    grid: Grid,
    rng: np.random.Generator,
    n_components: tuple[int, int] = (1, 6),
    sigma_fraction: tuple[float, float] = (0.05, 0.25),
    background: tuple[float, float] = (0.0, 0.05),
) -> np.ndarray:
    """A random prior for generalisation: a seeded Gaussian mixture of varying count and shape.

    Component count is drawn from ``n_components`` (inclusive), means uniformly over the grid,
    standard deviations as a fraction of the grid's smaller side from ``sigma_fraction``, a random
    orientation, Dirichlet weights, and a uniform background share from ``background``.
    """
    k = int(rng.integers(n_components[0], n_components[1] + 1))
    side = min(grid.width_m, grid.height_m)
    x0, y0, x1, y1 = grid.bounds
    comps = []
    weights = rng.dirichlet(np.ones(k))
    for w in weights:
        mean = (rng.uniform(x0, x1), rng.uniform(y0, y1))
        sig = tuple(rng.uniform(*sigma_fraction, size=2) * side)
        comps.append(
            GaussianComponent(
                mean_m=mean,
                sigma_m=sig,
                weight=float(max(w, 1e-6)),
                rotation_rad=float(rng.uniform(0, np.pi)),
            )
        )
    return gaussian_mixture(grid, comps, background=float(rng.uniform(*background)))


def _shape_error(source: str, shape: tuple[int, ...], grid: Grid) -> MapFileError:
    return MapFileError(
        f"{source}: shape {shape} does not match the grid; allowed: (ny, nx) = "
        f"{grid.shape} for {grid.nx} x {grid.ny} cells of {grid.cell_m / 1000:g} km "
        f"(row 0 at the south edge). A map of another extent needs a scenario whose "
        f"map.width_km / cell_km = nx and map.height_km / cell_km = ny; do not transpose "
        f"the array, which would move the mass relative to the airfields"
    )


def validate_map(values: np.ndarray, grid: Grid, source: str = "map") -> np.ndarray:
    """Check and normalise a prior; raise :class:`MapFileError` naming what is wrong.

    Requires real numbers of shape ``(ny, nx)``, finite and non-negative, with positive mass.
    The map is always divided by its sum (computed after scaling by the largest value, so
    values near the float limit cannot overflow it), so the result sums to 1 to rounding; a
    map whose sum was off by more than 1e-6 is reported with a warning.
    """
    allowed = "real, finite probabilities >= 0 with a positive sum"
    try:
        complex_ = bool(np.iscomplexobj(values))
        arr = None if complex_ else np.array(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise MapFileError(f"{source}: values that are not numbers; allowed: {allowed}") from None
    if arr is None:
        raise MapFileError(f"{source}: complex values; allowed: {allowed}")
    if arr.shape != grid.shape:
        raise _shape_error(source, arr.shape, grid)
    if not np.all(np.isfinite(arr)):
        n = int(np.sum(~np.isfinite(arr)))
        raise MapFileError(f"{source}: {n} value(s) are NaN or infinite; allowed: {allowed}")
    if np.any(arr < 0):
        raise MapFileError(
            f"{source}: {int(np.sum(arr < 0))} negative value(s) (min {arr.min():g}); "
            f"allowed: {allowed}"
        )
    peak = float(arr.max())
    if peak <= 0:
        raise MapFileError(f"{source}: all values are zero; allowed: {allowed}")
    scaled = arr / peak  # in [0, 1]: the sum cannot overflow
    total = float(scaled.sum())
    true_total = total * peak  # may be inf; only used for the message
    if not abs(true_total - 1.0) <= 1e-6:
        warnings.warn(f"{source}: map sums to {true_total:.6g}, normalised to 1", stacklevel=2)
    return scaled / total


def load_map(path: str | os.PathLike[str], grid: Grid) -> np.ndarray:
    """Read a prior from ``.npy`` (no pickles) or ``.csv`` (rows from south to north).

    The file must be a regular file; a ``.npy`` header's shape is checked before its data are
    read, and a ``.csv`` may not exceed 64 bytes a cell (a few MB for the paper's maps).
    """
    p = Path(path)
    name = f"map file {str(p)!r}"
    allowed = f"a .npy or .csv file of shape (ny, nx) = {grid.shape}"
    if not p.exists():
        raise MapFileError(f"{name} does not exist; allowed: {allowed}")
    if not p.is_file():
        kind = "a folder" if p.is_dir() else "not a regular file"
        raise MapFileError(f"{name} is {kind}; allowed: {allowed}")
    suffix = p.suffix.lower()
    if suffix not in (".npy", ".csv"):
        raise MapFileError(f"{name}: suffix {suffix!r}; allowed: {allowed}")
    try:
        if suffix == ".npy":
            mm = np.load(p, allow_pickle=False, mmap_mode="r")
            if not isinstance(mm, np.ndarray):  # np.load reads a .npz archive by its content
                with contextlib.suppress(AttributeError):
                    mm.close()
                raise MapFileError(
                    f"{name} holds a .npz archive ({type(mm).__name__}), not one array; "
                    f"allowed: {allowed} (np.save, not np.savez)"
                )
            if mm.shape != grid.shape:  # before reading the data
                raise _shape_error(name, mm.shape, grid)
            arr = np.array(mm)
        else:
            limit = max(2**20, 64 * grid.nx * grid.ny)
            if p.stat().st_size > limit:
                raise MapFileError(f"{name} is larger than {limit} bytes; allowed: {allowed}")
            arr = np.loadtxt(p, delimiter=",", ndmin=2)
    except MapFileError:
        raise
    except (ValueError, OSError, EOFError, TypeError) as err:
        raise MapFileError(f"{name} is corrupt or unreadable ({err}); allowed: {allowed}") from None
    return validate_map(arr, grid, source=name)


def build_prior(cfg: MapConfig, map_file: str | os.PathLike[str] | None = None) -> np.ndarray:
    """The prior POC of a map config: a user's file when given, else the configured prior."""
    grid = Grid.from_config(cfg)
    if map_file is not None:
        return load_map(map_file, grid)
    prior: PriorConfig = cfg.prior
    if prior.kind == "file":
        return load_map(prior.file, grid)  # type: ignore[arg-type]
    return gaussian_mixture(grid, prior.components, prior.background)
