"""The allocation planner: flyable tracks from the reach-aware optimal allocation of effort.

``poc-env plan --planner allocation`` and the ``allocation_plan`` policy
(:mod:`poc_env.agents.policies.allocation`). Steps of :func:`make_allocation_plan`:

1. **Allocation.** :func:`poc_env.theory.bound.reach_optimum` with the plan's own limits: each
   UAV sweeps ``eta W v_s`` m^2/s (``v_s`` the search speed, ``eta`` the share of pattern time
   spent on search lines, below) for the usable endurance 0.85 T (eq. 18) and needs the
   round trip ``(d(take-off, cell) + d(cell, landing)) / v_c`` at cruise speed to reach a cell.
   The result is the coverage ``C_j`` each cell should get.
2. **Tracks.** Coverage is laid as nested layers of parallel lines along x (or along y: every
   step runs on the map mirrored about its diagonal too, and the better one is kept). With
   ``Delta = max C / K`` (``K`` = ``levels``) the lines lie on a lattice of spacing
   ``h = W / max C`` (eq. 10: ``C = W / d``); lattice line ``i`` belongs to layer
   ``k = i mod K + 1`` and flies over the cells of its row whose coverage is at least
   ``(k - 1/2) Delta`` (``K`` is tried from ``levels``, default 3, 4, 6). A cell of coverage
   ``C`` is crossed by the lines of ``round(C / Delta)``
   layers, i.e. by lines at spacing ``W / (round(C / Delta) Delta)``, the coverage the allocation
   asks for up to the rounding. Lines are clipped to the cells, so nothing is flown outside the
   map.
3. **Route.** The lines of each connected region (8-connected cells of positive coverage) are
   flown boustrophedon (alternate directions, line by line in y); regions are chained nearest
   first from the airfields.
4. **Assignment.** The route is cut into contiguous pieces, one per UAV, greedily: each piece
   goes to the free UAV whose take-off is nearest its first point and grows while the UAV's
   eq. 17-18 time (transit at ``v_c`` out and home, lines and connections at ``v_s``, a
   half-turn at the maximum turn rate per line end) fits ``margin x 0.85 T``. Each line first
   goes to the airfield of least out-and-back distance and each field's lines are chained and
   cut among that field's UAVs; lines a field cannot fly go to UAVs left without a piece. Contiguous
   pieces put UAVs on different lines of the route at different times (deconfliction by
   construction; flown separation is measured, see docs/PLANNER.md). With no-fly zones every
   start's routes are made flyable round them UAV by UAV, each in its own lane where the
   router's way round (the same for every UAV) would break eq. 21 at the planned positions
   (:func:`poc_env.agents.planning.deconflict.in_lanes`; i24-deconflict).
5. **Effort scale.** Turns, connections and the cut into pieces cost time the allocation does
   not see, so steps 1-4 run for each ``eta`` of ``options.etas`` and each ``K`` and the plan keeps
   the one of highest planned POS (lines no UAV can fit are left unflown).
6. **Second start.** On large maps, one route chained over the whole map and cut into pieces
   spends much of each UAV's time in transit; the greedy rectangle plan
   (:mod:`poc_env.agents.planning.greedy_rectangles`: each UAV the best remaining rectangle it
   can search) is planned too, and so are the coverage boxes
   (:mod:`poc_env.agents.planning.coverage_boxes`: each UAV its own box and line spacing by
   the marginal gain of eq. 10 per cell; ``box_start=False`` leaves them out); with
   ``options.relax_start`` (off by default; i24-relax) the relaxation patches too
   (:mod:`poc_env.agents.planning.relax_patches`: each UAV its own sector of an allocation,
   laid graded; ``start`` ``"relax"``). The starts
   within ``options.refine_within`` of the best one's planned POS (at most ``refine_starts``) are
   refined and the plan keeps the best of them, refined or not, by the environment's model
   (:func:`sampled_sweep`) less the environment's violation penalty at the planned positions
   (``options.airspace_penalty``, off by default); ``start`` records which start and
   ``refined`` whether the refined routes were kept. Among the candidates within
   :data:`NOTHING` of the best the one of least total flight time is kept (i24-smallfix, F1),
   each with its UAVs that add less than :data:`GAIN_PER_HOUR` of the prior's mass per flight
   hour kept home first (i24-gainhour, G3).
7. **Polish** (``options.polish`` passes, off by default; i24-polish): the chosen routes are
   climbed by the environment's own sensor model (:func:`poc_env.agents.planning.polish.
   polish_routes`: waypoints moved, legs shifted sideways, slid, inserted or deleted while eq.
   17-18 and the refinement's airspace check hold), so ``posc`` never drops; on maps with
   no-fly zones no candidate may enter a zone or cut the router's clearance ring
   (:func:`~poc_env.agents.planning.polish.zone_guard`; i24-zonepolish; ``options.
   polish_zones=False`` skips the polish there as before, the regrade too; the regrade keeps
   its runs out of the zones by the same check since i24-smallfix); not
   on maps of more than ``options.polish_max_cells`` cells a side where it is set
   (i24-fastpolish; the settings say why it was skipped). The plan's optimizer
   settings record its passes and kept moves (``polish``).
   With ``options.polish_lines`` passes (off by default; i24-lines) a second polish follows,
   with the polish's moves and its ``block`` moves (a run of lawnmower lines translated as
   one) at radii ``options.polish_lines_radii``; the settings then also record its kept moves
   (``lines_moves``) and how many were block moves (``block_moves``).
   With ``options.polish_boxes`` passes (off by default; i24-boxes) a third polish follows
   with the box moves only (a route's box translated by ``options.polish_boxes_radii``,
   stretched or turned as one, an airfield's group of search parts translated or turned
   together); the settings then record how many it kept (``box_moves``).

The plan is the same schema-2 dict as :func:`poc_env.agents.planning.planner.make_plan` (see
:mod:`poc_env.agents.mission.plan`): per UAV the ``rectangle`` is ``null`` (a route plan has no
decision rectangle), ``areas_m`` the ground its search lines sweep (each line ``spacing_m``
wide, for maps and exports) and ``spacing_m`` the finest line spacing it flies
(``lines_along`` says whether the lines run along x or y); only
``waypoints_m`` is the route (``route`` true in the plan). Extra fields: ``planner``
(``"allocation"``), ``bound_reach`` (:func:`poc_env.theory.bound.reach_bound`, the environment's
reach-aware bound; also as ``bounds`` {``honest``, ``reach``} with
:func:`poc_env.theory.bound.honest_optimum`), ``allocation_pos`` (the allocation's own POS),
``eta`` and ``reason`` (why a plan is empty, else null). ``posc`` is the planned POS: the
whole flight paths (transit and connections sweep too) swept over the prior's sample points
with the environment's own detection law and cut-off (:func:`sampled_sweep`). It does not
depend on the cell size as W x length per cell (eq. 10 per cell) did: planned 0.4864 at 2.5 km
cells and 0.6097 at 5 km on ``paper_6_2`` where 0.5934 and 0.5861 were flown (figures now:
``poc-env bench plan --scale``, docs/PLANNER.md). ``eta``, ``K``, the line direction and the
start are still picked by W x length per cell, the score the refinement improves: picked by
the sampled model, the refined plan flew worse on ``small`` (0.627 against 0.646).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any, cast

import numpy as np

from poc_env.agents.mission.plan import SCHEMA
from poc_env.agents.planning.coverage_boxes import box_routes, cut_lines, sampled_boxes
from poc_env.agents.planning.coverage_lines import COVER_CAP, chain_regions, layered_tracks
from poc_env.agents.planning.deconflict import (
    FAN_DEG,
    LANE,
    apart,
    in_lanes,
    lanes,
    planned_positions,
)
from poc_env.agents.planning.flight_rules import (  # sampled_sweep: allocation's public scorer
    SPEED,
    Speeds,
    _swept_areas,
    plan_speeds,
    sampled_sweep,
)
from poc_env.agents.planning.flight_rules import path_coverage as _path_coverage
from poc_env.agents.planning.flight_rules import reserve_s as _reserve
from poc_env.agents.planning.geography import (
    found_scores,
    plan_geography,
    zone_prior,
)
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.polish import BOX_KINDS, KINDS, MOVES, polish_for
from poc_env.agents.planning.refine import (
    Airspace,
    fly_around,
    refine_routes,
    route_fits,
    route_time,
)
from poc_env.agents.planning.regrade import regrade_routes
from poc_env.agents.planning.relax_patches import field_groups, out_and_back, relax_routes
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, as_int
from poc_env.geometry import polyline_length
from poc_env.sim.core import operating_area, takeoff_heading
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.bound import field_key, reach_optimum, zone_reach
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.search_theory import pod_from_coverage, sweep_track

#: the planner's defaults (:class:`~poc_env.agents.planning.options.PlanOptions`; its fields
#: hold every choice of this planner and its starts, passed down as ``options``): the numbers
#: of coverage layers (K) tried, the share of 0.85 T a route may fill, the refinement's passes
#: and the starts refined. Kept as names for the callers that read them.
LEVELS = PlanOptions.levels
#: "Nothing", as a share of the prior's mass (``PlanOptions.nothing``; i24-smallfix, F1):
#: candidate plans whose planned POS lie within it of the best are tied, the one of least
#: total eq. 17 flight time kept (each with its UAVs below :data:`GAIN_PER_HOUR` kept home
#: first; until i24-gainhour it was also the plan's budget for them). 1e-4 of the mass: below
#: the 4 decimals POS_C is reported at, and below what any flying UAV finds on the reference
#: maps (``paper_6_2`` 0.06, 64 UAVs on a 150 km map 0.003).
NOTHING = PlanOptions.nothing
MARGIN = PlanOptions.margin
REFINE = PlanOptions.refine
REFINE_STARTS = PlanOptions.refine_starts
#: The floor a flying UAV must add, as a share of the prior's mass per eq. 17 flight hour
#: (``PlanOptions.gain_per_hour``; i24-gainhour, G3): a UAV whose route adds less than this
#: times its own flight hours to the plan's POS stays home (:func:`make_allocation_plan`'s
#: ``_home``). 1e-4 per hour (0.01 % per aircraft-hour): on the 500 km scenario at 48 UAVs
#: 19 UAVs fly 50.1 h where i24-smallfix's budget flew 24 for 64.9 h (flown POS_C -0.0012);
#: 5e-5 and 3e-4 measured beside it (results/plan_scale/i24-gainhour).
GAIN_PER_HOUR = PlanOptions.gain_per_hour


class _Reordered:
    """A scenario whose UAVs are taken in ``order`` (take-off and landing positions
    permuted; every other attribute the scenario's): :func:`~poc_env.agents.planning.
    deconflict.in_lanes` lanes UAVs in fleet order, each behind the ones before it, and the
    routes given to idle UAVs (i24-fleet) go behind every route already laid."""

    def __init__(self, sc: Scenario, order: list[int]) -> None:
        self._sc = sc
        self.takeoff_m = tuple(sc.takeoff_m[k] for k in order)
        self.landing_m = tuple(sc.landing_m[k] for k in order)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sc, name)


def _reordered(sc: Scenario, order: list[int]) -> Scenario:
    """``sc`` with its UAVs in ``order`` (:class:`_Reordered`), typed as a scenario."""
    return cast(Scenario, _Reordered(sc, order))


#: the fills again of a UAV whose filled route breaks eq. 21 (``PlanOptions.fill_apart``)
#: before it is left without a route (i24-stagger; ``_fill`` in :func:`make_allocation_plan`).
FILL_TRIES = 3
#: the distance, in ``d_s``, a filled route keeps from the flying UAVs at planned times
#: (:func:`~poc_env.agents.planning.deconflict.apart`; i24-stagger): a lane's width, for the
#: follower's drift (routes planned 1.1-1.4 km apart were flown 0.7 km apart). 1.0 (eq.
#: 21's d_s) was measured too (results/plan_scale/i24-stagger/README.md): 0.008 more planned
#: and 14 fewer idle UAVs at 48 UAVs on the audit's 500 km scenario, but 22 and 136 flown
#: collision steps away from the fields on two 40 x 40 cases where main flies 4 and 14.
FILL_WITHIN = LANE


def _mask_near(keep: np.ndarray, grid: Grid, s: int, at: np.ndarray, radius: float) -> None:
    """Zero ``keep`` (a value per sample point, :meth:`~poc_env.theory.probability_map.Grid.
    sample_points` with ``s``) within ``radius`` of each point of ``at`` ``(m, 2)``, in
    place."""
    h = grid.cell_m / s
    x0, y0 = grid.origin_m
    ny, nx = keep.shape
    for px, py in np.asarray(at, dtype=float).reshape(-1, 2):
        i0, i1 = max(int((px - radius - x0) // h), 0), min(int((px + radius - x0) // h) + 1, nx)
        j0, j1 = max(int((py - radius - y0) // h), 0), min(int((py + radius - y0) // h) + 1, ny)
        if i0 >= i1 or j0 >= j1:
            continue
        xs = x0 + (np.arange(i0, i1) + 0.5) * h
        ys = y0 + (np.arange(j0, j1) + 0.5) * h
        near = np.hypot(xs[None, :] - px, ys[:, None] - py) < radius
        keep[j0:j1, i0:i1][near] = 0.0


def _lines_of(routes) -> list[list[int]]:
    """Line indices per UAV of lawnmower routes (a line = two waypoints)."""
    return [list(range(len(r) // 2)) for r in routes]


def _check(sc: Scenario, prior: np.ndarray, grid: Grid) -> str | None:
    """ConfigError for malformed input; a reason string when the plan must be empty."""
    if prior.shape != grid.shape:
        raise ConfigError("prior", prior.shape, f"an array of the grid's shape {grid.shape}")
    if not np.all(np.isfinite(prior)) or np.any(prior < 0):
        raise ConfigError("prior", "array", "finite cell masses >= 0")
    x0, y0, x1, y1 = grid.bounds
    diag = float(np.hypot(x1 - x0, y1 - y0))
    if len(sc.takeoff_m) > 1 and sc.constraints.safety_distance_m >= diag:
        raise ConfigError(
            "constraints.safety_distance_km",
            sc.constraints.safety_distance_m / 1e3,
            f"below the map's diagonal {diag / 1e3:g} km (two UAVs could never search it apart)",
        )
    if float(prior.sum()) <= 0:
        return "the prior has no mass on the map"
    return None


def _split(route, takeoff, landing, sc: Scenario, margin: float, v: Speeds):
    """Contiguous route pieces per UAV (index lists), each piece's time, lines left unflown."""
    u = sc.uav
    budget = margin * u.usable_endurance_s
    turn_s = np.pi / u.max_turn_rate_rad_s  # a half-turn at the maximum rate
    n = len(takeoff)
    pieces: list[list[int]] = [[] for _ in range(n)]
    times = np.zeros(n)
    free = list(range(n))
    dropped = 0
    i = 0
    while i < len(route) and free:
        p0 = np.array([route[i][1], route[i][0]])
        placed = False
        for k in sorted(free, key=lambda j: float(np.hypot(*(takeoff[j] - p0)))):
            out_s = float(np.hypot(*(takeoff[k] - p0))) / v.out
            pattern = 0.0
            prev = None
            while i < len(route):
                y, a, b, _ = route[i]
                add = abs(b - a) / v.line
                if prev is not None:
                    add += float(np.hypot(a - prev[0], y - prev[1])) / v.line
                    add += turn_s
                home = float(np.hypot(*(landing[k] - np.array([b, y])))) / v.home
                if out_s + pattern + add + home > budget:
                    break
                pattern += add
                pieces[k].append(i)
                times[k] = out_s + pattern + home
                prev = (b, y)
                i += 1
            if pieces[k]:
                free.remove(k)
                placed = True
                break
        if not placed:  # no free UAV can fly this line alone: drop it
            dropped += 1
            i += 1
    return pieces, times, dropped + len(route) - i


def nearest_field(lines, heads: np.ndarray) -> np.ndarray:
    """The field of least out-and-back distance of each line ``(y, x_start, x_end, row)``:
    the index into ``heads`` ``(F, 2, 2)`` (per field its take-off and landing) of least
    ``|take-off - mid| + |landing - mid|``, ``mid`` the line's midpoint (ties: the lower
    index). All lines in one pass (elementwise the same operations as line by line, so the
    same fields: tests/planning/test_speed.py)."""
    if not len(lines):
        return np.zeros(0, dtype=np.int64)
    arr = np.asarray([ln[:3] for ln in lines], dtype=float)  # (L, 3): y, x_start, x_end
    mid = np.stack([0.5 * (arr[:, 1] + arr[:, 2]), arr[:, 0]], axis=1)  # (L, 2)
    to = heads[None, :, 0] - mid[:, None]  # (L, F, 2)
    la = heads[None, :, 1] - mid[:, None]
    d = np.hypot(to[..., 0], to[..., 1]) + np.hypot(la[..., 0], la[..., 1])
    return np.argmin(d, axis=1)


def _assign(regions, takeoff, landing, sc: Scenario, margin: float, v: Speeds):
    """Route and pieces per UAV: lines go to the field of least out-and-back distance, each
    field's lines are chained from it and cut among its UAVs (:func:`_split`); lines left over
    go to the UAVs left without a piece. Returns (route, pieces, times, lines unflown)."""
    n = len(takeoff)
    groups = field_groups(takeoff, landing)
    heads = np.array([[takeoff[g[0]], landing[g[0]]] for g in groups])  # (F, 2, 2)
    fid = [nearest_field(reg, heads) for reg in regions]  # each line's field, once
    route: list[tuple] = []
    pieces: list[list[int]] = [[] for _ in range(n)]
    times = np.zeros(n)
    leftover: list[tuple] = []
    for f, g in enumerate(groups):
        mine = [[ln for ln, q in zip(reg, fr, strict=True) if q == f]
                for reg, fr in zip(regions, fid, strict=True)]  # fmt: skip
        sub = chain_regions([r for r in mine if r], heads[f, 0])
        sp, st, _ = _split(sub, takeoff[g], landing[g], sc, margin, v)
        used = {j for p in sp for j in p}
        leftover += [ln for j, ln in enumerate(sub) if j not in used]
        base = len(route)
        route += sub
        for i, k in enumerate(g):
            pieces[k] = [base + j for j in sp[i]]
            times[k] = st[i]
    idle = [k for k in range(n) if not pieces[k]]
    if leftover and idle:
        sub = chain_regions([leftover], takeoff[idle].mean(axis=0))
        sp, st, _ = _split(sub, takeoff[idle], landing[idle], sc, margin, v)
        used = {j for p in sp for j in p}
        base = len(route)
        route += sub
        for i, k in enumerate(idle):
            pieces[k] = [base + j for j in sp[i]]
            times[k] = st[i]
        leftover = [ln for j, ln in enumerate(sub) if j not in used]
    return route, pieces, times, len(leftover)


def _fan_out(route, pieces, takeoff, sc: Scenario) -> list[list[list[float]]]:
    """Each UAV's waypoints; UAVs sharing a field first fly a dog-leg fanned out by bearing.

    UAVs taking off together towards nearby bearings would fly the transit side by side within
    d_s (eq. 21). Field-mates' bearings to their first lines are spread, lowest first, to at
    least ``FAN_DEG`` apart; a UAV whose bearing moved first flies to a point
    ``D = max(min(half the way, 8 km + 2 d_s), 4 d_s)`` out on its new bearing (the leg after
    it is flown at search speed by the follower), the others fly straight out at cruise speed.
    Straight paths ``FAN_DEG`` apart are ``d_s`` apart from ``d_s / sin FAN_DEG`` out (5.8 km
    for 10 deg and 1 km: the first two steps, when field-mates are together anyway).
    """
    wps = [
        [[float(x), float(route[j][0])] for j in idx for x in (route[j][1], route[j][2])]
        for idx in pieces
    ]
    return _spread(wps, takeoff, sc)


def _spread(wps, takeoff, sc: Scenario, taken=None) -> list[list[list[float]]]:
    """``wps`` (waypoints per UAV) with field-mates' outbound bearings spread by dog-legs
    (:func:`_fan_out`); lists are copied, ``wps`` is not changed. ``taken``: per UAV the
    outbound bearings (radians) field-mates not in ``wps`` fly already (the busy UAVs a fill
    joins, i24-stagger); each bearing is also moved up to ``FAN_DEG`` clear of those."""
    wps = [list(w) for w in wps]
    keys = [tuple(np.round(t, 3)) for t in takeoff]
    d_out = 8000.0 + 2 * sc.constraints.safety_distance_m
    box = operating_area(sc)  # eq. 20: a dog-leg stays inside, or is not flown
    for field in set(keys):
        mates = [k for k in range(len(takeoff)) if keys[k] == field and wps[k]]
        flown = sorted({float(b) for k in mates for b in (taken[k] if taken else ())})
        if len(mates) < 2 and not (mates and flown):
            continue
        a = takeoff[mates[0]]
        bearing = {k: float(np.arctan2(wps[k][0][1] - a[1], wps[k][0][0] - a[0])) for k in mates}
        ranked = sorted(mates, key=lambda k: bearing[k])
        gap = np.radians(FAN_DEG)
        prev = -np.inf
        for k in ranked:
            ang = max(bearing[k], prev + gap)
            for _ in flown:  # clear of the bearings flown already, moving up
                off = [(ang - b + np.pi) % (2 * np.pi) - np.pi for b in flown]
                if all(abs(d) >= gap for d in off):
                    break
                ang += gap - min(d for d in off if abs(d) < gap)
            prev = ang
            if ang == bearing[k]:
                continue
            dist = float(np.hypot(wps[k][0][0] - a[0], wps[k][0][1] - a[1]))
            reach = max(min(0.5 * dist, d_out), 4.0 * sc.constraints.safety_distance_m)
            if reach > _inside_reach(a, ang, box):  # only where the field is near eq. 20's edge
                continue
            wps[k] = [[float(a[0] + reach * np.cos(ang)), float(a[1] + reach * np.sin(ang))]] + wps[
                k
            ]
    return wps


def _inside_reach(a, ang: float, box: tuple[float, float, float, float]) -> float:
    """How far from ``a`` a straight leg on bearing ``ang`` (radians) stays inside the box
    ``(x0, y0, x1, y1)`` (eq. 20's operating area)."""
    out = np.inf
    for d, p, lo, hi in ((np.cos(ang), a[0], box[0], box[2]), (np.sin(ang), a[1], box[1], box[3])):
        if d > 1e-12:
            out = min(out, (hi - p) / d)
        elif d < -1e-12:
            out = min(out, (lo - p) / d)
    return float(out)


def fit_lawnmowers(
    routes, takeoff, landing, sc: Scenario, v: Speeds, headings, options: PlanOptions, taken=None
) -> list[list[list[float]]]:
    """A start's lawnmower routes (a line = two waypoints) with field-mates fanned out as the
    allocation's routes are (:func:`_spread`: eq. 21 on the way out), and each route's last
    lines dropped, the first dropped one flown in part (:func:`~poc_env.agents.planning.
    coverage_boxes.cut_lines`), until it keeps eq. 18 again (:func:`~poc_env.agents.planning.
    refine.route_fits`). ``taken``: :func:`_spread`'s bearings flown already, per UAV."""
    u = sc.uav
    w = sc.sensor.sweep_width_m
    rs = _spread(routes, takeoff, sc, taken)
    for k in range(len(takeoff)):
        arr = np.asarray(rs[k], dtype=float).reshape(-1, 2)
        lead = len(arr) % 2  # the dog-leg's waypoint before the lines

        def fits(q, k=k, arr=arr, lead=lead) -> bool:
            return route_fits(
                np.vstack([takeoff[k], arr[:lead], q, landing[k]]),
                v,
                u.max_turn_rate_rad_s,
                u.usable_endurance_s,
                _reserve(sc),
                headings[k],
            )

        if len(arr) and not fits(arr[lead:]):  # the last line cut short, or dropped
            arr = np.vstack([arr[:lead], cut_lines(arr[lead:], fits, w, options)[0]])
        rs[k] = [] if len(arr) - lead < 2 else arr.tolist()
    return rs


def _leave_one_out(belief: np.ndarray, sweep, idx: list[int]) -> dict[int, float]:
    """For each path ``k`` of ``idx``, the sum of ``belief`` once every other path of ``idx``
    has swept it (``sweep(belief, j)`` updates it in place by eq. 14; ``belief`` is consumed).
    Eq. 14 multiplies each sample point by each path's miss probability, so the order does not
    matter: the halves of ``idx`` sweep a copy for each other in turn, down to one path each,
    ``len(idx) log2 len(idx)`` sweeps where leaving each path out in turn takes
    ``len(idx)**2`` (i24-gainhour: every flying UAV's exact marginal POS)."""
    if len(idx) <= 1:
        return {k: float(belief.sum()) for k in idx}
    first, second = idx[: len(idx) // 2], idx[len(idx) // 2 :]
    part = belief.copy()
    for j in second:
        sweep(part, j)
    out = _leave_one_out(part, sweep, first)
    for j in first:  # the original consumed by the second half
        sweep(belief, j)
    return out | _leave_one_out(belief, sweep, second)


def _flight_time(wps, takeoff, landing, sc: Scenario, v: Speeds, heading0=None) -> float:
    """Eq. 17 time of a route (:func:`poc_env.agents.planning.refine.route_time`: out at ``v.out``,
    on the route at ``v.line``, home at ``v.home``, turns at the maximum turn rate)."""
    if not len(wps):
        return 0.0
    path = np.vstack([takeoff, np.asarray(wps, dtype=float).reshape(-1, 2), landing])
    return route_time(path, v, sc.uav.max_turn_rate_rad_s, heading0)


def _trim(routes, pieces, takeoff, landing, sc: Scenario, v: Speeds, headings) -> None:
    """Drop each UAV's last search lines until its route (dog-leg included) is flown whole
    under eq. 18 (:func:`poc_env.agents.planning.refine.route_fits`)."""
    u = sc.uav
    for k, idx in enumerate(pieces):
        while idx and not route_fits(
            np.vstack([takeoff[k], np.asarray(routes[k]).reshape(-1, 2), landing[k]]),
            v,
            u.max_turn_rate_rad_s,
            u.usable_endurance_s,
            _reserve(sc),
            headings[k],
        ):
            idx.pop()
            del routes[k][-2:]
        if not idx:
            routes[k].clear()


def _cell_pos(paths, takeoff, landing, prior, grid: Grid, w: float, law: str) -> float:
    """The POS the refinement scores routes by (:func:`poc_env.agents.planning.refine.
    refine_routes`): W x length per cell, eq. 10 per cell; it picks the start to refine."""
    cov = sum(
        (
            _path_coverage([takeoff[j], *paths[j], landing[j]], grid, w)
            for j in range(len(paths))
            if paths[j]
        ),
        np.zeros(grid.shape),
    )
    return float(np.sum(prior * pod_from_coverage(cov, law)))


def violation_penalty(
    sc: Scenario, routes, v: Speeds | None = None, options: PlanOptions | None = None
) -> float:
    """The environment's violation penalty of ``routes`` (waypoints per UAV between its
    take-off and landing) at their planned positions, in POS: ``reward.violation_penalty`` per
    UAV-step in violation of eq. 21 / 24 (:func:`~poc_env.agents.planning.refine.
    swarm_violations`, every ``dt``, with margins ``options.penalty_separation`` on d_s and
    ``options.penalty_range`` on the range, by default the refinement's: the follower flies the
    route, not its timing, to the second) over ``alpha`` x UAVs (team
    credit: every UAV is credited the swarm's POS, so this is the reward's own exchange rate),
    times ``options.penalty_weight``."""
    opt = PlanOptions() if options is None else options
    v = plan_speeds(sc, SPEED) if v is None else v
    air = Airspace(
        sc.episode.dt_s,
        opt.penalty_separation * sc.constraints.safety_distance_m,
        opt.penalty_range * sc.comms.range_m,
        sc.comms.min_neighbours,
    )
    _, pos, act = planned_positions(sc, routes, v, air.dt_s)
    n = pos.shape[1]
    rw = sc.reward
    rate = opt.penalty_weight * rw.violation_penalty / (max(rw.alpha, 1e-12) * n)
    return rate * air.violations(pos, act)


def _mapped(sc: Scenario, plan: dict[str, Any], check: bool = True) -> list[list[list[float]]]:
    """The routes of ``plan`` (a plan of fewer UAVs, :func:`plan_fleets`) given to ``sc``'s
    UAVs of the same airfields (take-off and landing to the millimetre,
    :func:`~poc_env.theory.bound.field_key`), in fleet order; the UAVs left over get none.
    A plan with more UAVs of a field than ``sc`` has, or one that is not a plan
    (:func:`~poc_env.agents.mission.plan.check_plan`, its fields named ``floor...``), raises
    :class:`ConfigError`; ``check=False``: ``plan`` is the planner's own (``half_fleet``), not
    checked (its POS may round above 1)."""
    from poc_env.agents.mission.plan import check_plan

    try:
        if check:
            check_plan(plan)
    except ConfigError as e:  # i24-dayaudit: a str or {} floor raised AttributeError / KeyError
        field = "floor" + e.field[len("plan") :] if e.field.startswith("plan") else e.field
        raise ConfigError(field, e.value, e.allowed) from None
    keys = [field_key(a, b) for a, b in zip(sc.takeoff_m, sc.landing_m, strict=True)]
    free = list(range(len(keys)))
    out: list[list[list[float]]] = [[] for _ in keys]
    for j, uu in enumerate(plan.get("uavs", [])):
        key = field_key(uu["takeoff_m"], uu["landing_m"])
        k = next((i for i in free if keys[i] == key), None)
        if k is None:
            raise ConfigError(
                f"floor.uavs[{j}]", [uu["takeoff_m"], uu["landing_m"]],
                "a UAV of an airfield with a UAV left in this scenario's fleet (a plan of "
                "fewer UAVs of the same scenario)",
            )  # fmt: skip
        free.remove(k)
        out[k] = [[float(a), float(b)] for a, b in uu["waypoints_m"]]
    return out


def plan_fleets(
    scenario: Scenario | str,
    sizes,
    *,
    prior: np.ndarray | None = None,
    each: Callable[[dict[str, Any]], object] | None = None,
    **kw,
) -> list[dict[str, Any]]:
    """The allocation plans of ``scenario`` with each fleet size of ``sizes`` (the fleet's own
    take-off/landing pairs, one from each group in turn, :meth:`~poc_env.config.Scenario.
    with_uavs`), in
    increasing order, each planned with the one before as its ``floor``
    (:func:`make_allocation_plan`): POS_C non-decreasing in the fleet (up to float rounding;
    i24-fleet) wherever the floor's routes keep the fill's clearance; with ``fill_apart`` a
    floor route that does not is flown anew, which can cost POS_C (i24-chain). ``each``:
    called with each plan as it is made (``plan --fleet-sizes``'s progress; i24-fleetcli).
    ``kw``: :func:`make_allocation_plan`'s other keywords."""
    sc = load_scenario(scenario)
    one = np.ndim(sizes) == 0  # a list's bad entry named by its index (i24-dayaudit)
    ns = sorted({
        as_int("sizes" if one else f"sizes[{i}]", n, 1, 64)
        for i, n in enumerate([sizes] if one else np.asarray(sizes, dtype=object).tolist())
    })  # fmt: skip
    if not ns:
        raise ConfigError("sizes", sizes, "one or more fleet sizes in [1, 64]")
    plans: list[dict[str, Any]] = []
    for n in ns:
        floor = plans[-1] if plans else None
        plans.append(make_allocation_plan(sc.with_uavs(n), prior=prior, floor=floor, **kw))
        if each is not None:
            each(plans[-1])
    return plans


#: the fields of ``opt`` its default plan keeps (:func:`_best_of_default`): the keyword-level
#: ones and every ``polish*`` field, so a polish option added later is kept without a change
#: here -- except ``polish_starts``: the default plan polishes its own chosen start only (as
#: the recorded ``polish_starts=2`` runs of results/plan_scale/grade did); and ``nothing``
#: (i24-smallfix: ``nothing=0`` flies every route in both plans) and ``gain_per_hour``.
_DEFAULT_KEPT = (
    "levels", "etas", "margin", "refine", "refine_starts", "greedy_start", "box_start",
    "nothing", "gain_per_hour",
    *(f.name for f in dataclasses.fields(PlanOptions)
      if f.name.startswith("polish") and f.name != "polish_starts"),
)  # fmt: skip


def default_options(opt: PlanOptions) -> PlanOptions:
    """The options of ``opt``'s default plan under ``also_default``: ``PlanOptions()`` with
    ``opt``'s :data:`_DEFAULT_KEPT` fields."""
    return PlanOptions(**{k: getattr(opt, k) for k in _DEFAULT_KEPT})


def _best_of_default(sc, prior, map_source, seed, speed, crs, opt: PlanOptions, t0: float):
    """``opt.also_default``: the plan with ``opt`` and the default plan (``PlanOptions()`` with
    ``opt``'s keyword-level fields: levels, margin, refine, starts; and its polish), the one
    of more planned POS kept (ties: ``opt``'s). The effort levels' guarantee: a thorough plan
    never plans less POS than the default one (polished alike). (By POS alone: the default
    plan is the shipped planner's, its violations accepted as they are; ``opt``'s own pick
    among its starts is the one that prices violations, ``airspace_penalty``.)"""
    kw = {"prior": prior, "map_source": map_source, "seed": seed, "speed": speed, "crs": crs}
    mine = make_allocation_plan(sc, options=dataclasses.replace(opt, also_default=False), **kw)
    base = make_allocation_plan(sc, options=default_options(opt), **kw)
    kept = mine if float(mine["posc"]) >= float(base["posc"]) else base
    settings = {**kept["optimizer"]["settings"], "options": opt.changed()}
    settings["kept"] = "default" if kept is base else "options"
    return {
        **kept,
        "optimizer": {**kept["optimizer"], "settings": settings},
        "runtime_s": time.perf_counter() - t0,
    }


def make_allocation_plan(
    scenario: Scenario | str = "paper_6_2",
    *,
    prior: np.ndarray | None = None,
    map_source: str = "builtin",
    uavs: int | None = None,
    seed: int = 0,
    levels: int | tuple[int, ...] | None = None,
    margin: float | None = None,
    speed: str = SPEED,
    refine: int | None = None,
    crs: dict[str, Any] | None = None,
    greedy_start: bool | None = None,
    box_start: bool | None = None,
    refine_starts: int | None = None,
    options: PlanOptions | None = None,
    floor: dict[str, Any] | None = None,
    _half: bool = False,
) -> dict[str, Any]:
    """The allocation plan of ``scenario`` on ``prior`` (see the module docstring); ``crs``
    (a :func:`poc_env.agents.mission.crs.make_crs` record) is recorded for exports.

    ``greedy_start``: also start from the greedy rectangle plan
    (:func:`poc_env.agents.planning.greedy_rectangles.make_greedy_rectangles_plan`);
    ``box_start``: also from the coverage boxes
    (:func:`poc_env.agents.planning.coverage_boxes.box_routes`); ``refine_starts``: how many of
    the best starts may be refined (module docstring, step 6; ``start`` in the plan says which
    was kept). ``options``: every other choice of the planner
    (:class:`~poc_env.agents.planning.options.PlanOptions`; default ``PlanOptions()``, the
    ``"default"`` effort level; ``PlanOptions.preset("thorough")`` for the slower, better one);
    ``levels``, ``margin``, ``refine``, ``greedy_start``, ``box_start`` and ``refine_starts``
    given here override its fields of the same names. ``floor``: a plan of this scenario and
    prior for fewer UAVs (:func:`plan_fleets`; i24-fleet): its routes flown by UAVs of the
    same airfields here, the UAVs left over given coverage boxes on the mass those routes
    leave (``options.fill_idle``'s fill), kept instead of this plan if that plans more POS, so
    the plan never plans less than ``floor`` (up to float rounding) -- with
    ``options.fill_apart`` (default) only where ``floor``'s routes keep the fill's clearance:
    they go through the fill's own check first (:func:`~poc_env.agents.planning.deconflict.
    apart` at :data:`FILL_WITHIN`), a route that fails it flown anew by the fill (i24-chain);
    ``optimizer.settings.fleet`` records it. Without ``floor``, a plan that leaves a UAV
    without a route is compared so with the plan of half its fleet
    (``options.half_fleet``; ``fleet.floor`` is then ``"half_fleet"``) and, from
    ``options.three_quarter_from`` UAVs (0, off, by default), with the plan of three quarters
    of it too (i24-monotone; ``fleet.floors``, ``fleet.kept_uavs``).

    ``_half`` (internal): this is the half fleet's plan of a larger one (``half_fleet``), whose
    idle UAVs that plan fills; ``own_apart`` may then leave UAVs idle (i24-ownclear).

    Deterministic (``seed`` is recorded only). Malformed input raises
    :class:`~poc_env.errors.ConfigError`; a plan that cannot search anything (no mass, no UAV
    reaching any mass) has empty waypoint lists, ``posc`` 0 and a ``reason``.
    """
    t0 = time.perf_counter()
    sc = load_scenario(scenario)
    if uavs is not None:
        sc = sc.with_uavs(as_int("uavs", uavs, 1, 64))
    opt = PlanOptions() if options is None else options
    if not isinstance(opt, PlanOptions):
        raise ConfigError("options", opt, "a PlanOptions (poc_env.agents.planning.options)")
    if levels is not None:
        ks = [as_int("levels", k, 1, 64) for k in np.atleast_1d(levels).tolist()]
        opt = dataclasses.replace(opt, levels=tuple(ks))
    if refine is not None:
        opt = dataclasses.replace(opt, refine=as_int("refine", refine, 0, 100))
    if margin is not None:
        if not (0.1 <= float(margin) <= 1.0):
            raise ConfigError("margin", margin, "a share of 0.85 T in [0.1, 1]")
        opt = dataclasses.replace(opt, margin=float(margin))
    if refine_starts is not None:
        opt = dataclasses.replace(opt, refine_starts=as_int("refine_starts", refine_starts, 1, 3))
    if greedy_start is not None:
        opt = dataclasses.replace(opt, greedy_start=bool(greedy_start))
    if box_start is not None:
        opt = dataclasses.replace(opt, box_start=bool(box_start))
    if opt.also_default:
        if floor is not None:
            raise ConfigError("floor", "a plan", "no floor with options.also_default")
        return _best_of_default(sc, prior, map_source, seed, speed, crs, opt, t0)
    mapped = None if floor is None else _mapped(sc, floor)  # bad input before any planning
    ks = list(opt.levels)
    refine = opt.refine
    margin = opt.margin
    greedy_start, box_start, refine_starts = opt.greedy_start, opt.box_start, opt.refine_starts
    grid = Grid.from_config(sc.map)
    prior = build_prior(sc.map) if prior is None else np.asarray(prior, dtype=float)
    reason = _check(sc, prior, grid)
    router = ZoneRouter.for_scenario(sc)
    full_prior = prior
    if router.active:  # the mass a sensor reaches from outside the zones (eq. 20)
        prior = zone_prior(sc, prior, router, opt.zone_reach)
        if reason is None and float(prior.sum()) <= 0:
            reason = "the prior has no mass outside the no-fly zones"
    u = sc.uav
    w = sc.sensor.sweep_width_m
    law = sc.sensor.law
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    n = len(takeoff)
    v = plan_speeds(sc, speed)
    tau = out_and_back(grid, takeoff, landing, v)
    budget = np.full(n, u.usable_endurance_s)
    if reason is None and not np.any((tau < budget[:, None, None]) & (prior > 0)[None]):
        reason = "no UAV can reach any mass and come back within 0.85 T (eq. 18)"

    oy_ox = (grid.origin_m[1], grid.origin_m[0])
    frames = {  # lines along x, or along y (the same code on the mirrored map)
        False: (grid, takeoff, landing, prior),
        True: (
            Grid(grid.ny, grid.nx, grid.cell_m, oy_ox),
            takeoff[:, ::-1],
            landing[:, ::-1],
            prior.T,
        ),
    }

    def build(alloc, k: int, swap: bool):
        g_f, to_f, la_f, _ = frames[swap]
        cov = alloc.coverage.T if swap else alloc.coverage
        regions = layered_tracks(cov, g_f, w, k)
        route, pieces, times, left = _assign(regions, to_f, la_f, sc, margin, v)
        return alloc, route, pieces, times, left, swap

    def fly(res) -> tuple[list, list]:
        """Waypoints (map frame) and line indices per UAV of a build, fanned out and trimmed."""
        _, route, pieces, _, _, swap = res
        g_f, to_f, la_f, _ = frames[swap]
        paths = _fan_out(route, pieces, to_f, sc)
        idx = [list(p) for p in pieces]
        _trim(paths, idx, to_f, la_f, sc, v, takeoff_heading(g_f.bounds, to_f))
        if swap:
            paths = [[[q[1], q[0]] for q in path] for path in paths]
        if router.active:
            paths = _around_all(paths)
        return paths, idx

    heading0 = takeoff_heading(grid.bounds, takeoff)

    def _around(k: int, wps, lane: int = 0) -> list[list[float]]:
        """UAV ``k``'s waypoints made flyable around the zones in lane ``lane``
        (:func:`~poc_env.agents.planning.deconflict.lanes`), cut to fit eq. 18."""
        path = fly_around(
            router,
            np.vstack([takeoff[k], np.asarray(wps, dtype=float).reshape(-1, 2), landing[k]]),
            lambda p: route_fits(
                p, v, u.max_turn_rate_rad_s, u.usable_endurance_s, _reserve(sc), heading0[k]
            ),
            lambda p: lanes(p, lane, sc.constraints.safety_distance_m, router),
        )
        return [[float(a), float(b)] for a, b in path[1:-1]]

    def _around_all(rs) -> list[list[list[float]]]:
        """Every UAV's waypoints made flyable around the zones, each in its own lane where the
        router's way round would put it within d_s of another (i24-deconflict: the router
        gives field-mates the same way round, eq. 21)."""
        return in_lanes(sc, rs, v, _around)

    def _lawnmower_start(rs) -> list[list[list[float]]]:
        """A start's lawnmower routes fitted (:func:`fit_lawnmowers`) and routed around the
        zones."""
        rs = fit_lawnmowers(rs, takeoff, landing, sc, v, heading0, opt)
        if router.active:
            rs = _around_all(rs)
        return rs

    def _reversed(k: int, wps) -> list:
        """UAV ``k``'s lawnmower waypoints flown from the other end (the fan-out's dog-leg
        first, as laid), if that keeps eq. 18: an alternative for :func:`apart` on maps
        without zones (with zones :func:`in_lanes` has tried it)."""
        arr = np.asarray(wps, dtype=float).reshape(-1, 2)
        lead = len(arr) % 2
        q = np.vstack([arr[:lead], arr[lead:][::-1]])
        path = np.vstack([takeoff[k], q, landing[k]])
        fits = route_fits(
            path, v, u.max_turn_rate_rad_s, u.usable_endurance_s, _reserve(sc), heading0[k]
        )
        return [q.tolist()] if fits and len(arr) - lead > 2 else []

    # the alternatives apart tries for a route (with zones in_lanes has tried them)
    _alternative: Callable[[int, Any], list] | None = None if router.active else _reversed

    def _bearings(rs, todo) -> list[list[float]] | None:
        """Per UAV of ``todo`` the outbound bearings of its field-mates with a route in ``rs``
        (their first waypoint from the field), for the fill's fan-out (:func:`_spread`);
        ``None`` without ``fill_apart`` (the i24-fleet fill, fanned among itself)."""
        if not opt.fill_apart:
            return None
        keys = [tuple(np.round(t, 3)) for t in takeoff]
        return [
            [
                float(np.arctan2(rs[j][0][1] - takeoff[j][1], rs[j][0][0] - takeoff[j][0]))
                for j in range(n)
                if len(rs[j]) and keys[j] == keys[k]
            ]
            for k in todo
        ]

    def _fill(rs) -> list[list[list[float]]]:
        """``rs`` with its UAVs without a route given the coverage boxes
        (:func:`~poc_env.agents.planning.coverage_boxes.box_routes`) of the mass the other
        routes leave on the sample points (eq. 14, the environment's sensor; the prior as the
        starts see it, zone interiors discounted), fitted to eq. 18 and, with zones, in lanes
        behind the routes already laid (i24-fleet). With ``fill_apart`` (i24-stagger) the
        fill fans out clear of the bearings its busy field-mates fly (:func:`_spread`), and a
        filled route whose planned flight comes within ``FILL_WITHIN x d_s`` of a UAV (busy,
        or filled and kept before it; :func:`~poc_env.agents.planning.deconflict.apart`; on
        maps without zones after its box flown from the other end) is not dropped at once:
        its UAV is filled again, up to :data:`FILL_TRIES` times, on the mass the routes kept
        leave with the mass within ``d_s + W/2`` of its conflicting positions taken out, so
        it takes a box away from the UAVs it met.
        ``rs`` itself (the same object) when no UAV is idle, none is busy (that is the boxes
        start's own job) or nothing is gained."""
        idle = [k for k in range(n) if not len(rs[k])]
        if not idle or len(idle) == n:
            return rs
        s = sc.sensor.samples_per_cell
        cutoff = sc.sensor.cutoff_sweep_widths * w
        d_s = sc.constraints.safety_distance_m
        fine = np.ascontiguousarray(grid.refine(prior, s))
        keep = np.ones_like(fine)  # the share of each sample point's mass offered to the fill
        out = [list(r) for r in rs]
        todo = idle
        for _ in range(1 + (FILL_TRIES if opt.fill_apart else 0)):
            bel = fine * keep
            for k in range(n):
                if len(out[k]):
                    path = np.vstack([takeoff[k], np.asarray(out[k], dtype=float), landing[k]])
                    sweep_track(bel, grid, s, path, w, law, cutoff, grid.cell_m)
            ix = np.asarray(todo)
            new = box_routes(
                grid.coarsen(bel, s),
                grid,
                w,
                law,
                v,
                takeoff[ix],
                landing[ix],
                u.usable_endurance_s,
                u.max_turn_rate_rad_s,
                _reserve(sc),
                heading0[ix],
                sampled=(bel, s, cutoff),
                options=dataclasses.replace(
                    opt, rounds=opt.fill_rounds, chain_rounds=opt.fill_rounds
                ),
            )
            fixed = [k for k in range(n) if len(out[k])]
            new = fit_lawnmowers(
                new, takeoff[ix], landing[ix], sc, v, heading0[ix], opt, _bearings(out, todo)
            )
            if not any(new):
                break
            for j, k in enumerate(todo):
                out[k] = new[j]
            if router.active:  # the new routes in lanes behind every route already laid
                order = fixed + todo
                laid = in_lanes(
                    _reordered(sc, order),
                    [out[k] for k in order],
                    v,
                    lambda j, q, lane, order=order, fixed=fixed, now=out: (
                        now[order[j]] if order[j] in fixed else _around(order[j], q, lane)
                    ),
                )
                for j, k in enumerate(order):
                    if k not in fixed:
                        out[k] = laid[j]
            if not opt.fill_apart:
                break
            out, where = apart(sc, out, v, todo, _alternative, FILL_WITHIN)
            if not where:
                break
            for at in where.values():  # the mass it met taken out of its next fill
                _mask_near(keep, grid, s, at, d_s + w / 2)
            todo = sorted(where)
        if not any(out[k] for k in idle):
            return rs
        return out

    eta = 0.0
    chosen = 0
    best: tuple[Any, ...] | None = None
    best_val = -1.0
    fleet = None
    if reason is None:
        for cand, k in [(e, k) for e in opt.etas for k in ks]:
            if k == ks[0]:
                alloc = reach_optimum(
                    prior,
                    grid.cell_area_m2,
                    tau,
                    np.full(n, cand * w * v.line),
                    budget,
                    law,
                )
            for swap in (False, True):
                res = build(alloc, k, swap)
                paths, _ = fly(res)
                val = _cell_pos(paths, takeoff, landing, prior, grid, w, law)
                if val > best_val:
                    best, best_val, eta, chosen = res, val, cand, k
        # the bound credits what the environment's sensor detects from outside the zones (its
        # law's reach), not the planner's W/2 discount above (zone_reach; unchanged without)
        fleet = reach_optimum(*zone_reach(sc, full_prior), tau, np.full(n, w * v.line), budget, law)
        if best is None or not any(best[2]):
            reason = "no UAV can fly any search line within 0.85 T (eq. 18)"
            best = None

    def _penalty(rs) -> float:  # where the boxes are graded and sampled (as they are picked)
        if opt.airspace_penalty and sampled_boxes(grid, opt):
            return violation_penalty(sc, rs, v, opt)
        return 0.0

    def _sampled_total(rs) -> float:
        paths = [[takeoff[k], *rs[k], landing[k]] if rs[k] else [] for k in range(n)]
        return float(sum(sampled_sweep(sc, grid, full_prior, paths)[0]))

    nothing = opt.nothing * float(full_prior.sum())
    sent_home: dict[int, dict[int, tuple[float, float]]] = {}  # by id(routes): k -> (POS, h)

    def _hours(rs) -> float:
        """The plan's total eq. 17 flight time (every UAV's route, take-off to landing)."""
        return sum(
            _flight_time(rs[k], takeoff[k], landing[k], sc, v, heading0[k]) for k in range(n)
        )

    def _pick(cands: list[tuple], home: bool = False) -> tuple:
        """The candidate kept among ``cands`` (``(score, routes, pieces, ...)``, in order of
        preference; score the sampled POS less the penalty): the candidates whose score lies
        within ``options.nothing`` (:data:`NOTHING`) of the prior's mass of the best are tied,
        with ``home`` each has its UAVs that add too little for their hours kept home
        (:func:`_home`; F1, G3), and the one of least total flight time (:func:`_hours`) is
        kept, the first of them on equal times (F1: a tie on POS_C is broken by the flying,
        not by the order). Without a tie, or with ``options.nothing`` 0, the first of the
        highest score, as before (kept home too: only the tied are, so the candidates that
        lose cost no sweeps)."""
        top = max(c[0] for c in cands)
        tied = [c for c in cands if c[0] >= top - nothing]
        if opt.nothing == 0:
            return tied[0]
        if home:
            for i, c in enumerate(tied):
                r_, p_, s_ = _home(c[1], c[2], c[0] + _penalty(c[1]))
                if r_ is not c[1]:
                    tied[i] = (s_ - _penalty(r_), r_, p_, *c[3:])
        if len(tied) == 1:
            return tied[0]
        hours = [_hours(c[1]) for c in tied]
        return tied[int(np.argmin(hours))]

    def _home(trial, t_pieces, score: float | None):
        """A candidate plan (as :func:`_with_fill` returns it) with the UAVs that add too
        little for their flight hours kept home (F1: no aircraft sent for nothing; G3: nor
        for hours at next to nothing), pieces and POS updated; as it is with
        ``options.gain_per_hour`` or ``options.nothing`` 0.

        A UAV's floor is :data:`GAIN_PER_HOUR` of the prior's mass times its eq. 17 flight
        hours. Every flying UAV's marginal POS (what the plan finds less without it: the
        sampled eq. 14 total, :func:`sampled_sweep`) is computed (:func:`_leave_one_out`); the
        UAVs below their floor are tried longest flight first (the UAV's index on equal ones:
        the most aircraft hours saved first; least POS per hour first sent home the 0.28 h
        UAV of the one-sighting case and flew the 1.63 h one), and each kept home if the plan
        without it (and the ones already kept home) finds less than its floor below the plan
        with it. So each UAV kept home added less than its floor to the plan it left, the plan
        loses less than ``gain_per_hour`` times the flight hours it saves, and every UAV that
        flies adds at least its floor to the plan (a UAV's marginal only grows as others stay
        home). With a polish (``standard``, ``thorough``) it is applied to the polished plan,
        not to the candidates before it (a UAV sent home first lost its hours to the polish).
        Until the measurement of i24-gainhour only the UAVs whose credit swept first or last
        was below the floor were tried: on the 500 km scenario at 48 UAVs two others flew
        below it (3.72 h for 4.3e-5, 2.78 h for 2.0e-4). The UAVs kept home are
        recorded with what each added and its hours (``sent_home``, plan.json's
        ``optimizer.settings.home``)."""
        if opt.nothing == 0 or opt.gain_per_hour == 0:
            return trial, t_pieces, score
        rate = opt.gain_per_hour * float(full_prior.sum())  # POS per flight hour
        paths = [[takeoff[k], *trial[k], landing[k]] if trial[k] else [] for k in range(n)]
        hours = {k: _flight_time(trial[k], takeoff[k], landing[k], sc, v, heading0[k]) / 3600
                 for k in range(n) if trial[k]}  # fmt: skip
        now = float(sum(sampled_sweep(sc, grid, full_prior, paths)[0]))
        s_ = sc.sensor.samples_per_cell
        cut = sc.sensor.cutoff_sweep_widths * w
        base = np.ascontiguousarray(grid.refine(full_prior, s_))
        mass = float(base.sum())

        def sweep(belief: np.ndarray, j: int) -> None:  # path j swept (eq. 14)
            sweep_track(belief, grid, s_, np.asarray(paths[j], dtype=float), w, law, cut,
                        grid.cell_m)  # fmt: skip

        left_out = _leave_one_out(base.copy(), sweep, list(hours))
        tried = [k for k, h in hours.items() if now - (mass - left_out[k]) < rate * h]
        home: dict[int, tuple[float, float]] = {}  # k -> (what it added, its hours)
        if not tried:  # the common case: every UAV adds its floor
            return trial, t_pieces, score
        for j in range(n):  # the routes never tried swept once (eq. 14, as sampled_sweep)
            if paths[j] and j not in tried:
                sweep(base, j)
        for k in sorted(tried, key=lambda k: (-hours[k], k)):  # the longest flight first
            left = base.copy()  # the plan without k and the ones already home
            for j in tried:
                if j != k and j not in home:
                    sweep(left, j)
            without = mass - float(left.sum())
            if now - without < rate * hours[k]:
                home[k] = (now - without, hours[k])
                now = without
        if not home:
            return trial, t_pieces, score
        kept = [[] if k in home else trial[k] for k in range(n)]
        k_pieces = [[] if k in home else list(p_) for k, p_ in enumerate(t_pieces)]
        sent_home[id(kept)] = home
        return kept, k_pieces, None if score is None else _sampled_total(kept)

    def _flown(trial, t_pieces, score: float | None):
        """A candidate as the pick compares it: idle UAVs filled (:func:`_with_fill`), then
        UAVs that find nothing kept home (:func:`_home`)."""
        return _home(*_with_fill(trial, t_pieces, score))

    # the starts: (W x length per cell score, name, routes, line pieces)
    starts: list[tuple[float, str, list, list]] = []
    routes: list[list[list[float]]] = [[] for _ in range(n)]
    pieces: list[list[int]] = [[] for _ in range(n)]
    alloc_pos = 0.0
    along = "x"
    spacing = w
    if best is not None:
        alloc_pos = float(best[0].pos)
        a_routes, a_pieces = fly(best)
        along = "y" if best[5] else "x"
        spacing = w / max(float(np.minimum(best[0].coverage, COVER_CAP).max()), 1e-12)
        starts.append((best_val, "allocation", a_routes, a_pieces))
    if best is not None and greedy_start:
        from poc_env.agents.planning.greedy_rectangles import make_greedy_rectangles_plan

        gp = make_greedy_rectangles_plan(sc, prior=full_prior, speed=speed,
                                         zone_reach=opt.zone_reach)  # fmt: skip
        g_routes = [list(u_["waypoints_m"]) for u_ in gp["uavs"]]
        if router.active:  # its UAVs in lanes too (i24-deconflict: it routes each alone)
            g_routes = _around_all(g_routes)
        g_val = _cell_pos(g_routes, takeoff, landing, prior, grid, w, law)
        starts.append((g_val, "greedy_rectangles", g_routes, _lines_of(g_routes)))
    if best is not None and box_start:
        b_routes = box_routes(
            prior,
            grid,
            w,
            law,
            v,
            takeoff,
            landing,
            u.usable_endurance_s,
            u.max_turn_rate_rad_s,
            _reserve(sc),
            heading0,
            sampled=(
                grid.refine(prior, sc.sensor.samples_per_cell),
                sc.sensor.samples_per_cell,
                sc.sensor.cutoff_sweep_widths * w,
            ),
            options=opt,
        )
        b_routes = _lawnmower_start(b_routes)
        b_val = _cell_pos(b_routes, takeoff, landing, prior, grid, w, law)
        starts.append((b_val, "boxes", b_routes, _lines_of(b_routes)))
    if best is not None and opt.relax_start:  # i24-relax: each UAV a patch of the relaxation
        r_best: tuple[float, list] | None = None
        for cand in opt.relax_etas:
            r_routes = relax_routes(
                prior,
                grid,
                w,
                law,
                v,
                takeoff,
                landing,
                tau,
                cand,
                u.usable_endurance_s,
                u.max_turn_rate_rad_s,
                _reserve(sc),
                heading0,
                tuple(ks),
                opt.relax_scales,
                opt,
            )
            r_routes = _lawnmower_start(r_routes)
            r_val = _cell_pos(r_routes, takeoff, landing, prior, grid, w, law)
            if r_best is None or r_val > r_best[0]:
                r_best = (r_val, r_routes)
        if r_best is not None:
            starts.append((r_best[0], "relax", r_best[1], _lines_of(r_best[1])))

    def _with_fill(trial, t_pieces, score: float | None):
        """A candidate plan (routes, pieces, its sampled POS or None) with its idle UAVs filled
        (:func:`_fill`, ``options.fill_idle``; i24-fleet), pieces and POS updated; as it was
        when no UAV is idle or nothing is gained. Applied to every candidate the pick compares
        (each start, refined or not), not to the starts before their ranking: the same starts
        are ranked and refined as without it, and each candidate only gains, so the plan never
        plans less than without the fill."""
        if not opt.fill_idle:
            return trial, t_pieces, score
        filled = _fill(trial)
        if filled is trial:
            return trial, t_pieces, score
        f_pieces = [list(p_) if len(trial[k]) else list(range(len(filled[k]) // 2))
                    for k, p_ in enumerate(t_pieces)]  # fmt: skip
        return filled, f_pieces, None if score is None else _sampled_total(filled)

    # the best starts by W x length per cell (stable: allocation, greedy, boxes on ties)
    starts.sort(key=lambda t: -t[0])
    start = starts[0][1] if starts else "allocation"
    refined = bool(refine)
    home_why: dict[int, tuple[float, float]] = {}  # the kept plan's UAVs sent home (_home)
    big = not opt.polish_here(grid.nx, grid.ny)  # above polish_max_cells a side
    polishing = bool(opt.polish or opt.polish_lines or opt.polish_boxes or opt.regrade)
    # the polish runs (not skipped below): the floor per flight hour is then applied to the
    # polished plan, not before it (sent home first, a UAV's hours are lost to the polish:
    # the 500 km scenario's 24-UAV ``standard`` plan 0.9329 against 0.9564 without the floor)
    will_polish = (
        polishing
        and not (router.active and not opt.polish_zones)
        and not (big and not opt.polish_big_work)
    )

    if starts:
        routes, pieces = starts[0][2], starts[0][3]
        if starts[0][1] != "allocation":  # lawnmower lines, a line = two waypoints
            spacing = w
        if not refine:  # the start kept as it is, its idle UAVs filled
            routes, pieces, _ = (_with_fill if will_polish else _flown)(routes, pieces, None)
            home_why = sent_home.get(id(routes), {})
    ranked: list[tuple[float, list, list, str, bool]] = []  # every start scored, for the polish
    if starts and refine:
        sampled_of = {t[1]: _sampled_total(t[2]) for t in starts}
        top = starts[: max(1, refine_starts)]
        top_s = max(sampled_of[t[1]] for t in top)
        by_model = opt.refine_sampled and box_start and sampled_boxes(grid, opt)
        tried = [
            t
            for i, t in enumerate(top)
            if t[0] >= opt.refine_within * starts[0][0]
            and (i == 0 or not by_model or sampled_of[t[1]] >= opt.refine_within * top_s)
        ]
        for _, name, s_routes, s_pieces in tried:
            r_routes, _ = refine_routes(
                s_routes,
                takeoff,
                landing,
                prior,
                grid,
                w,
                law,
                v,
                u.usable_endurance_s,
                u.max_turn_rate_rad_s,
                _reserve(sc),
                sweeps=refine,
                headings=takeoff_heading(grid.bounds, takeoff),
                airspace=Airspace(
                    sc.episode.dt_s,
                    opt.separation_margin * sc.constraints.safety_distance_m,
                    opt.range_margin * sc.comms.range_m,
                    sc.comms.min_neighbours,
                ),
            )
            if router.active:  # the refined routes made flyable: they keep c (issue 24)
                r_routes = _around_all(r_routes)
            # the refinement scores W x length per cell; kept only if the environment's model
            # agrees (on cells wider than W it can lose: large_400 at 10 km, 0.463 -> 0.416)
            for was_refined in (True, False):
                trial: list[list[list[float]]] = r_routes if was_refined else s_routes
                score = _sampled_total(trial) if was_refined else sampled_of[name]
                trial, t_pieces, score = _with_fill(trial, s_pieces, score)
                score -= _penalty(trial)
                ranked.append((score, trial, t_pieces, name, was_refined))
        # the starts not refined are kept as they are if the environment's model scores them
        # higher (W x length per cell ranks the starts, and misjudges cells wider than W)
        for _, name, s_routes, s_pieces in starts:
            if any(name == t[1] for t in tried):
                continue
            f_routes, f_pieces, score = _with_fill(s_routes, s_pieces, sampled_of[name])
            score -= _penalty(f_routes)
            ranked.append((score, f_routes, f_pieces, name, False))
        # the best by the environment's model; on a tie, the least flying (F1)
        _, routes, pieces, start, refined = _pick(ranked, home=not will_polish)
        home_why = sent_home.get(id(routes), {})

    def _polish(rs):
        """The polish stages in turn -- the polish, the second polish with the block moves too
        (i24-lines), the third with the box moves only (i24-boxes; boxes and groups moved as
        one), and the regrade (i24-regrade: runs of lines re-spaced jointly) first, between the
        polishes or last (``regrade_at``) -- each from the routes the one before left; passes
        and moves summed, each later stage's own kept moves as ``regrade_moves``,
        ``lines_moves`` and ``box_moves``."""
        moves = KINDS if opt.polish_grade else MOVES
        out: tuple = (rs, 0.0, {})
        # i24-bigpolish: above the cell limit the polish stages share a work budget (candidate
        # steps scored) and the second polish has its own passes
        left = opt.polish_big_work if big else None
        lines = opt.polish_big_lines or opt.polish_lines if big else opt.polish_lines
        later = (
            ("regrade", opt.regrade if opt.regrade_at == "first" else 0, (), (), None),
            ("polish", opt.polish, moves, opt.polish_radii, None),
            ("regrade", opt.regrade if opt.regrade_at == "between" else 0, (), (), None),
            ("lines", lines, (*moves, "block"), opt.polish_lines_radii, None),
            ("box", opt.polish_boxes, BOX_KINDS, opt.polish_lines_radii, opt.polish_boxes_radii),
            ("regrade", opt.regrade if opt.regrade_at == "end" else 0, (), (), None),
        )
        for stage, passes, kinds, radii, box_radii in later:
            if not passes or (left is not None and left <= 0 and stage != "regrade"):
                continue
            if stage == "regrade":  # i24-regrade: runs of lines re-spaced jointly; with zones
                pr, val, stats = polish_for(  # its runs kept out of them (i24-smallfix)
                    sc, out[0], full_prior, passes, speeds=v,
                    separation_margin=opt.separation_margin, range_margin=opt.range_margin,
                    routine=regrade_routes, **({"router": router} if router.active else {}),
                )  # fmt: skip
            else:
                pr, val, stats = _polish_stage(out[0], passes, kinds, radii, box_radii, left)
                if left is not None:  # the budget's rest for the next stage
                    left -= stats["work"]
            st0 = out[2]
            # i24-bigpolish: the budget's steps scored and whether it stopped a stage
            spent = {}
            if "work" in stats:
                spent = {"work": st0.get("work", 0) + stats["work"],
                         "spent": bool(st0.get("spent")) or stats["spent"]}  # fmt: skip
            out = (
                pr,
                val,
                {
                    **st0,
                    **stats,
                    "passes": st0.get("passes", 0) + stats["passes"],
                    "moves": st0.get("moves", 0) + stats["moves"],
                    **({} if stage == "polish" else {f"{stage}_moves": stats["moves"]}),
                    **spent,
                },
            )
        return out

    def _polish_stage(rs, passes, moves, radii, box_radii=None, work=None):
        return polish_for(
            sc,
            rs,
            full_prior,
            passes,
            speeds=v,
            separation_margin=opt.separation_margin,
            range_margin=opt.range_margin,
            radii=radii,
            moves=moves,
            block_windows=opt.polish_lines_windows,  # i24-cheapolish (block moves only)
            block_radii=opt.polish_lines_block_radii or None,
            **({} if box_radii is None else {"box_radii": box_radii}),
            # i24-zonepolish: with zones, no candidate enters one (eq. 20; polish.zone_guard)
            **({"router": router} if router.active and opt.polish_zones else {}),
            **({} if work is None else {"work": max(0, work)}),  # i24-bigpolish
            # i24-fast2s: candidates screened at a shorter cut-off, the best scored exactly
            **(
                {"screen": opt.polish_screen, "screen_cutoff": opt.polish_screen_cutoff}
                if opt.polish_screen
                else {}
            ),
        )

    polished: dict[str, Any] | None = None
    if polishing and router.active and not opt.polish_zones:  # eq. 20: zones not seen
        polished = {"passes": 0, "moves": 0, "skipped": "no-fly zones"}
    elif polishing and big and not opt.polish_big_work:  # the size rule (i24-fastpolish)
        polished = {"passes": 0, "moves": 0, "skipped": "map larger than polish_max_cells"}
    elif polishing and any(routes):
        # the chosen plan polished, and with ``polish_starts`` the next best of the starts
        # (refined or not) too: the best polished one kept (by POS less the penalty)
        pool = [(routes, pieces, start, refined)]
        for _, r_, p_, name, was_refined in sorted(ranked, key=lambda t: -t[0]):
            if len(pool) >= opt.polish_starts:
                break
            if any(r_ is q[0] for q in pool) or not any(r_):
                continue
            pool.append((r_, p_, name, was_refined))
        polished_pool = []
        for r_, p_, name, was_refined in pool:
            pr, val, stats = _polish(r_)
            score = val - (_penalty(pr) if len(pool) > 1 else 0.0)
            polished_pool.append((score, pr, p_, name, was_refined, stats))
        _, routes, pieces, start, refined, polished = _pick(polished_pool)
        if len(pool) > 1:
            polished = {**polished, "plans": len(pool)}
        routes, pieces, _ = _home(routes, pieces, None)  # the floor on the polished routes
        home_why = sent_home.get(id(routes), {})
    own_rec: dict[str, Any] | None = None
    if opt.own_apart and opt.fill_apart and n > 1 and any(routes):
        # i24-ownclear: the plan's own routes through the fill's clearance where it costs less
        # than the violations it removes (the reward's exchange rate, violation_penalty)
        # every route in conflict dropped (its box flown from the other end tried first on
        # maps without zones) and its UAV filled: the fill's own rule (_fill, i24-stagger),
        # the cleared plan kept if POS less the penalty does not fall (ties: the clear plan)
        cleared, where = apart(sc, routes, v, range(n), _alternative, FILL_WITHIN)
        if cleared != routes:
            if where and opt.fill_idle:
                cleared = _fill(cleared)
            cleared, _, _ = _home(cleared, _lines_of(cleared), None)
            o_pen = violation_penalty(sc, routes, v, opt)
            c_pen = violation_penalty(sc, cleared, v, opt)
            o_val, c_val = _sampled_total(routes), _sampled_total(cleared)
            # no aircraft grounded to clear the air: as many UAVs fly as in the own plan (but
            # in the half fleet's plan, whose idle UAVs the larger fleet's fill refills)
            flying = _half or sum(map(bool, cleared)) >= sum(map(bool, routes))
            took = flying and c_val - c_pen >= o_val - o_pen
            own_rec = {"kept": "cleared" if took else "own", "dropped": len(where),
                       "flying": [sum(map(bool, routes)), sum(map(bool, cleared))],
                       "pos": [o_val, c_val], "penalty": [o_pen, c_pen]}  # fmt: skip
            if took:
                routes, pieces, refined = cleared, _lines_of(cleared), True
                home_why = sent_home.get(id(routes), {})
    fleet_rec: dict[str, Any] | None = None
    half = (floor is None and opt.half_fleet and opt.fill_idle and n > 1 and any(routes)
            and not all(routes))  # fmt: skip
    floors: list[tuple[dict[str, Any], list[list[list[float]]]]] = []  # (plan, its routes here)
    if half:  # i24-chain: a fleet larger than its plan uses also tries half of it as a floor,
        # and (i24-monotone, from ``three_quarter_from`` UAVs) three quarters of it, in the
        # plan asked for only: 32 UAVs are compared with 24's plan, not only with 16's
        sizes = [n // 2]
        if 0 < opt.three_quarter_from <= n and not _half and 3 * n // 4 > n // 2:
            sizes.append(3 * n // 4)
        for m in sizes:
            f_plan = make_allocation_plan(
                sc.with_uavs(m), prior=full_prior, map_source=map_source, seed=seed,
                speed=speed, crs=crs, options=opt, _half=True,
            )  # fmt: skip
            floors.append((f_plan, _mapped(sc, f_plan, check=False)))
    elif floor is not None and mapped is not None:
        floors.append((floor, mapped))
    if floors:  # i24-fleet: never below fewer UAVs' plan
        # the floor's own UAVs met their floor in its plan, but the UAVs the fill adds to it
        # go through the rule here (G3: every flying UAV adds its floor); the two plans fly
        # different fleets, so their flight hours are priced at the floor's rate (an hour
        # worth ``gain_per_hour`` of the mass: one UAV flying 0.8 h more for 0.001 of a
        # sighting is not kept over the plan that sent that sighting's UAV home) and compared
        # as the starts are (_pick: within ``nothing`` the one of fewer flight hours, F1), the
        # fleet's own plan first, then the floors in turn (half, three quarters)
        per_s = opt.gain_per_hour * float(full_prior.sum()) / 3600 if opt.nothing else 0.0
        own = (_sampled_total(routes) - _penalty(routes) - per_s * _hours(routes)
               if any(routes) else 0.0)  # fmt: skip
        cands: list[tuple] = [(own, routes, pieces)]
        whys, dropped = [], []
        for _, f_mapped in floors:
            cut: dict[int, np.ndarray] = {}
            if opt.fill_apart:  # i24-chain: the floor's routes held to the fill's own clearance
                f_mapped, cut = apart(sc, f_mapped, v, range(n), _alternative, FILL_WITHIN)
            dropped.append(len(cut))
            f_routes = _fill(f_mapped)
            f_routes, f_pieces, _ = _home(f_routes, _lines_of(f_routes), None)
            whys.append(sent_home.get(id(f_routes), {}))
            f_val = _sampled_total(f_routes) - _penalty(f_routes) - per_s * _hours(f_routes)
            cands.append((f_val, f_routes, f_pieces))
        got = _pick(cands)[1]
        i_kept = next((i for i, c in enumerate(cands[1:]) if c[1] is got), None)
        fleet_rec = {"floor_uavs": len(floors[0][0]["uavs"]),
                     "floor_posc": float(floors[0][0]["posc"]),
                     "kept": "own" if i_kept is None else "floor",
                     **({"floor": "half_fleet"} if half else {}),
                     # i24-monotone: the pick's criterion (planned POS less the penalty and
                     # the hours at the floor's rate) and the UAVs flying of the own plan and
                     # of each floor lifted; the floor routes the clearance dropped
                     "value": [float(c[0]) for c in cands],
                     "flying": [sum(map(bool, c[1])) for c in cands],
                     "dropped": dropped}  # fmt: skip
        if len(floors) > 1:  # i24-monotone: the floors tried, half and three quarters
            fleet_rec["floors"] = [
                {"uavs": len(f_plan["uavs"]), "posc": float(f_plan["posc"])} for f_plan, _ in floors
            ]
        if i_kept is not None:
            fleet_rec["kept_uavs"] = len(floors[i_kept][0]["uavs"])
            routes, pieces, refined = cands[1 + i_kept][1], cands[1 + i_kept][2], True
            start = str(floors[i_kept][0].get("start", "allocation"))
            home_why = whys[i_kept]
    moved = polished is not None and polished["moves"] > 0  # lines no longer in pairs
    # the planned POS by the environment's own detection model (sampled_sweep), not by W x
    # length per cell: eq. 10 per cell piles a line's effort into the cells it crosses (too
    # little where cells are narrower than W, too much where they are wider)
    flown_pos, flown_found = sampled_sweep(
        sc,
        grid,
        full_prior,
        [[takeoff[k], *routes[k], landing[k]] if routes[k] else [] for k in range(n)],
    )
    posc = float(sum(flown_pos))
    home_rec = [  # the UAVs the rule kept home (G3): what each would add, in its hours
        {"id": k + 1, "pos": float(m_), "hours": float(h_)}
        for k, (m_, h_) in sorted(home_why.items())
        if not routes[k]
    ]
    x0, y0, x1, y1 = grid.bounds
    heading_k = takeoff_heading(grid.bounds, takeoff)
    uav_out = []
    for k in range(n):
        wps = routes[k]
        arr = np.asarray(wps, dtype=float).reshape(-1, 2)
        inside = (arr[:, 0] >= x0) & (arr[:, 0] <= x1) & (arr[:, 1] >= y0) & (arr[:, 1] <= y1)
        if refine or moved:  # transit: the waypoints before the route first enters the map
            lead = int(np.argmax(inside)) if inside.any() else len(arr)
        else:  # the dog-leg before the lines
            lead = len(arr) - 2 * len(pieces[k])
        legs: np.ndarray = np.zeros((0, 2, 2))
        if (refine or moved) and len(arr) > lead + 1:  # every leg is flown as search
            legs = np.stack([arr[lead:-1], arr[lead + 1 :]], axis=1)
        elif not (refine or moved):  # the lines
            legs = arr[lead:].reshape(-1, 2, 2)
        path = np.vstack([takeoff[k], arr, landing[k]])
        t_k = _flight_time(wps, takeoff[k], landing[k], sc, v, heading_k[k])
        uav_out.append(
            {
                "id": k + 1,
                "rectangle": None,
                "areas_m": _swept_areas(np.asarray(legs), spacing) if len(legs) else [],
                "spacing_m": spacing if wps else 0.0,
                "takeoff_m": [float(c) for c in takeoff[k]],
                "landing_m": [float(c) for c in landing[k]],
                "waypoints_m": wps,
                "transit_waypoints": lead if wps else 0,
                "track_length_m": polyline_length(path) if wps else 0.0,
                "flight_time_s": t_k,
                **found_scores(full_prior, float(flown_pos[k]), flown_found[k]),
                "feasible": bool(t_k <= u.usable_endurance_s),
            }
        )
    runtime = time.perf_counter() - t0
    geo = plan_geography(sc, full_prior, crs)
    rb = geo.get("bounds", {}).get("reach", 0.0) if reason is None or prior.sum() > 0 else 0.0
    geo["flight"] = {  # the speeds this plan is flown at (plan_speeds)
        **geo["flight"],
        "cruise_speed_mps": v.home,
        "search_speed_mps": v.line,
        "transit_speed_mps": v.out,
    }
    return {
        **geo,
        "schema": SCHEMA,
        "scenario": sc.name,
        "seed": int(seed),
        "map_source": map_source,
        "planner": "allocation",
        "route": True,
        "lines_along": along,
        "speed_rule": speed,
        "speeds_mps": v.as_dict(),
        "optimizer": {
            "name": "allocation",
            "settings": {
                "levels": chosen,
                "tried": ks,
                "margin": margin,
                "speed": speed,
                "refine": refine,
                **({"options": opt.changed()} if opt.changed() else {}),
                **({"polish": polished} if polished is not None else {}),
                **({"fleet": fleet_rec} if fleet_rec is not None else {}),
                **({"own_apart": own_rec} if own_rec is not None else {}),
                **({"home": home_rec} if home_rec else {}),
            },
        },
        "runtime_s": runtime,
        "posc": posc,
        "upper_bound": float(fleet.upper) if fleet is not None else 0.0,
        "bound_reach": float(rb),
        "allocation_pos": alloc_pos,
        "eta": float(eta),
        "start": start,
        "refined": refined,
        "reason": reason,
        "objective": -posc,
        "history": [],
        "x": [],
        "uavs": uav_out,
    }
