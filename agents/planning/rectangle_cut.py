"""The rectangle-cut allocation of search regions (§2.1 of Fan et al., Drones 2024).

The paper allocates the swarm's search regions in two steps: ``n`` rectangles of ``1.3 S_u``
(``S_u`` the most one UAV can search) placed to maximise the average-POC criterion of eq. 4,
then one polygon search region inside each, drawn by hand. :func:`rectangle_cut_allocation`
does both from a prior map, the hand-drawing replaced by the rule stated in its docstring; the
polygons are :class:`~poc_env.theory.regions.PolygonRegion` objects, the regions that a region
plan (:mod:`poc_env.agents.planning.survey`) flies and :mod:`poc_env.agents.planning.region_planner`
tunes. The criterion itself (eq. 1-4: regions, their POC and average POC) is search theory and
lives in :mod:`poc_env.theory.regions`, as does :func:`~poc_env.theory.regions.rectangle_mass`,
the compiled rectangle-mass kernel that scores the rectangles here.

Units are SI: metres, square metres, radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from scipy import ndimage
from scipy.optimize import differential_evolution
from shapely.geometry import MultiPolygon, Polygon
from shapely.validation import make_valid

from poc_env.errors import ConfigError, GeometryError, check_positive, check_range
from poc_env.geometry import rectangle_polygon
from poc_env.theory.probability_map import Grid
from poc_env.theory.regions import (
    PolygonRegion,
    cell_overlap,
    check_prior,
    rectangle_mass,
    region_poc,
)

__all__ = ["Allocation", "RectangleSpec", "rectangle_cut_allocation"]

RectangleSpec = tuple[tuple[float, float], float, float, float]


@dataclass(frozen=True)
class Allocation:
    """Result of :func:`rectangle_cut_allocation`.

    Attributes
    ----------
    rectangles:
        One ``((x_c, y_c), length, width, theta)`` per UAV: the rectangle Q of §3.1.6, length
        along ``theta`` (radians from the x axis, in [0, pi)), ``length >= width``. Sorted by
        decreasing POC.
    rectangle_polygons:
        The rectangles as shapely polygons.
    polygons:
        The polygon search region derived inside each rectangle (same order).
    average_poc:
        Eq. 4 of the rectangles (exact, shapely overlap), probability per square metre.
    polygon_average_poc:
        Eq. 4 of the derived polygons.
    union_poc:
        POC of the union of the rectangles (the numerator of ``average_poc``).
    polygon_union_poc:
        POC of the union of the polygons.
    rectangle_area_m2, usable_area_m2:
        ``factor * S_u`` and ``S_u``.
    evaluations:
        Candidate solutions scored by differential evolution (population members over all
        generations, the initial population included).
    """

    rectangles: tuple[RectangleSpec, ...]
    rectangle_polygons: tuple[Polygon, ...]
    polygons: tuple[PolygonRegion, ...]
    average_poc: float
    polygon_average_poc: float
    union_poc: float
    polygon_union_poc: float
    rectangle_area_m2: float
    usable_area_m2: float
    evaluations: int


class _UnionObjective:
    """Vectorised union POC of n rectangles on sample points (probability, not negated).

    The points are a quadrature of the prior: cells holding at least ``coarse_below`` times the
    largest cell POC are split into ``s x s`` sub-cells (the fine lattice of
    ``grid.sample_points(s)``), each carrying ``1 / s^2`` of the cell's POC; lighter cells are
    one point at the centre carrying the whole cell. A point counts when it lies in a
    rectangle (eq. 6, the rectangle's frame), once however many rectangles hold it: the centre
    rule of :func:`rectangle_mass`, exclusive over each individual's rectangles.
    """

    def __init__(self, grid: Grid, prior: np.ndarray, s: int, n: int, area: float, coarse_below):
        big = (prior >= coarse_below * prior.max()) & (prior > 0)
        small = ~big & (prior > 0)
        big_fine = np.repeat(np.repeat(big, s, axis=0), s, axis=1)
        self.grid = grid
        self.s = s
        self.fine = Grid(grid.nx * s, grid.ny * s, grid.cell_m / s, grid.origin_m)
        self.fine_mass = np.where(big_fine, grid.refine(prior, s), 0.0)
        self.coarse_mass = np.where(small, prior, 0.0)
        self.n = n
        self.area = area
        self.evaluations = 0

    def decode(self, x: np.ndarray):
        """``x`` (4n, S) -> cx, cy, half-length, half-width, theta, each (n, S)."""
        p = np.asarray(x, dtype=float).reshape(self.n, 4, -1)
        cx, cy, aspect, theta = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
        hl = 0.5 * np.sqrt(self.area * aspect)
        hw = 0.5 * np.sqrt(self.area / aspect)
        return cx, cy, hl, hw, theta

    def mass(self, cx, cy, hl, hw, theta, *, exclusive: bool, fine_mass=None, coarse_mass=None):
        """Quadrature mass in rectangles of leading shape (...): (...,) (see rectangle_mass)."""
        center = np.stack([cx, cy], axis=-1)
        fm = self.fine_mass if fine_mass is None else fine_mass
        cm = self.coarse_mass if coarse_mass is None else coarse_mass
        args = (center, 2.0 * hl, 2.0 * hw, theta)
        return rectangle_mass(
            self.fine, *args, exclusive=exclusive, centres=True, weights=fm
        ) + rectangle_mass(self.grid, *args, exclusive=exclusive, centres=True, weights=cm)

    def inside(self, cx, cy, hl, hw, theta):
        """Which points lie in one rectangle: (fine (NY, NX), coarse (ny, nx)) 0/1 arrays."""
        center = np.stack([cx, cy], axis=-1)
        args = (center, 2.0 * hl, 2.0 * hw, theta)
        return (
            rectangle_mass(self.fine, *args, exclusive=False, centres=True),
            rectangle_mass(self.grid, *args, exclusive=False, centres=True),
        )

    def union_mass(self, x: np.ndarray) -> np.ndarray:
        """``x`` (4n,) or (4n, S) -> union POC, scalar or (S,)."""
        x = np.asarray(x, dtype=float)
        single = x.ndim == 1
        cx, cy, hl, hw, theta = (v.T for v in self.decode(x[:, None] if single else x))
        val = self.mass(cx, cy, hl, hw, theta, exclusive=True).sum(axis=-1)
        return val[0] if single else val

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        self.evaluations += 1 if x.ndim == 1 else x.shape[1]
        return -self.union_mass(x)


def _greedy_start(obj: _UnionObjective, grid: Grid, aspect_range: tuple[float, float]):
    """A greedy solution: place rectangles one at a time on the most uncovered POC.

    Centre candidates are the 16 cells with the most uncovered POC in a window the size of a
    rectangle; each is tried with 3 aspect ratios and 6 directions.
    """
    fine_rem = obj.fine_mass.copy()
    coarse_rem = obj.coarse_mass.copy()
    win = max(1, round(math.sqrt(obj.area) / grid.cell_m))
    aspects = np.unique(np.linspace(aspect_range[0], aspect_range[1], 3))
    thetas = np.arange(6) * (math.pi / 6)
    centers = grid.centers.reshape(-1, 2)
    ca, ct = (a.ravel() for a in np.meshgrid(np.arange(aspects.size), thetas, indexing="ij"))
    x: list[float] = []
    for _ in range(obj.n):
        cell_rem = grid.coarsen(fine_rem, obj.s) + coarse_rem
        smooth = ndimage.uniform_filter(cell_rem, size=win, mode="constant")
        top = np.argsort(-smooth.ravel(), kind="stable")[:16]
        cc = np.repeat(centers[top], ca.size, axis=0)
        a_idx = np.tile(ca, top.size)
        th = np.tile(ct, top.size)
        asp = aspects[a_idx]
        hl, hw = 0.5 * np.sqrt(obj.area * asp), 0.5 * np.sqrt(obj.area / asp)
        gain = obj.mass(
            cc[:, 0], cc[:, 1], hl, hw, th, exclusive=False, fine_mass=fine_rem,
            coarse_mass=coarse_rem,
        )  # fmt: skip
        b = int(np.argmax(gain))
        x.extend([cc[b, 0], cc[b, 1], asp[b], th[b]])
        fine_in, coarse_in = obj.inside(cc[b, 0], cc[b, 1], hl[b], hw[b], th[b])
        fine_rem[fine_in > 0] = 0.0
        coarse_rem[coarse_in > 0] = 0.0
    return np.array(x, dtype=float)


def _derive_polygon(
    rect: Polygon,
    grid: Grid,
    fine_mass: np.ndarray,
    s: int,
    usable_area: float,
    claimed: np.ndarray,
) -> tuple[Polygon, np.ndarray]:
    """The dense polygon of area about ``usable_area`` inside ``rect`` (rule: see caller).

    Returns the polygon and the mask of fine sub-cells it was built from.
    """
    h = grid.cell_m / s
    ny, nx = fine_mass.shape
    frac = cell_overlap(rect, Grid(nx, ny, h, grid.origin_m))
    inrect = frac > 1e-9
    sub_area = (frac * h * h).ravel()
    density = (fine_mass / (h * h)).ravel()
    taken = claimed.ravel().astype(np.int8)
    pts = grid.sample_points(s)
    w = fine_mass * frac
    free = inrect & ~claimed
    total = float(w[free].sum())
    if total > 0:
        centroid = (pts[free] * w[free][:, None]).sum(axis=0) / total
    else:
        centroid = np.asarray(rect.centroid.coords[0])
    dist = np.hypot(pts[..., 0] - centroid[0], pts[..., 1] - centroid[1]).ravel()

    def take(cand: np.ndarray, need: float) -> np.ndarray:
        """Flat indices of the best sub-cells of ``cand`` until their area is closest to
        ``need``: unclaimed before claimed, then density descending, then distance ascending."""
        idx = np.flatnonzero(cand)
        order = idx[np.lexsort((dist[idx], -density[idx], taken[idx]))]
        cum = np.cumsum(sub_area[order])
        k = int(np.searchsorted(cum, need))
        if 0 < k < cum.size and abs(cum[k - 1] - need) < abs(cum[k] - need):
            k -= 1
        return order[: min(k + 1, cum.size)]

    # 1. the densest sub-cells whose area reaches S_u
    sel = np.zeros(inrect.shape, dtype=bool)
    sel.ravel()[take(inrect, usable_area)] = True
    # 2. the connected piece (4-neighbours) holding the most POC, without holes
    lab, nlab = ndimage.label(sel)
    if nlab > 1:
        score = ndimage.sum(w + 1e-12 * frac, lab, index=np.arange(1, nlab + 1))
        sel = lab == (1 + int(np.argmax(score)))
    sel = ndimage.binary_fill_holes(sel) & inrect
    # 3. grow it through its densest neighbours back to S_u if step 2 made it short
    cross = ndimage.generate_binary_structure(2, 1)
    for _ in range(2 * (nx + ny)):
        deficit = usable_area - float(sub_area[sel.ravel()].sum())
        if deficit <= 0.5 * h * h:
            break
        frontier = ndimage.binary_dilation(sel, cross) & inrect & ~sel
        if not np.any(frontier):
            break
        sel.ravel()[take(frontier, deficit)] = True
        sel = ndimage.binary_fill_holes(sel) & inrect
    # 4. polygon: union of boxes, clipped to the rectangle, largest piece, simplified, valid
    jj, ii = np.nonzero(sel)
    x0, y0 = grid.origin_m
    boxes = shapely.box(x0 + ii * h, y0 + jj * h, x0 + (ii + 1) * h, y0 + (jj + 1) * h)
    poly = _largest_polygon(shapely.intersection(shapely.union_all(boxes), rect))
    poly = Polygon(poly.exterior)
    poly = _largest_polygon(make_valid(poly.simplify(0.5 * h, preserve_topology=True)))
    poly = _largest_polygon(shapely.intersection(Polygon(poly.exterior), rect))
    return Polygon(poly.exterior), sel


def _largest_polygon(geom: shapely.Geometry) -> Polygon:
    if isinstance(geom, Polygon):
        return geom
    parts = [g for g in getattr(geom, "geoms", []) if isinstance(g, (Polygon, MultiPolygon))]
    polys: list[Polygon] = []
    for g in parts:
        polys.extend(g.geoms if isinstance(g, MultiPolygon) else [g])
    if not polys:
        raise GeometryError(f"derived polygon is empty or degenerate ({geom.geom_type})")
    return max(polys, key=lambda p: p.area)


def rectangle_cut_allocation(
    grid: Grid,
    prior: np.ndarray,
    n: int,
    usable_area_m2: float,
    rng: np.random.Generator | int,
    *,
    factor: float = 1.3,
    max_iter: int = 100,
    popsize: int = 6,
    samples_per_cell: int = 4,
    aspect_range: tuple[float, float] = (1.0, 3.0),
    tol: float = 1e-3,
    coarse_below: float = 0.02,
) -> Allocation:
    """The rectangle-cut method of §2.1: n rectangles, then a polygon inside each.

    **Rectangles.** Each of the ``n`` rectangles has area ``factor * S_u`` (the paper's 1.3
    S_u), where ``S_u = usable_area_m2`` is the most one UAV can search. With every area fixed,
    maximising eq. 4 is maximising the POC of the union of the rectangles, overlap counted
    once. Decision variables per rectangle: centre ``(x, y)`` within the grid's bounds, aspect
    ratio ``length / width`` in ``aspect_range`` and direction ``theta`` in ``[0, pi]``
    (reported modulo pi).
    They are optimised by ``scipy.optimize.differential_evolution`` seeded from ``rng`` (no
    global random state; ``polish=False`` since the objective is piecewise constant) on a
    vectorised objective: the union POC of the whole population at once (``vectorized=True``;
    the compiled rectangle-mass kernel under its centre rule, :func:`rectangle_mass`: a
    point-in-rotated-rectangle test in the rectangle's frame, eq. 6, visiting only the points
    near each rectangle). The points are a
    quadrature of the prior: a cell holding at least ``coarse_below`` times the largest cell
    POC is split into ``samples_per_cell ** 2`` sub-cells (``grid.sample_points``) that
    share its POC; a lighter cell is a single point at its centre. The initial population holds
    a greedy solution (rectangles placed one at a time on the most uncovered POC), perturbed
    copies of it (a fifth of the population) and uniform random members.

    Budget: ``popsize * 4n`` members (default 6 x 4n: 144 for n = 6) for at most ``max_iter``
    generations (default 100), stopping earlier once the spread of the population's union
    POC is below ``tol`` (relative). Measured: 30 x 40 cells, n = 6, five Gaussian clusters
    with 2 % background: about 2 s on one core (the objective: one compiled pass per
    population, :func:`rectangle_mass`).

    The reported ``average_poc`` and ``union_poc`` are then recomputed with exact area
    fractions (:func:`rectangle_mass`; the rectangles' union is the sum of their exclusive
    parts).

    **Polygons** (the paper draws them by hand; here a rule). Inside each rectangle, taken in
    order of decreasing POC, on the fine lattice of ``samples_per_cell`` sub-cells per cell
    side:

    1. rank the sub-cells meeting the rectangle by POC density - sub-cells already used by an
       earlier polygon last, so that polygons overlap only when a rectangle has too little
       ground of its own - ties broken by distance to the rectangle's POC centroid; take the
       top ones until their area inside the rectangle is closest to ``S_u``;
    2. keep the 4-connected piece holding the most POC and fill its holes;
    3. if that is short of ``S_u``, grow it through its densest neighbouring sub-cells;
    4. take the union of the chosen sub-cell boxes clipped to the rectangle, keep the largest
       piece, fill holes, simplify with tolerance half a sub-cell, make it valid and clip it to
       the rectangle again.

    The polygon lies inside its rectangle, has area close to ``S_u`` (within about one
    sub-cell row of the boundary) and keeps the densest part, so its average POC is normally
    higher than the rectangle's.

    Raises :class:`~poc_env.errors.ConfigError` naming the argument for ``n < 1``,
    ``usable_area_m2 <= 0``, a rectangle area ``factor * usable_area_m2`` larger than the
    grid, a bad ``aspect_range``, ``factor``, budget or ``rng``.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ConfigError("n", n, "an integer >= 1 (number of UAVs / rectangles)")
    n = int(n)
    s_u = check_positive("usable_area_m2", usable_area_m2)
    factor = check_positive("factor", factor)
    area = factor * s_u
    grid_area = grid.width_m * grid.height_m
    if area > grid_area:
        raise ConfigError(
            "usable_area_m2",
            usable_area_m2,
            f"factor * usable_area_m2 <= grid area {grid_area:g} m^2, i.e. usable_area_m2 <= "
            f"{grid_area / factor:g} m^2",
        )
    try:
        lo, hi = (float(v) for v in aspect_range)
    except (TypeError, ValueError):
        raise ConfigError("aspect_range", aspect_range, "a pair (lo, hi), 1 <= lo <= hi") from None
    if not (math.isfinite(hi) and 1.0 <= lo <= hi):
        raise ConfigError("aspect_range", aspect_range, "a pair (lo, hi), 1 <= lo <= hi")
    for name, val, least in (("max_iter", max_iter, 1), ("popsize", popsize, 1)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < least:
            raise ConfigError(name, val, f"an integer >= {least}")
    if (
        isinstance(samples_per_cell, bool)
        or not isinstance(samples_per_cell, (int, np.integer))
        or not 1 <= samples_per_cell <= 32
    ):
        raise ConfigError("samples_per_cell", samples_per_cell, "an integer in [1, 32]")
    coarse_below = check_range("coarse_below", coarse_below, 0.0, 1.0)
    tol = check_positive("tol", tol, allow_zero=True)
    if isinstance(rng, (int, np.integer)) and not isinstance(rng, bool):
        rng = np.random.default_rng(int(rng))
    if not isinstance(rng, np.random.Generator):
        raise ConfigError("rng", rng, "a numpy.random.Generator (or an integer seed)")
    p = check_prior(prior, grid)
    s = int(samples_per_cell)

    if p.sum() <= 0:
        raise ConfigError("prior", "all zeros", "a map with positive mass")
    obj = _UnionObjective(grid, p, s, n, area, coarse_below)

    x0, y0, x1, y1 = grid.bounds
    lower = np.tile([x0, y0, lo, 0.0], n)
    upper = np.tile([x1, y1, hi, math.pi], n)
    dim = 4 * n
    size = max(5, int(popsize) * dim)

    greedy = _greedy_start(obj, grid, (lo, hi))
    n_jit = max(1, size // 5)
    scale = np.tile([0.25 * math.sqrt(area), 0.25 * math.sqrt(area), 0.2 * (hi - lo), 0.3], n)
    jitter = greedy + rng.normal(size=(n_jit, dim)) * scale
    randoms = lower + rng.random((size - 1 - n_jit, dim)) * (upper - lower)
    init = np.clip(np.vstack([greedy[None], jitter, randoms]), lower, upper)

    result = differential_evolution(
        obj,
        bounds=list(zip(lower, upper, strict=True)),
        maxiter=int(max_iter),
        init=init,
        tol=tol,
        polish=False,
        vectorized=True,
        updating="deferred",
        rng=rng,
    )
    best = np.asarray(result.x, dtype=float)
    if obj.union_mass(greedy) > obj.union_mass(best):  # DE keeps its best; belt and braces
        best = greedy

    cx, cy, hl, hw, theta = (a[:, 0] for a in obj.decode(best[:, None]))
    specs = [
        (
            (float(cx[k]), float(cy[k])),
            float(2 * hl[k]),
            float(2 * hw[k]),
            float(theta[k] % math.pi),
        )
        for k in range(n)
    ]
    rect_polys = [rectangle_polygon(*spec) for spec in specs]
    args = (np.stack([cx, cy], axis=-1), 2 * hl, 2 * hw, theta)
    pocs = rectangle_mass(grid, *args, exclusive=False, weights=p)  # exact area fractions
    order = np.argsort(-pocs, kind="stable")
    specs = [specs[k] for k in order]
    rect_polys = [rect_polys[k] for k in order]

    union_poc = float(rectangle_mass(grid, *args, exclusive=True, weights=p).sum())
    rect_avg = union_poc / (n * area)

    fine_mass = grid.refine(p, s)
    claimed = np.zeros(fine_mass.shape, dtype=bool)
    polys: list[PolygonRegion] = []
    for k, rect in enumerate(rect_polys):
        poly, used = _derive_polygon(rect, grid, fine_mass, s, s_u, claimed)
        claimed |= used
        polys.append(PolygonRegion.from_geometry(poly, name=f"allocation polygon {k}"))
    poly_union = region_poc(shapely.union_all([q.geometry for q in polys]), grid, p)
    poly_avg = poly_union / sum(q.area_m2 for q in polys)

    return Allocation(
        rectangles=tuple(specs),
        rectangle_polygons=tuple(rect_polys),
        polygons=tuple(polys),
        average_poc=float(rect_avg),
        polygon_average_poc=float(poly_avg),
        union_poc=float(union_poc),
        polygon_union_poc=float(poly_union),
        rectangle_area_m2=float(area),
        usable_area_m2=float(s_u),
        evaluations=int(obj.evaluations),
    )
