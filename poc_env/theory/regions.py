"""Search regions and their allocation (§2.1 of Fan et al., Drones 2024).

The paper describes a search region in one of two ways: a polygon given by its vertices
(eq. 1) or a "search base circle" given by a centre and a radius (eq. 2). A region is scored
by its average POC, the probability of containment per unit area (eq. 3). For several regions
the numerator is the POC of their union, so an overlap is counted once, while the denominator
adds up every region's area, so an overlap is paid for by each region that covers it (eq. 4).

POC inside a region is computed by *area-weighted* cell overlap: the target is uniform within
a cell, so a region covering a fraction ``a`` of cell ``(j, i)`` holds ``a * POC[j, i]`` of
it. Overlaps are exact polygon clipping with shapely, not tests of cell centres.

The paper's rectangle-cut method, which places regions to maximise eq. 4, is a planner:
:func:`poc_env.agents.planning.rectangle_cut.rectangle_cut_allocation`.

Units are SI: metres, square metres, radians.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeAlias

import numpy as np
import shapely
from shapely.geometry import Point, Polygon
from shapely.validation import explain_validity

import poc_env._kernels.rectangles as _rectangles
import poc_env.limits as limits
from poc_env.errors import ConfigError, GeometryError
from poc_env.geometry import validate_polygon
from poc_env.theory.probability_map import Grid

__all__ = [
    "CircleRegion",
    "PolygonRegion",
    "area_fractions",
    "average_poc",
    "cell_overlap",
    "check_prior",
    "exclusive_fractions",
    "rectangle_mass",
    "region_poc",
    "region_pocs",
]

#: Segments per quarter circle of :attr:`CircleRegion.geometry` (256 edges in all).
CIRCLE_QUAD_SEGS = 64


# --------------------------------------------------------------------------- regions


@dataclass(frozen=True)
class PolygonRegion:
    """A polygon search region Omega_p = (p_1, ..., p_n) (eq. 1).

    ``vertices`` is an ``(n, 2)`` sequence of ``(x, y)`` in metres (n >= 3, the ring is closed
    implicitly); ``holes`` an optional sequence of vertex sequences cut out of it. The polygon
    is checked when the object is made: fewer than three vertices, zero area, a
    self-intersecting ring (a "bow-tie") or non-finite coordinates raise
    :class:`~poc_env.errors.GeometryError` naming ``name``.
    """

    vertices: tuple[tuple[float, float], ...]
    holes: tuple[tuple[tuple[float, float], ...], ...] = ()
    name: str = field(default="polygon region", compare=False)

    def __post_init__(self) -> None:
        poly = validate_polygon(self.vertices, self.name, holes=self.holes)
        verts = tuple((float(x), float(y)) for x, y in np.asarray(self.vertices, dtype=float))
        holes = tuple(
            tuple((float(x), float(y)) for x, y in np.asarray(h, dtype=float)) for h in self.holes
        )
        object.__setattr__(self, "vertices", verts)
        object.__setattr__(self, "holes", holes)
        # cached_property writes straight into __dict__, which a frozen dataclass allows.
        self.__dict__["geometry"] = poly

    @cached_property
    def geometry(self) -> Polygon:
        """The region as a valid shapely polygon."""
        return validate_polygon(self.vertices, self.name, holes=self.holes)

    @property
    def area_m2(self) -> float:
        """Area S(Omega) in square metres (holes excluded)."""
        return float(self.geometry.area)

    @classmethod
    def from_geometry(cls, geom: Polygon, name: str = "polygon region") -> PolygonRegion:
        """A region from a shapely polygon (its exterior and interior rings)."""
        if not isinstance(geom, Polygon) or geom.is_empty:
            raise GeometryError(f"{name}: need a non-empty shapely Polygon, got {geom.geom_type}")
        return cls(
            tuple(geom.exterior.coords)[:-1],
            tuple(tuple(r.coords)[:-1] for r in geom.interiors),
            name=name,
        )


@dataclass(frozen=True)
class CircleRegion:
    """A search base circle Omega_c = (c, r) (eq. 2): centre ``center_m`` and radius ``radius_m``.

    ``radius_m`` must be a finite number > 0 (else :class:`~poc_env.errors.GeometryError`).
    :attr:`area_m2` is the exact pi r^2. :attr:`geometry` is a regular 256-gon whose
    circumradius is enlarged so that its area equals pi r^2 to rounding; its boundary is within
    5e-5 r of the true circle, so a cell's overlap differs from the circle's by at most the
    boundary length in that cell times 5e-5 r.
    """

    center_m: tuple[float, float]
    radius_m: float
    name: str = field(default="circle region", compare=False)

    def __post_init__(self) -> None:
        try:
            cx, cy = (float(v) for v in self.center_m)
        except (TypeError, ValueError):
            raise GeometryError(
                f"{self.name}: center_m must be a pair of numbers (x, y), got {self.center_m!r}"
            ) from None
        if not (math.isfinite(cx) and math.isfinite(cy)):
            raise GeometryError(f"{self.name}: center_m must be finite, got {self.center_m!r}")
        try:
            r = float(self.radius_m)
        except (TypeError, ValueError):
            raise GeometryError(
                f"{self.name}: radius_m must be a number > 0, got {self.radius_m!r}"
            ) from None
        if not (math.isfinite(r) and r > 0):
            raise GeometryError(f"{self.name}: radius_m must be a finite number > 0, got {r!r}")
        object.__setattr__(self, "center_m", (cx, cy))
        object.__setattr__(self, "radius_m", r)

    @property
    def area_m2(self) -> float:
        """Area pi r^2 in square metres."""
        return math.pi * self.radius_m**2

    @cached_property
    def geometry(self) -> Polygon:
        """A 256-gon with the circle's centre and area (circumradius scaled up slightly)."""
        k = 4 * CIRCLE_QUAD_SEGS
        inscribed_area = 0.5 * k * math.sin(2.0 * math.pi / k)  # per unit circumradius^2
        r = self.radius_m * math.sqrt(math.pi / inscribed_area)
        return Point(self.center_m).buffer(r, quad_segs=CIRCLE_QUAD_SEGS)


