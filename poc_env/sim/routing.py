"""Routes that keep eq. 20: shortest paths around no-fly zones inside the operating area.

One implementation for every planner (allocation, DE, survey patterns) and for the waypoint
follower's transit legs (:mod:`poc_env.sim.autopilot`).

- The **keep-out** area is the union of the zones grown by a clearance ``c``
  (:func:`clearance_m`): the follower cuts corners (a waypoint counts as reached half a step
  away, or passed at its closest approach within half a step plus the turn radius, then it
  turns at most ``omega_max``), so a route that keeps ``c`` from every zone is flown without
  entering one. Its polygons (round joins, :data:`QUAD_SEGS` segments per quarter circle) are
  grown a little further, to ``c / cos(pi / (4 QUAD_SEGS))`` (+1 %), so that their chords,
  not only their vertices, keep ``c``.
- **Shortest paths** (:meth:`ZoneRouter.path`): a visibility graph over the vertices of the
  keep-out polygons, edges tested with shapely against the **obstacle**, the zones grown by
  ``c`` itself (a finer round buffer, inside the keep-out polygons, so paths may run along the
  keep-out boundary), all pairs solved once with Dijkstra (``scipy.sparse.csgraph``); a query
  joins its two ends to the visible vertices. Every path and every leg the refinement accepts
  (:meth:`ZoneRouter.crosses`) therefore keeps ``c`` from every zone (issue 24: with the
  obstacle at ``0.9 c`` and two segments per quarter circle, routes passed 0.90-0.92 c from
  zones). Vertices outside the operating area (eq. 20's box, convex) are dropped, so paths stay
  inside it. An end already inside the ``c`` ring (an airfield near a zone) joins vertices
  whose segments come no closer to the zones than that end itself (else, if there is no such
  path, any that misses the zones): a route from a field at ``d < c`` keeps ``d`` (issue 24:
  take-off and landing legs of fields at 0.92-0.96 c cut the ring down to 0.012 c).
- **Clipping** (:meth:`ZoneRouter.reroute`): every leg of a polyline is cut to its parts
  outside the keep-out area and consecutive parts are joined by shortest paths, so search legs
  fly only searchable airspace and transit goes around.
- **Reach** (:meth:`ZoneRouter.reach_share`): the share of each cell within a lateral range
  of flyable airspace, i.e. the part of a zone's interior a sensor reaches from outside.
  Planners multiply the prior by the share of each cell's area within ``W/2`` of the keep-out
  area's outside (the zone-interior mass discount, a conservative model); the bounds
  (:func:`poc_env.theory.bound.zone_reach`) use the share of its sample points within the
  detection law's reach (the inverse cube's cut-off) of the zones' outside.

**Speed** (issue 24: planning with zones within 2 s on ``paper_6_2``). A segment's test
against the obstacle, the keep-out area or the zones (shapely's ``intersects``) first goes
through a compiled test of its edges (:func:`poc_env._kernels.segments.edge_contacts`): a
certified proper crossing is a hit, a certified absence of contact is decided by one end's
side (``contains_xy``), and only the uncertain rest (touches, collinear runs, near-zero
orientations) goes to shapely. Each answer is shapely's exactly; the router also remembers its
answers (a point's visible vertices, the paths and clipped pieces between repeated ends: a
plan reroutes the same legs many times). ``reference=True`` (or the class attribute
:attr:`ZoneRouter.reference`) answers with shapely alone and remembers nothing: the definition
the tests hold the fast path to, plan for plan.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np
import shapely
from scipy.sparse.csgraph import shortest_path
from shapely.geometry import LineString, Point

from poc_env._kernels.segments import edge_contacts
from poc_env.geometry import as_polygon
from poc_env.sim.constraints import NoFlyZones
from poc_env.theory.regions import reach_share

__all__ = ["ZoneRouter", "clearance_m"]

#: segments per quarter circle of the keep-out polygons' round joins (the graph's vertices).
QUAD_SEGS = 4
#: the keep-out polygons' growth over ``c``: their chords keep ``c`` (+1 %: GEOS's buffer
#: came 0.2 % short of its distance where two zones' keep-out areas meet), so the obstacle
#: (the zones grown by ``c``, finely rounded) lies strictly inside them.
_GROW = 1.01 / float(np.cos(np.pi / (4 * QUAD_SEGS)))
#: a zone's keep-out polygon with more vertices than this (a circle digitised with thousands)
#: is simplified outwards (:func:`_keep_out`): the graph has a node per vertex and its cost
#: grows as their square (a 2,000-vertex circle: 263 s and 1.25 GB for one allocation plan).
MAX_KEEP_OUT_VERTICES = 256
#: the simplification's tolerance, a share of ``c`` (doubled until the polygon is small enough)
SIMPLIFY_SHARE = 0.01
#: a segment with an end inside the c ring may come closer to the zones than that end by this
#: share of c (rounding; :meth:`ZoneRouter._visible`).
KEEP_TOL = 1e-6
#: answers a router remembers per kind (paths, pieces, visible vertices) before it forgets them
#: all (a follower's router lives as long as its episode).
CACHE_SIZE = 20_000


def _vertices(poly: Any) -> int:
    return sum(len(r.coords) - 1 for r in (poly.exterior, *poly.interiors))


def _keep_out(zone: Any, clearance: float) -> Any:
    """``zone`` grown by ``_GROW * clearance`` (its keep-out polygon); one of more than
    :data:`MAX_KEEP_OUT_VERTICES` vertices simplified by a tolerance ``t`` (from
    :data:`SIMPLIFY_SHARE` of ``c``, doubled up to 8 % of it until it is small enough), then
    grown by ``t`` with mitred joins, so that it still holds the plain keep-out polygon (paths
    keep ``c``) and departs from it by at most ``2 t``. Zones of few vertices: the plain
    polygon, unchanged."""
    grown = zone.buffer(_GROW * clearance, quad_segs=QUAD_SEGS)
    if _vertices(grown) <= MAX_KEEP_OUT_VERTICES:
        return grown
    tol = SIMPLIFY_SHARE * clearance
    while True:
        out = grown.simplify(tol).buffer(tol, join_style="mitre")
        if _vertices(out) <= MAX_KEEP_OUT_VERTICES or tol >= 0.08 * clearance:
            return out
        tol *= 2


class _Edges:
    """A polygonal geometry's boundary edges, grouped by ring, for exact segment tests."""

    def __init__(self, geom: Any) -> None:
        self.geom = geom
        rings = [r for p in getattr(geom, "geoms", [geom]) for r in (p.exterior, *p.interiors)]
        starts, ends, first, boxes = [], [], [0], []
        for ring in rings:
            pts = np.asarray(ring.coords, dtype=float)[:, :2]
            starts.append(pts[:-1])
            ends.append(pts[1:])
            first.append(first[-1] + len(pts) - 1)
            boxes.append([*pts.min(axis=0), *pts.max(axis=0)])
        a = np.concatenate(starts) if starts else np.zeros((0, 2))
        b = np.concatenate(ends) if ends else np.zeros((0, 2))
        self._e = (
            np.ascontiguousarray(a[:, 0]),
            np.ascontiguousarray(a[:, 1]),
            np.ascontiguousarray(b[:, 0]),
            np.ascontiguousarray(b[:, 1]),
        )
        self._rings = np.asarray(first, dtype=np.int64)
        self._boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)

    def hits(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Bool (L,): ``shapely.intersects(LineString(a[i], b[i]), geom)``, exactly (the
        module doc's compiled test first, shapely for what it leaves uncertain)."""
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        b = np.asarray(b, dtype=float).reshape(-1, 2)
        state = np.empty(len(a), dtype=np.int8)
        ax, ay = np.ascontiguousarray(a.T)
        bx, by = np.ascontiguousarray(b.T)
        edge_contacts(
            ax,
            ay,
            bx,
            by,
            *self._e,
            self._rings,
            self._boxes,
            state,
        )
        hit = state == 1
        clear = state == 0  # no contact with the boundary: wholly inside or wholly outside
        if clear.any():
            if len(a) > 1 and a.strides[0] == 0:  # one start (broadcast): one test
                hit[clear] = shapely.contains_xy(self.geom, a[0, 0], a[0, 1])
            else:
                hit[clear] = shapely.contains_xy(self.geom, a[clear, 0], a[clear, 1])
        unsure = state == 2
        if unsure.any():
            lines = shapely.linestrings(np.stack([a[unsure], b[unsure]], axis=1))
            hit[unsure] = shapely.intersects(lines, self.geom)
        return hit


def _key(*points: np.ndarray) -> bytes:
    return b"".join(np.asarray(p, dtype=float).tobytes() for p in points)


def reach_and_turn_m(scenario: Any, speed: Any) -> Any:
    """Half a step at ``speed`` (m/s; the follower's reach) plus the turn radius
    ``speed / omega_max`` (eq. 19's turn-rate bound), in metres: the follower's capture radius
    at ``speed`` and, at ``v_max``, the clearance kept from every zone (:func:`clearance_m`)."""
    v = np.asarray(speed, dtype=float)
    return 0.5 * v * scenario.episode.dt_s + v / scenario.uav.max_turn_rate_rad_s


def clearance_m(scenario: Any) -> float:
    """Clearance kept from every zone: :func:`reach_and_turn_m` at ``v_max`` (metres)."""
    return float(reach_and_turn_m(scenario, scenario.uav.max_speed_mps))


class ZoneRouter:
    """Shortest flyable paths around ``zones`` inside the box ``area`` (see the module doc).

    Parameters
    ----------
    zones:
        Polygons (vertex arrays, metres), e.g. ``MapConfig.no_fly_zones_m``.
    area:
        ``(x0, y0, x1, y1)``: eq. 20's operating area, or None (the plane).
    clearance:
        ``c`` in metres (:func:`clearance_m`).
    reference:
        Shapely's predicates alone, nothing remembered (the module doc's "Speed"); None: the
        class attribute :attr:`reference`.
    """

    #: the default of ``reference`` (tests set it to plan with the reference router).
    reference: bool = False

    def __init__(
        self,
        zones: Sequence[Any],
        area: Sequence[float] | None,
        clearance: float,
        reference: bool | None = None,
    ) -> None:
        self.zones = tuple(as_polygon(z, f"no_fly_zones[{i}]") for i, z in enumerate(zones))
        self.clearance = float(clearance)
        self.area = None if area is None else tuple(float(v) for v in area)
        self.active = bool(self.zones)
        if reference is not None:
            self.reference = bool(reference)
        self._paths: dict[bytes, np.ndarray | None] = {}
        self._pieces: dict[bytes, list[tuple[np.ndarray, np.ndarray]]] = {}
        self._seen: dict[bytes, np.ndarray] = {}
        self._routes: dict[bytes, np.ndarray] = {}
        if not self.active:
            return
        raw = shapely.union_all(self.zones)
        self.keep_out = shapely.union_all([_keep_out(z, self.clearance) for z in self.zones])
        self.obstacle = raw.buffer(self.clearance, quad_segs=16)
        self.raw = raw.buffer(1.0)
        self._zones_union = raw
        for g in (self.keep_out, self.obstacle, self.raw, raw):
            shapely.prepare(g)
        self._edges_of = {id(g): _Edges(g) for g in (self.keep_out, self.obstacle, self.raw)}
        polys = list(getattr(self.keep_out, "geoms", [self.keep_out]))
        nodes = [np.asarray(r.coords)[:-1, :2] for p in polys for r in (p.exterior, *p.interiors)]
        pts = np.concatenate(nodes) if nodes else np.zeros((0, 2))
        if self.area is not None:
            x0, y0, x1, y1 = self.area
            ok = (pts[:, 0] > x0) & (pts[:, 0] < x1) & (pts[:, 1] > y0) & (pts[:, 1] < y1)
            pts = pts[ok]
        self.nodes = pts
        n = len(pts)
        w = np.full((n, n), np.inf)
        if n > 1:
            i, j = np.triu_indices(n, 1)
            vis = ~self._hits(self.obstacle, pts[i], pts[j])
            d = np.hypot(*(pts[i] - pts[j]).T)
            w[i[vis], j[vis]] = d[vis]
            w[j[vis], i[vis]] = d[vis]
        self.dist, self.pred = shortest_path(
            np.where(np.isfinite(w), w, 0.0), method="D", directed=False, return_predecessors=True
        )
        self._edges = NoFlyZones([p for p in getattr(self.obstacle, "geoms", [self.obstacle])])
        # the vertices inside the obstacle (a segment from them is tested against the zones)
        self._nodes_near = shapely.contains_xy(self.obstacle, pts[:, 0], pts[:, 1])

    @classmethod
    def for_scenario(cls, scenario: Any, area: Sequence[float] | None = None) -> ZoneRouter:
        """The router of a scenario's zones, its operating area (eq. 20) and clearance."""
        if area is None:
            from poc_env.sim.core import operating_area

            area = operating_area(scenario)
        return cls(scenario.map.no_fly_zones_m, area, clearance_m(scenario))

    # -- queries -----------------------------------------------------------------------------
    def _hits(self, geom: Any, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Bool (L,): the segments ``a[i] -> b[i]`` intersect ``geom`` (one of the router's
        three geometries; shapely's answer, computed as the module doc's "Speed" says)."""
        if self.reference:
            return shapely.intersects(shapely.linestrings(np.stack([a, b], axis=1)), geom)
        return self._edges_of[id(geom)].hits(a, b)

    def _remember(self, cache: dict, key: bytes, value: Any) -> None:
        if self.reference:
            return
        if len(cache) >= CACHE_SIZE:
            cache.clear()
        cache[key] = value

    def _visible(
        self, p: np.ndarray, targets: np.ndarray, nodes: bool = False, keep: bool = True
    ) -> np.ndarray:
        """Bool (T,): the straight segments p -> targets miss the obstacle (the zones grown by
        c). A segment with an end already inside that ring (a field near a zone, a UAV cutting
        a corner) misses the zones themselves and, with ``keep``, comes no closer to them than
        that end is (:data:`KEEP_TOL`): a route from a field at ``d < c`` from a zone keeps
        ``d``, the least any route from there can keep. ``nodes``: the targets are the graph's
        vertices (the answer is remembered per ``p`` and ``keep``)."""
        if not len(targets):
            return np.zeros(0, dtype=bool)
        key = _key(p) + bytes([keep]) if nodes else b""
        if nodes and key in self._seen:
            return self._seen[key]
        starts = np.broadcast_to(p, targets.shape)
        hit = self._hits(self.obstacle, starts, targets)
        if nodes and not self.reference:
            near = self._nodes_near.copy()
        else:
            near = shapely.contains_xy(self.obstacle, targets[:, 0], targets[:, 1])
        if self.reference:
            p_near = bool(self.obstacle.contains(Point(p)))
        else:  # the same predicate on the prepared geometry, without a Point
            p_near = bool(shapely.contains_xy(self.obstacle, p[0], p[1]))
        if p_near:
            near[:] = True
        if near.any():
            hit[near] = self._hits(self.raw, starts[near], targets[near])
            if keep:  # no closer to the zones than the end inside the ring
                ends = targets[near]
                d_end = shapely.distance(self._zones_union, shapely.points(ends))
                if p_near:
                    d_end = np.minimum(d_end, shapely.distance(self._zones_union, Point(p)))
                lines = shapely.linestrings(np.stack([starts[near], ends], axis=1))
                gap = shapely.distance(self._zones_union, lines)
                hit[near] |= gap < d_end - KEEP_TOL * self.clearance
        vis = ~hit
        if nodes:
            self._remember(self._seen, key, vis)
        return vis

    def path(self, a, b) -> np.ndarray | None:
        """The shortest flyable polyline ``a -> b`` ((k, 2), ends included), or None."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        if not self.active:
            return np.stack([a, b])
        key = _key(a, b)
        if key in self._paths:
            got = self._paths[key]
            return None if got is None else got.copy()
        res = self._path(a, b)
        self._remember(self._paths, key, None if res is None else res.copy())
        return res

    def _path(self, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        # an end inside the c ring: a path that keeps its distance if there is one, else one
        # that only misses the zones
        res = self._shortest(a, b, True)
        return self._shortest(a, b, False) if res is None else res

    def _shortest(self, a: np.ndarray, b: np.ndarray, keep: bool) -> np.ndarray | None:
        if self._visible(a, b[None], keep=keep)[0]:
            return np.stack([a, b])
        n = len(self.nodes)
        if not n:
            return None
        va = self._visible(a, self.nodes, True, keep)
        vb = self._visible(b, self.nodes, True, keep)
        da = np.where(va, np.hypot(*(self.nodes - a).T), np.inf)
        db = np.where(vb, np.hypot(*(self.nodes - b).T), np.inf)
        tot = da[:, None] + self.dist + db[None, :]
        k = int(np.argmin(tot))
        i, j = divmod(k, n)
        if not np.isfinite(tot[i, j]):
            return None
        chain = [j]
        while chain[-1] != i:
            chain.append(int(self.pred[i, chain[-1]]))
        return np.vstack([a, self.nodes[chain[::-1]], b])

    def length(self, a, b) -> float:
        """Length of :meth:`path` (``inf`` when there is none)."""
        p = self.path(a, b)
        return float(np.hypot(*np.diff(p, axis=0).T).sum()) if p is not None else np.inf

    def crosses(self, starts, ends) -> np.ndarray:
        """Bool (L,): legs ``starts -> ends`` ((L, 2) each) that enter the zones grown by c
        (the obstacle; vectorised, for local search)."""
        if not self.active:
            return np.zeros(len(np.asarray(starts).reshape(-1, 2)), dtype=bool)
        return self._edges.segment_crosses(np.asarray(starts, float), np.asarray(ends, float))

    def enters_zones(self, starts, ends) -> np.ndarray:
        """Bool (L,): legs ``starts -> ends`` ((L, 2) each) that meet the zones themselves
        (grown by 1 m; eq. 20 proper, not the clearance), shapely's ``intersects`` answered as
        the module doc's "Speed" says (i24-zonepolish: the polish's check)."""
        a = np.asarray(starts, dtype=float).reshape(-1, 2)
        if not self.active or not len(a):
            return np.zeros(len(a), dtype=bool)
        return self._hits(self.raw, a, np.asarray(ends, dtype=float).reshape(-1, 2))

    def pieces(self, a, b) -> list[tuple[np.ndarray, np.ndarray]]:
        """The parts of the leg ``a -> b`` outside the keep-out area, in flight order."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        if not self.active:
            return [(a, b)]
        key = _key(a, b)
        if key in self._pieces:
            return list(self._pieces[key])
        res = self._clip(a, b)
        self._remember(self._pieces, key, res)
        return list(res)

    def _clip(self, a: np.ndarray, b: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        seg = LineString([a, b]) if np.any(a != b) else None
        if seg is None:
            return [] if self.keep_out.contains(Point(a)) else [(a, b)]
        if not self._hits(self.keep_out, a[None], b[None])[0]:
            return [(a, b)]
        return self._parts(a, b, seg.difference(self.keep_out))

    @staticmethod
    def _parts(a: np.ndarray, b: np.ndarray, rest: Any) -> list[tuple[np.ndarray, np.ndarray]]:
        """The pieces of the leg ``a -> b`` left in ``rest`` (its difference with the keep-out
        area), in flight order."""
        out = []
        d = b - a
        for g in getattr(rest, "geoms", [rest]):
            if g.is_empty or g.length <= 1e-6:
                continue
            c = np.asarray(g.coords)[:, :2]
            t = (c - a) @ d
            c = c[np.argsort(t)]
            out.append((np.asarray(c[0]), np.asarray(c[-1]), float(np.min(t))))
        out.sort(key=lambda r: r[2])
        return [(s, e) for s, e, _ in out]

    def _clip_legs(self, a: np.ndarray, b: np.ndarray) -> None:
        """Remember :meth:`pieces` of the legs ``a[i] -> b[i]`` ((L, 2) each, every one known
        to meet the keep-out area) not remembered yet: :meth:`_clip`'s answers, the differences
        taken in one shapely call."""
        keys = [_key(p, q) for p, q in zip(a, b)]
        todo = [i for i, k in enumerate(keys) if k not in self._pieces and np.any(a[i] != b[i])]
        if len(todo) < 2:
            return
        rest = shapely.difference(
            shapely.linestrings(np.stack([a[todo], b[todo]], axis=1)), self.keep_out
        )
        for i, r in zip(todo, rest):
            self._remember(self._pieces, keys[i], self._parts(a[i].copy(), b[i].copy(), r))

    def reroute(self, points) -> np.ndarray:
        """``points`` (take-off, waypoints, landing) made flyable: each leg cut to its parts
        outside the keep-out area, consecutive parts joined by :meth:`path` (a part that cannot
        be reached is dropped). The first and last points are kept."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if not self.active or len(pts) < 2:
            return pts
        if self.reference:
            return self._reroute(pts)
        key = pts.tobytes()
        got = self._routes.get(key)
        if got is None:
            got = self._reroute(pts)
            self._remember(self._routes, key, got)
        return got.copy()

    def _reroute(self, pts: np.ndarray) -> np.ndarray:
        """:meth:`reroute` of ``pts`` ((n, 2), n >= 2)."""
        cur = pts[0]
        out = [cur]
        eps = 1e-6

        def go(to) -> bool:
            nonlocal cur
            if float(np.hypot(*(to - cur))) <= eps:
                return True
            p = self.path(cur, to)
            if p is None:
                return False
            out.extend(p[1:])
            cur = out[-1]
            return True

        # legs clear of the keep-out area are their own piece (one batched test); the fast
        # router clips the others in one call and goes straight on along a run of clear legs
        # (the route is then at the leg's start itself: going there adds nothing)
        clear = ~self._hits(self.keep_out, pts[:-1], pts[1:])
        fast = not self.reference
        if fast:
            cut = np.flatnonzero(~clear)
            self._clip_legs(pts[cut], pts[cut + 1])
        at = False  # the route is at the leg's start itself (a clear leg's end)
        for leg, (p, q) in enumerate(itertools.pairwise(pts)):
            if at and clear[leg]:
                out.append(q)
                cur = q
                continue
            at = False
            for s, e in [(p, q)] if clear[leg] else self.pieces(p, q):
                if go(s):
                    out.append(e)
                    cur = e
                    at = fast and bool(clear[leg])
        if not go(pts[-1]):
            out.append(pts[-1])  # no flyable way: the straight leg (the caller checks)
        res = np.asarray(out)
        keep = np.ones(len(res), dtype=bool)
        keep[1:] = np.hypot(*np.diff(res, axis=0).T) > eps
        return res[keep]

    def flyable(self, points) -> bool:
        """Whether the polyline ``points`` enters no zone (eq. 20, every leg)."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if not self.active or len(pts) < 2:
            return True
        return not bool(shapely.intersects(LineString(pts), shapely.union_all(self.zones)))

    def reach_share(
        self,
        grid: Any,
        *,
        reach_m: float,
        zones_only: bool = False,
        samples_per_cell: int | None = None,
    ) -> np.ndarray:
        """(ny, nx): the share of each cell within ``reach_m`` of flyable airspace (1 away from
        zones): the part of a zone's interior a sensor of lateral range ``reach_m`` reaches from
        outside (:func:`poc_env.theory.regions.reach_share`, the one implementation).

        Parameters
        ----------
        grid:
            The :class:`~poc_env.theory.probability_map.Grid` of the cells.
        reach_m:
            The sensor's lateral range: ``W / 2`` in the planners' model (a sweep of width
            ``W``); the detection law's reach for the bounds
            (:func:`poc_env.theory.bound.zone_reach`). Keyword-only: the method used to take
            the sweep width ``W`` in its place, and an old call now fails instead of
            discounting with twice the reach.
        zones_only:
            Measure depth into the zones themselves (what the environment forbids, eq. 20)
            instead of the keep-out area (the zones grown by the clearance, where the planners
            route). The bounds use the zones: a flight may pass closer than the clearance.
        samples_per_cell:
            ``None``: the share of each cell's area (the planners' measure); an integer: the
            share of its sample points (the bounds' measure).
        """
        if not self.active:
            return np.ones(grid.shape)
        region = self._zones_union if zones_only else self.keep_out
        return reach_share(region, grid, reach_m, samples_per_cell=samples_per_cell)