Region: TypeAlias = PolygonRegion | CircleRegion | shapely.Geometry


def _geometry_of(region: Any, name: str = "region") -> shapely.Geometry:
    """A valid areal shapely geometry from a region object, a shapely geometry or vertices."""
    if isinstance(region, (PolygonRegion, CircleRegion)):
        return region.geometry
    if isinstance(region, shapely.Geometry):
        if region.is_empty:
            return region
        if not region.is_valid:
            raise GeometryError(f"{name}: invalid geometry ({explain_validity(region)})")
        return region
    return validate_polygon(region, name)


def _area_of(region: Any, name: str = "region") -> float:
    if isinstance(region, (PolygonRegion, CircleRegion)):
        return region.area_m2
    return float(_geometry_of(region, name).area)


def _as_region_list(regions: Any) -> list:
    if isinstance(regions, (PolygonRegion, CircleRegion, shapely.Geometry)):
        return [regions]
    try:
        out = list(regions)
    except TypeError:
        raise ConfigError(
            "regions", regions, "a region or a sequence of regions (PolygonRegion, CircleRegion)"
        ) from None
    if not out:
        raise ConfigError("regions", regions, "at least one region")
    return out


def check_prior(prior: Any, grid: Grid) -> np.ndarray:
    """``prior`` as a float array of the grid's shape ``(ny, nx)``, finite and >= 0, else a
    :class:`~poc_env.errors.ConfigError` naming ``prior``."""
    arr = np.asarray(prior, dtype=float)
    if arr.shape != grid.shape:
        raise ConfigError("prior", f"array of shape {arr.shape}", f"shape (ny, nx) = {grid.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ConfigError("prior", "array with negative or non-finite values", "finite >= 0")
    return arr


# --------------------------------------------------------------------------- overlap and POC


def _lattice_overlap(
    geom: shapely.Geometry, origin: tuple[float, float], pitch: float, nx: int, ny: int
) -> np.ndarray:
    """Fraction of each square of a ``(ny, nx)`` lattice of side ``pitch`` inside ``geom``.

    Squares outside the geometry's bounding box are 0 without any clipping; inside it, squares
    that are disjoint from / strictly inside the geometry are classified with a prepared
    geometry and only the squares on its boundary are clipped (``shapely.intersection``).
    """
    out = np.zeros((ny, nx))
    if geom.is_empty:
        return out
    x0, y0 = origin
    minx, miny, maxx, maxy = geom.bounds
    i0 = int(np.clip(math.floor((minx - x0) / pitch), 0, nx))
    i1 = int(np.clip(math.ceil((maxx - x0) / pitch), 0, nx))
    j0 = int(np.clip(math.floor((miny - y0) / pitch), 0, ny))
    j1 = int(np.clip(math.ceil((maxy - y0) / pitch), 0, ny))
    if i1 <= i0 or j1 <= j0:
        return out
    ii, jj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1))
    boxes = shapely.box(
        x0 + ii * pitch, y0 + jj * pitch, x0 + (ii + 1) * pitch, y0 + (jj + 1) * pitch
    )
    g = geom
    shapely.prepare(g)  # in place; speeds up the predicates, does not change the geometry
    frac = np.zeros(boxes.shape)
    inside = shapely.contains_properly(g, boxes)
    frac[inside] = 1.0
    edge = ~inside & shapely.intersects(g, boxes)
    if np.any(edge):
        frac[edge] = shapely.area(shapely.intersection(boxes[edge], g)) / pitch**2
    out[j0:j1, i0:i1] = np.clip(frac, 0.0, 1.0)
    return out


def cell_overlap(region: Region | Sequence[Sequence[float]], grid: Grid) -> np.ndarray:
    """Fraction of each cell's area that lies inside ``region``, shape ``(ny, nx)``.

    ``region`` is a :class:`PolygonRegion`, a :class:`CircleRegion`, a shapely (multi)polygon
    or an ``(n, 2)`` vertex array. Overlap areas are exact polygon clipping
    (``shapely.intersection`` of the cell boxes with the region, then ``shapely.area``); only
    cells meeting the region's bounding box are looked at, the others are 0.
    """
    geom = _geometry_of(region)
    return _lattice_overlap(geom, grid.origin_m, grid.cell_m, grid.nx, grid.ny)


_NONE = np.zeros((0, 0))


_Rects = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _flat_rectangles(center, length, width, theta) -> tuple[tuple[int, ...], _Rects]:
    """The kernels' rectangle arguments: the leading shape of ``center`` (..., 2) and flat
    contiguous centre x, centre y, half length, half width, cos theta, sin theta."""
    c = np.asarray(center, dtype=float)
    lead = c.shape[:-1]
    th = np.broadcast_to(np.asarray(theta, dtype=float), lead)

    def flat(v):
        return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=float), lead).ravel())

    half_l = 0.5 * np.asarray(length, dtype=float)
    half_w = 0.5 * np.asarray(width, dtype=float)
    return lead, (
        flat(c[..., 0]),
        flat(c[..., 1]),
        flat(half_l),
        flat(half_w),
        flat(np.cos(th)),
        flat(np.sin(th)),
    )


def rectangle_mass(
    grid: Grid,
    center,
    length,
    width,
    theta,
    *,
    exclusive: bool,
    centres: bool = False,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """Prior mass in rotated rectangles ``Q(center, l, w, theta)``: the one compiled kernel
    (:func:`poc_env._kernels.rectangles.rectangle_fractions`) behind the planner's objective and
    the region allocator (:mod:`poc_env.agents.planning.rectangle_cut`).

    ``center`` (..., 2), the others (...). Without ``weights`` returns the fraction of every
    cell inside each rectangle, (..., ny, nx); with ``weights`` (ny, nx) (e.g. the prior)
    returns ``sum fraction * weights`` per rectangle, (...), without the per-cell array. The
    fraction is the exact area fraction, or with ``centres`` 1 / 0 as the cell's centre lies
    in the rectangle or not (a quadrature; pass a grid of sample points). With ``exclusive``
    the last leading axis holds one individual's rectangles, and each excludes the cells (or,
    for areas, the parts of cells) covered by the ones before it (§3.1.6).
    """
    lead, rects = _flat_rectangles(center, length, width, theta)
    group = lead[-1] if exclusive and lead else 1
    mass = np.zeros(lead)
    if weights is None:
        out = np.zeros((*lead, grid.ny, grid.nx))
        shaped = out.reshape(-1, group, grid.ny, grid.nx)
        w = _NONE
    else:
        w = np.ascontiguousarray(weights, dtype=float)
        if w.shape != grid.shape:
            raise ConfigError("weights", w.shape, f"shape {grid.shape}")
        shaped = np.zeros((0, 0, 0, 0))
    _rectangles.rectangle_fractions(
        *rects,
        float(grid.origin_m[0]),
        float(grid.origin_m[1]),
        float(grid.cell_m),
        grid.ny,
        grid.nx,
        bool(exclusive),
        bool(centres),
        w,
        shaped,
        mass.reshape(-1, group),
    )
    return out if weights is None else mass


def boundary_mass(
    grid: Grid,
    center,
    length,
    width,
    theta,
    weights: np.ndarray,
    *,
    exclusive: bool,
    max_overlap: int | None = None,
) -> np.ndarray:
    """Weighted mass of rotated rectangles, ``sum area(cell ∩ Q) / cell_area * weights``, by
    boundary integrals (:func:`poc_env._kernels.rectangles.rectangle_masses`).

    The same numbers as :func:`rectangle_mass` with ``weights`` (to rounding, about 1e-15
    relative), without per-cell areas: each rectangle costs the grid lines its edges cross,
    not the cells it covers. ``center`` (..., 2), the others (...), ``weights`` (ny, nx);
    returns (...). With ``exclusive`` the last leading axis holds one individual's
    rectangles, each less the union of the ones before it (§3.1.6, exactly, down to slivers
    of cells). The map ends at the grid. ``max_overlap``: above this many earlier rectangles
    meeting one, its individual goes by the per-cell exclusive areas instead of
    inclusion-exclusion (default :data:`poc_env._kernels.rectangles.MAX_TERMS_OVERLAP`; the
    same numbers to rounding, polynomial where inclusion-exclusion is exponential).
    """
    c = np.asarray(center, dtype=float)
    if c.ndim < 1 or c.shape[-1] != 2:
        raise ConfigError("center", c.shape, "shape (..., 2)")
    w = np.ascontiguousarray(weights, dtype=float)
    if w.shape != grid.shape:
        raise ConfigError("weights", w.shape, f"shape {grid.shape}")
    lead, rects = _flat_rectangles(c, length, width, theta)
    group = lead[-1] if exclusive and lead else 1
    mass = np.zeros(lead)
    _rectangles.rectangle_masses(
        *rects,
        float(grid.origin_m[0]),
        float(grid.origin_m[1]),
        float(grid.cell_m),
        w,
        bool(exclusive),
        mass.reshape(-1, group),
        -1 if max_overlap is None else int(max_overlap),
    )
    return mass


def area_fractions(grid: Grid, center, length, width, theta) -> np.ndarray:
    """Exact area fraction of every cell inside each rectangle ``Q(center, l, w, theta)``.

    ``center`` (..., 2), ``length``/``width``/``theta`` (...); returns (..., ny, nx) in [0, 1].
    The map ends at the grid: a rectangle reaching beyond it covers only its part over the map.
    The rectangle case of :func:`cell_overlap` (same numbers, to rounding), compiled: a closed
    form for cells crossed by one pair of sides, polygon clipping near corners.
    """
    return rectangle_mass(grid, center, length, width, theta, exclusive=False)


def exclusive_fractions(grid: Grid, center, length, width, theta) -> np.ndarray:
    """Area fractions of each UAV's rectangle *not covered by the UAVs before it* (§3.1.6).

    ``center`` (..., n, 2), the others (..., n); returns (..., n, ny, nx). UAV ``i`` gets the
    exact area of ``cell ∩ Q_i \\ (Q_0 ∪ ... ∪ Q_{i-1})``: the overlap rule "a cell already
    allocated to an earlier UAV adds nothing", applied to every part of a cell, so the
    fractions of one cell add up to at most 1 and a copy of another UAV's rectangle -- or any
    overlap, down to a sliver of a cell -- is credited nothing.
    """
    c = np.asarray(center, dtype=float)
    if c.ndim < 2:
        raise ConfigError("center", c.shape, "shape (..., n, 2)")
    return rectangle_mass(grid, center, length, width, theta, exclusive=True)


def region_poc(region: Region | Sequence[Sequence[float]], grid: Grid, prior: np.ndarray) -> float:
    """POC inside ``region``: sum over cells of (overlap fraction) x (cell POC).

    The numerator of eq. 3. The target is uniform within a cell, so half a cell inside the
    region contributes half the cell's POC (not 0 or 1 as a test of the cell centre would).
    """
    p = check_prior(prior, grid)
    return float(np.sum(cell_overlap(region, grid) * p))


def region_pocs(regions: Sequence[Region], grid: Grid, prior: np.ndarray) -> np.ndarray:
    """:func:`region_poc` of each region separately (overlaps counted in each), shape ``(m,)``."""
    p = check_prior(prior, grid)
    return np.array([float(np.sum(cell_overlap(r, grid) * p)) for r in _as_region_list(regions)])


def average_poc(regions: Region | Sequence[Region], grid: Grid, prior: np.ndarray) -> float:
    """Average POC, the search criterion of eq. 3 (one region) and eq. 4 (several).

    One region: ``f = POC(Omega) / S(Omega)`` (eq. 3), in probability per square metre.

    Several regions: ``f = POC(Omega_1 u ... u Omega_n) / (S(Omega_1) + ... + S(Omega_n))``
    (eq. 4). The numerator is the POC of the *union* of the regions, so probability in an
    overlap is counted once; the denominator is the *sum* of the regions' areas, so an overlap
    is paid for once per region covering it - searching the same ground twice costs resources
    twice but cannot find the target twice. Overlap therefore always lowers ``f``.

    Areas are the regions' full areas, including any part outside the grid (which holds no
    POC). A single region must be passed as a region object (or shapely geometry), not as a
    bare vertex list, which would be read as a list of regions.
    """
    regs = _as_region_list(regions)
    geoms = [_geometry_of(r, f"regions[{k}]") for k, r in enumerate(regs)]
    union = geoms[0] if len(geoms) == 1 else shapely.union_all(geoms)
    numerator = region_poc(union, grid, prior)
    denominator = float(sum(_area_of(r, f"regions[{k}]") for k, r in enumerate(regs)))
    if denominator <= 0:
        raise GeometryError("regions: total area is zero")
    return numerator / denominator


def reach_share(
    region: Any, grid: Grid, reach_m: float, samples_per_cell: int | None = None
) -> np.ndarray:
    """(ny, nx): the share of each cell within ``reach_m`` of the outside of ``region`` (a
    shapely geometry: no-fly zones, or the zones grown by a clearance): the part of a zone's
    interior a sensor of lateral range ``reach_m`` reaches from outside it (eq. 20). The one
    implementation of the zone reach share; :meth:`poc_env.sim.routing.ZoneRouter.reach_share`
    gives the planners' and :func:`poc_env.theory.bound.zone_reach` the bounds'.

    Parameters
    ----------
    region:
        The area nothing may fly in (shapely (multi)polygon).
    grid:
        The cells.
    reach_m:
        The sensor's lateral range (m).
    samples_per_cell:
        ``None``: the share of each cell's **area** outside ``region`` shrunk by ``reach_m``
        (shapely's buffer; the planners' measure). An integer ``s``: the share of the cell's
        ``s x s`` **sample points** (the centres of its fine cells, where the environment puts
        the target, :mod:`poc_env.sim.core`) outside ``region`` or within ``reach_m`` of its
        boundary, by exact point distances (the bounds' measure).

    Returns
    -------
    numpy.ndarray
        Shares in [0, 1], 1 away from ``region``.
    """
    share = np.ones(grid.shape)
    hidden = region.buffer(-float(reach_m))
    if hidden.is_empty:
        return share
    ox, oy = grid.origin_m
    c = grid.cell_m
    x0, y0, x1, y1 = hidden.bounds
    c0, c1 = max(int((x0 - ox) // c), 0), min(int((x1 - ox) // c) + 1, grid.nx)
    r0, r1 = max(int((y0 - oy) // c), 0), min(int((y1 - oy) // c) + 1, grid.ny)
    if c0 >= c1 or r0 >= r1:
        return share
    if samples_per_cell is not None:  # exact point distances, no polygon approximation
        s = int(samples_per_cell)
        n = (r1 - r0) * (c1 - c0) * s * s
        limits.check_memory(
            "sensor.samples_per_cell", s, n * limits.REACH_BYTES_PER_SAMPLE,
            f"zone reach of {n} sample points ({r1 - r0} x {c1 - c0} cells under the zones, "
            f"{s} x {s} a cell)",
        )  # fmt: skip
        h = c / s
        xs = ox + c0 * c + (np.arange((c1 - c0) * s) + 0.5) * h
        ys = oy + r0 * c + (np.arange((r1 - r0) * s) + 0.5) * h
        px, py = np.meshgrid(xs, ys)
        deep = shapely.contains_xy(region, px, py)
        far = shapely.distance(region.boundary, shapely.points(px[deep], py[deep]))
        deep[deep] = far > float(reach_m)
        hid = deep.reshape(r1 - r0, s, c1 - c0, s).sum(axis=(1, 3))
        share[r0:r1, c0:c1] = 1.0 - hid / float(s * s)
        return share
    rr, cc = np.mgrid[r0:r1, c0:c1]
    cells = shapely.box(ox + cc * c, oy + rr * c, ox + (cc + 1) * c, oy + (rr + 1) * c)
    share[r0:r1, c0:c1] = 1.0 - shapely.area(shapely.intersection(cells, hidden)) / (c * c)
    return np.clip(share, 0.0, 1.0)
