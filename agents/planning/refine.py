"""Route refinement: local search on the waypoints of a route plan, scored as the environment
scores a flight.

:func:`refine_routes` takes each UAV's waypoints (between its take-off and landing fields) and
improves the planned POS of the whole swarm by hill climbing on single waypoints. The score is
the planned POS of :mod:`poc_env.agents.planning.allocation`: every leg of every UAV's flight path,
transit included, adds coverage ``W x (length inside the cell) / area`` to the cells it crosses
(eq. 10 per cell) and the swarm finds ``sum_j p_j POD(C_j)`` (eq. 14-16 with the detection
law's POD). Moves, for waypoint ``i`` of UAV ``k`` in turn:

* **move** it by one of :data:`RADII` (in cells) in one of 8 directions;
* **delete** it;
* **insert** a waypoint before it (and before the landing field, to extend a route), at the
  leg's midpoint moved across the leg by one of ``0, +-RADII`` cells.

A move is kept when it raises the swarm's planned POS by more than :data:`TOL` and keeps the
UAV's eq. 17 time (out at ``v.out``, on the route at ``v.line``, home at ``v.home``, plus a
turn of ``|angle| / omega_max`` at every waypoint, the allocation planner's half-turn rule
generalised) within ``budget``; the best move of each waypoint is taken. Moved and inserted
waypoints stay inside the map. The search stops after ``sweeps`` passes over all waypoints or
after a pass without a kept move, so a refinement is deterministic (no clock, no random draw).

Coverage is sampled at four points per cell along each leg (as the allocation planner's
``_path_coverage``), so the score equals the allocation planner's ``posc`` of the same routes.
A move changes the coverage of the cells its old and new legs cross only, so the candidates are
scored there (:func:`move_gains`: the swarm's coverage per cell is kept and updated in place
when a move is kept), and the airspace check counts the moved UAV's pairs with the others
only (:class:`AirspaceCount`); both give the full computation's numbers.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from poc_env.agents.planning import _kernels
from poc_env.sim.comms import in_range, two_neighbour_ok
from poc_env.sim.constraints import pairwise_distances, separation_violations
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import pod_from_coverage

#: candidates (best planned POS first) checked against the airspace per waypoint.
TRIES = 6
#: move radii in cells.
RADII = (0.5, 1.0, 2.0, 4.0)
#: least gain in planned POS for a move to be kept.
TOL = 1e-9
#: share of ``|heading change| / omega_max`` a waypoint costs (:func:`arrival_times`): the
#: follower cuts corners (a waypoint counts as reached half a step away), so a full turn at the
#: maximum rate overstates the time; 0.5 matched the follower's arrival times to 1-2 min on
#: paper_6_2 (docs/PLANNER.md).
TURN_SHARE = 0.5
_DIRS = np.array(
    [[np.cos(a), np.sin(a)] for a in np.arange(8) * np.pi / 4], dtype=float
)  # unit steps of the move


def leg_samples(starts, ends, grid: Grid, w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coverage samples of :func:`leg_coverage`: per sample inside the map, the leg it lies
    on (index into ``starts``), its flat cell index and its coverage (eq. 10 per cell), in the
    order :func:`leg_coverage` sums them (a leg's samples from its start). One compiled pass
    (:func:`poc_env.agents.planning._kernels.leg_samples`; the legs' lengths by numpy)."""
    starts = np.asarray(starts, dtype=float).reshape(-1, 2)
    ends = np.asarray(ends, dtype=float).reshape(-1, 2)
    if not len(starts):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0)
    d = ends - starts
    ox, oy = grid.origin_m
    return _kernels.leg_samples(
        np.ascontiguousarray(starts[:, 0]),
        np.ascontiguousarray(starts[:, 1]),
        np.ascontiguousarray(d[:, 0]),
        np.ascontiguousarray(d[:, 1]),
        np.hypot(d[:, 0], d[:, 1]),
        float(ox),
        float(oy),
        float(grid.cell_m),
        grid.nx,
        grid.ny,
        float(w),
        float(grid.cell_area_m2),
    )


def leg_coverage(starts, ends, grid: Grid, w: float, rows: np.ndarray | None = None) -> np.ndarray:
    """Coverage (eq. 10 per cell) of legs ``starts -> ends`` (L, 2), sampled at a quarter cell,
    summed per row of ``rows`` (L,) (default: all in one row): an array (rows, ny * nx).
    Nothing outside the map counts."""
    n_legs = len(np.asarray(starts, dtype=float).reshape(-1, 2))
    rows = np.zeros(n_legs, dtype=np.int64) if rows is None else np.asarray(rows)
    n_rows = int(rows.max()) + 1 if rows.size else 1
    ncell = grid.ny * grid.nx
    if not n_legs:
        return np.zeros((n_rows, ncell))
    leg, cell, weight = leg_samples(starts, ends, grid, w)
    out = np.bincount(rows[leg] * ncell + cell, weights=weight, minlength=n_rows * ncell)
    return out.reshape(n_rows, ncell)


def _dedupe(path) -> np.ndarray:
    """``path`` without points within 1 mm of the point before (no zero-length legs)."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(p) < 2:
        return p
    keep = np.ones(len(p), dtype=bool)
    keep[1:] = np.hypot(*np.diff(p, axis=0).T) > 1e-3
    keep[-1] = True
    return p[keep]


def arrival_times(path, speeds, turn_rate: float, heading0: float | None = None) -> np.ndarray:
    """Time (s) at which a flight reaches each point of ``path`` (take-off, waypoints, landing):
    the first leg at ``speeds.out``, the last at ``speeds.home``, the rest at ``speeds.line``,
    and ``TURN_SHARE x |heading change| / turn_rate`` at every waypoint, and at take-off when
    the UAV starts with heading ``heading0`` (rad) (eq. 17 with the turns of the eq. 19
    turn-rate limit). A point repeating the one before adds nothing."""
    p = np.ascontiguousarray(np.asarray(path, dtype=float).reshape(-1, 2))
    out = np.zeros(len(p))
    h0 = np.nan if heading0 is None else float(heading0)
    if len(p) > 1:
        cost = TURN_SHARE / turn_rate
        dep = np.empty(len(p))
        _kernels.route_timeline(
            p, speeds.out, speeds.line, speeds.home, cost, np.inf, 0.0, h0, out, dep
        )
    return out


def route_time(path, speeds, turn_rate: float, heading0: float | None = None) -> float:
    """Eq. 17 time of a full path: :func:`arrival_times` at the landing field."""
    return float(arrival_times(path, speeds, turn_rate, heading0)[-1])


def route_fits(
    path, speeds, turn_rate: float, budget: float, reserve: float, heading0: float | None = None
) -> bool:
    """Whether a path is flown whole under eq. 18: it lands within ``budget`` and at no
    waypoint is the return rule due, i.e. ``t_i + |p_i - landing| / speeds.home + reserve <=
    budget`` (the follower and the environment's autopilot turn home when the usable endurance
    left only covers the direct flight home at ``v_c`` plus ``reserve``). Along a straight leg
    ``t + distance home / v`` is convex, so the waypoints are where it peaks."""
    p = np.ascontiguousarray(np.asarray(path, dtype=float).reshape(-1, 2))
    if len(p) < 2:
        return True
    out = np.empty(len(p))
    dep = np.empty(len(p))
    h0 = np.nan if heading0 is None else float(heading0)
    cost = TURN_SHARE / turn_rate
    return bool(
        _kernels.route_timeline(
            p, speeds.out, speeds.line, speeds.home, cost, budget, reserve, h0, out, dep
        )
    )


def track(path, speeds, turn_rate: float, times, heading0: float | None = None):
    """Where a flight of ``path`` is at ``times`` (:func:`arrival_times`'s timing): positions
    (S, 2) and whether it is still flying (S,)."""
    p = np.ascontiguousarray(_dedupe(path))
    arrive = np.zeros(len(p))
    dep = np.full(len(p), np.inf)
    h0 = np.nan if heading0 is None else float(heading0)
    if len(p) > 1:
        cost = TURN_SHARE / turn_rate
        _kernels.route_timeline(
            p, speeds.out, speeds.line, speeds.home, cost, np.inf, 0.0, h0, arrive, dep
        )
    t = np.ascontiguousarray(times, dtype=float)
    pos = np.empty((len(t), 2))
    act = np.empty(len(t), dtype=bool)
    _kernels.route_sample(p, arrive, dep, t, pos, act)
    return pos, act


def swarm_violations(
    pos, act, separation_m: float, range_m: float, min_neighbours: int, dist=None
) -> int:
    """UAV-steps in violation at sampled positions ``pos (S, n, 2)`` of the flying UAVs ``act
    (S, n)``: closer than ``separation_m`` to another (eq. 21) or with fewer than
    ``min_neighbours`` others within ``range_m`` (eq. 24, §3.2.4) -- the environment's own
    checks (:func:`poc_env.sim.constraints.separation_violations`,
    :func:`poc_env.sim.comms.two_neighbour_ok`). ``dist``: their
    :func:`~poc_env.sim.constraints.pairwise_distances`, when already known."""
    dist = pairwise_distances(pos) if dist is None else dist
    close, _ = separation_violations(pos, separation_m, act, dist)
    ok = two_neighbour_ok(in_range(pos, range_m, act, dist), min_neighbours, act)
    return int(close.sum() + (~ok & act).sum())


@dataclass(frozen=True)
class Airspace:
    """The environment's separation and communication rules, checked every ``dt_s`` at the
    planned positions (:func:`swarm_violations`); ``separation_m`` and ``range_m`` may carry
    margins for the follower's timing."""

    dt_s: float
    separation_m: float
    range_m: float
    min_neighbours: int

    def violations(self, pos, act, dist=None) -> int:
        return swarm_violations(
            pos, act, self.separation_m, self.range_m, self.min_neighbours, dist
        )


class AirspaceCount:
    """:meth:`Airspace.violations` of a swarm kept up to date as one UAV at a time moves.

    Per sampled step ``s`` and UAV ``i`` it keeps the number of flying others closer than
    ``separation_m`` (eq. 21) and within ``range_m`` (eq. 24) and the number of UAVs flying;
    moving UAV ``k`` (:meth:`move`) changes the pairs ``(k, j)`` only, so the counts are
    updated from UAV ``k``'s distances to the others (O(steps x n) instead of the full pass's
    O(steps x n^2); one compiled pass, :func:`poc_env.agents.planning._kernels.airspace_move`,
    with UAV ``k``'s current pairs kept until a move is kept). The count is
    :func:`swarm_violations`'s exactly: a flying UAV-step with a partner too close, plus one
    with fewer than ``min(min_neighbours, flying - 1)`` others in range
    (:func:`poc_env.sim.comms.two_neighbour_ok` with the flying UAVs)."""

    def __init__(self, airspace: Airspace, pos: np.ndarray, act: np.ndarray) -> None:
        self.air = airspace
        self.pos = np.array(pos, dtype=float)  # (S, n, 2)
        self.act = np.array(act, dtype=bool)  # (S, n)
        n = self.pos.shape[1]
        d = pairwise_distances(self.pos)
        both = self.act[:, :, None] & self.act[:, None, :] & ~np.eye(n, dtype=bool)[None]
        self.close = np.sum(both & (d < airspace.separation_m), axis=2)
        self.near = np.sum(both & (d <= airspace.range_m), axis=2)
        self.flying = self.act.sum(axis=1)
        self.value = self._total(self.close, self.near, self.flying, self.act)
        # UAV k's pairs at its current positions (:meth:`_pairs`), kept until a move is kept:
        # the refinement tries several moves of one UAV against the same others
        self._current: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _total(self, close, near, flying, act) -> int:
        need = np.minimum(self.air.min_neighbours, flying - 1)[:, None]
        return int(np.sum(act & (close > 0)) + np.sum(act & (near < need)))

    def _pairs(self, k: int, pos_k: np.ndarray, act_k: np.ndarray):
        """UAV ``k``'s pairs with the others at positions ``pos_k (S, 2)``, flying ``act_k``:
        (too close, in range), each (S, n) with column ``k`` False."""
        c = self.pos - pos_k[:, None, :]
        d = np.sqrt(c[..., 0] * c[..., 0] + c[..., 1] * c[..., 1])
        both = act_k[:, None] & self.act
        both[:, k] = False
        return both & (d < self.air.separation_m), both & (d <= self.air.range_m)

    def move(self, k: int, pos_k, act_k) -> tuple[int, tuple]:
        """The count with UAV ``k`` at ``pos_k (S, 2)``, flying ``act_k (S,)``, and the state
        that :meth:`keep` makes current (the counts are not changed until then)."""
        pos_k = np.asarray(pos_k, dtype=float)
        act_k = np.asarray(act_k, dtype=bool)
        if k not in self._current:
            self._current[k] = self._pairs(k, self.pos[:, k], self.act[:, k])
        old_c, old_n = self._current[k]
        close = np.empty_like(self.close)
        near = np.empty_like(self.near)
        flying = np.empty_like(self.flying)
        value = int(
            _kernels.airspace_move(
                self.pos, self.act, self.close, self.near, self.flying, k,
                np.ascontiguousarray(pos_k), np.ascontiguousarray(act_k), old_c, old_n,
                float(self.air.separation_m), float(self.air.range_m),
                int(self.air.min_neighbours), close, near, flying,
            )
        )  # fmt: skip
        act = self.act.copy()
        act[:, k] = act_k
        return value, (k, pos_k, act, close, near, flying, value)

    def keep(self, state: tuple) -> None:
        """Make the move of :meth:`move`'s ``state`` current."""
        k, pos_k, act, close, near, flying, value = state
        self.pos[:, k] = pos_k
        self.act, self.close, self.near, self.flying, self.value = act, close, near, flying, value
        self._current.clear()  # every UAV's pairs with k changed


def candidate_edits(path: np.ndarray, i: int, offsets: np.ndarray, across: np.ndarray, lo, hi):
    """The refinement's candidate edits of waypoint ``i`` of ``path`` (take-off, waypoints,
    landing; module docstring) and the legs they fly, in :func:`move_gains`' form: ``qs``
    (C, 2) the new points; ``ops`` (C,) 0 move waypoint ``i`` to ``qs[c]`` (one per
    ``offsets`` row, then) 1 delete it (when it is not the landing), 2 insert ``qs[c]``
    before it (one per ``across``: the leg's midpoint moved across the leg); ``starts``,
    ``ends`` the new legs (a moved or inserted point's two legs, a deletion's one), ``rows``
    their candidate and ``kinds`` per candidate 0 (legs ``i-1, i`` and ``i, i+1`` replaced)
    or 1 (leg ``i-1, i``). Points are clipped to ``lo``-``hi``. One pass of numpy over all
    candidates, elementwise the same operations as candidate by candidate (the same points,
    bit for bit: tests/planning/test_speed.py)."""
    a = path[i - 1]
    b = path[i]
    d = b - a
    length = float(np.hypot(*d))
    normal = np.array([-d[1], d[0]]) / length if length > 0 else np.zeros(2)
    ins = np.clip(0.5 * (a + b) + across[:, None] * normal[None, :], lo, hi)  # (I, 2)
    n_i = len(ins)
    movable = i < len(path) - 1  # the landing is not moved or deleted
    n_m = len(offsets) if movable else 0
    o = 2 * n_m + 1 if movable else 0  # the inserts' first leg
    starts = np.empty((o + 2 * n_i, 2))
    ends = np.empty((o + 2 * n_i, 2))
    if movable:
        nxt = path[i + 1]
        mv = np.clip(b + offsets, lo, hi)  # (M, 2)
        starts[0 : 2 * n_m : 2] = a
        starts[1 : 2 * n_m : 2] = mv
        ends[0 : 2 * n_m : 2] = mv
        ends[1 : 2 * n_m : 2] = nxt
        starts[2 * n_m] = a
        ends[2 * n_m] = nxt
        qs = np.concatenate([mv, b[None], ins])
    else:
        qs = ins
    starts[o::2] = a
    starts[o + 1 :: 2] = ins
    ends[o::2] = ins
    ends[o + 1 :: 2] = b
    ops, rows, kinds = _edit_layout(n_m, n_i, movable)
    return qs, ops, starts, ends, rows, kinds


@functools.lru_cache(maxsize=16)
def _edit_layout(n_m: int, n_i: int, movable: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``ops``, ``rows`` and ``kinds`` of :func:`candidate_edits` (read-only): they depend on
    the numbers of moves and inserts only."""
    if movable:
        ops = np.concatenate([np.zeros(n_m, dtype=np.int64), [1], np.full(n_i, 2)])
        rows = np.concatenate(
            [np.repeat(np.arange(n_m), 2), [n_m], n_m + 1 + np.repeat(np.arange(n_i), 2)]
        )
        kinds = np.concatenate([np.zeros(n_m + 1, dtype=np.int64), np.ones(n_i, dtype=np.int64)])
    else:
        ops = np.full(n_i, 2, dtype=np.int64)
        rows = np.repeat(np.arange(n_i), 2)
        kinds = np.ones(n_i, dtype=np.int64)
    for arr in (ops, rows, kinds):
        arr.setflags(write=False)
    return ops, rows, kinds


def move_gains(
    total, p_flat, grid: Grid, w: float, law: str, starts, ends, rows, kinds, old, scratch=None
):
    """Candidate moves of one waypoint scored on the cells they change only.

    ``total`` (ny * nx): the swarm's coverage; ``p_flat``: the prior; candidate ``r`` replaces
    the leg ``old[0] -> old[1]`` (``kinds[r]`` 1) or the legs ``old[0] -> old[1] -> old[2]``
    (``kinds[r]`` 0) by its new legs ``starts[l] -> ends[l]`` with ``rows[l] == r``. Returns
    the cells touched (flat indices, ascending), the candidates' coverage there (R, cells) and
    their gain in planned POS ``sum_j p_j (POD(C'_j) - POD(C_j))`` (R,): the full score's change,
    since every other cell keeps its coverage. The coverage equals the full
    ``total - old legs + new legs`` of :func:`leg_coverage` bit for bit (same samples, summed in
    the same order). ``scratch``: a boolean array of ``ny * nx`` False (kept so on return)
    and an int64 array of ``ny * nx``, in which the cells are marked and numbered (the same
    cells and positions as without, found without sorting)."""
    leg_n, cell_n, wt_n = leg_samples(starts, ends, grid, w)
    _, cell_a, wt_a = leg_samples(old[0], old[1], grid, w)
    movable = len(old) > 2
    if movable:
        _, cell_b, wt_b = leg_samples(old[1], old[2], grid, w)
    else:
        cell_b, wt_b = cell_a[:0], wt_a[:0]
    if scratch is None:
        cells = np.unique(np.concatenate([cell_n, cell_a, cell_b]))
        pos_n, pos_a, pos_b = (np.searchsorted(cells, q) for q in (cell_n, cell_a, cell_b))
    else:  # the cells marked and read back in order, numbered (the scratch then cleared)
        mark, number = scratch
        for q in (cell_n, cell_a, cell_b):
            mark[q] = True
        cells = np.flatnonzero(mark)
        mark[cells] = False
        number[cells] = np.arange(len(cells))
        pos_n, pos_a, pos_b = number[cell_n], number[cell_a], number[cell_b]
    nu = len(cells)
    n_rows = len(kinds)
    new = np.bincount(
        np.asarray(rows, dtype=np.int64)[leg_n] * nu + pos_n,
        weights=wt_n,
        minlength=n_rows * nu,
    ).reshape(n_rows, nu)
    old_a = np.bincount(pos_a, weights=wt_a, minlength=nu)
    old_b = np.bincount(pos_b, weights=wt_b, minlength=nu) if movable else 0.0
    here = total[cells]
    base0 = here - old_a - old_b
    base1 = here - old_a
    cand = np.where(np.asarray(kinds)[:, None] == 0, base0, base1) + new
    gain = (pod_from_coverage(cand, law) - pod_from_coverage(here, law)[None]) @ p_flat[cells]
    return cells, cand, gain


def refine_routes(
    routes: Sequence[Sequence[Sequence[float]]],
    takeoff,
    landing,
    prior: np.ndarray,
    grid: Grid,
    w: float,
    law: str,
    speeds,
    budget: float,
    turn_rate: float,
    reserve: float,
    sweeps: int = 4,
    headings=None,
    airspace: Airspace | None = None,
) -> tuple[list[list[list[float]]], float]:
    """Refined waypoints per UAV and their planned POS (module docstring). ``routes[k]`` are
    UAV ``k``'s waypoints between ``takeoff[k]`` and ``landing[k]``; a route that does not
    :func:`route_fits` ``budget`` and ``reserve`` first loses waypoints from its end until it
    does, and every kept move keeps it fitting. ``headings`` (n,): the UAVs' headings at
    take-off (rad), or None. With ``airspace``, a move is kept only if it adds no
    :func:`swarm_violations` at the planned positions (the best-scoring candidates are tried in
    turn, at most :data:`TRIES`). The moves do not see no-fly zones: on a map with zones the
    caller makes the refined routes flyable afterwards (:func:`fly_around`, eq. 20, keeping the
    clearance c)."""
    takeoff = np.asarray(takeoff, dtype=float).reshape(-1, 2)
    landing = np.asarray(landing, dtype=float).reshape(-1, 2)
    n = len(takeoff)
    p_flat = np.asarray(prior, dtype=float).ravel()
    x0, y0, x1, y1 = grid.bounds
    c = grid.cell_m
    lo = np.array([x0 + 1e-6 * c, y0 + 1e-6 * c])
    hi = np.array([x1 - 1e-6 * c, y1 - 1e-6 * c])
    paths = [
        _dedupe(
            np.vstack([takeoff[k], np.asarray(routes[k], dtype=float).reshape(-1, 2), landing[k]])
        )
        for k in range(n)
    ]

    h0 = [None] * n if headings is None else [float(h) for h in headings]

    def fits(path: np.ndarray, k: int) -> bool:
        return route_fits(path, speeds, turn_rate, budget, reserve, h0[k])

    turn_cost = TURN_SHARE / turn_rate

    def fits_all(path: np.ndarray, i: int, qs, ops, k: int) -> np.ndarray:
        """:func:`route_fits` of each candidate edit of ``path`` at ``i`` (``ops`` 0 move to,
        1 delete, 2 insert before it ``qs``), in one compiled pass."""
        ok = np.empty(len(ops), dtype=bool)
        hk = h0[k]
        _kernels.fits_batch(
            np.ascontiguousarray(path),
            i,
            np.ascontiguousarray(np.array(qs, dtype=float).reshape(-1, 2)),
            np.asarray(ops, dtype=np.int64),
            speeds.out,
            speeds.line,
            speeds.home,
            turn_cost,
            budget,
            reserve,
            np.nan if hk is None else float(hk),
            ok,
        )
        return ok

    for k in range(n):
        while len(paths[k]) > 2 and not fits(paths[k], k):
            paths[k] = np.delete(paths[k], -2, axis=0)

    def path_cov(path: np.ndarray) -> np.ndarray:
        return leg_coverage(path[:-1], path[1:], grid, w)[0]

    if airspace is not None:
        times = np.arange(int(np.ceil(budget / airspace.dt_s)) + 1) * airspace.dt_s
        pos = np.empty((len(times), n, 2))
        act = np.empty((len(times), n), dtype=bool)
        for k in range(n):
            pos[:, k], act[:, k] = track(paths[k], speeds, turn_rate, times, h0[k])
        count = AirspaceCount(airspace, pos, act)  # kept up to date as UAVs move

    covs = [path_cov(p) for p in paths]
    total = np.sum(covs, axis=0) if n else np.zeros(p_flat.size)  # a fresh array, updated in place
    value = float(p_flat @ pod_from_coverage(total, law))
    radii = np.asarray(RADII) * c
    offsets = (radii[:, None, None] * _DIRS[None]).reshape(-1, 2)
    across = np.concatenate([[0.0], radii, -radii]) if len(radii) else np.zeros(1)
    scratch = (np.zeros(p_flat.size, dtype=bool), np.zeros(p_flat.size, dtype=np.int64))
    for _ in range(max(0, int(sweeps))):
        kept = 0
        for k in range(n):
            i = 1
            while i < len(paths[k]):  # i: the waypoint moved/deleted, or inserted before
                path = paths[k]
                # the candidates (:func:`candidate_edits`): qs, ops 0 move, 1 delete, 2 insert
                qs, ops, starts, ends, rows, kinds = candidate_edits(
                    path, i, offsets, across, lo, hi
                )

                def cand(c: int, path=path, i=i, qs=qs, ops=ops) -> np.ndarray:
                    if ops[c] == 0:
                        return np.vstack([path[:i], qs[c], path[i + 1 :]])
                    if ops[c] == 1:
                        return np.vstack([path[:i], path[i + 1 :]])
                    return np.vstack([path[:i], qs[c], path[i:]])

                ok = fits_all(path, i, qs, ops, k)
                cells, cand_here, gain = move_gains(
                    total, p_flat, grid, w, law, starts, ends, rows, kinds, path[i - 1 : i + 2],
                    scratch,
                )  # fmt: skip
                vals = value + gain
                vals = np.where(ok, vals, -np.inf)
                j = -1
                for c_j in np.argsort(-vals, kind="stable")[:TRIES]:
                    if not vals[c_j] > value + TOL:
                        break
                    if airspace is None:
                        j = int(c_j)
                        break
                    v_new, state = count.move(
                        k, *track(cand(int(c_j)), speeds, turn_rate, times, h0[k])
                    )
                    if v_new <= count.value:
                        j = int(c_j)
                        count.keep(state)
                        break
                if j >= 0:
                    paths[k] = cand(j)
                    total[cells] = cand_here[j]
                    value = float(vals[j])
                    kept += 1
                    if ops[j] == 1:
                        continue  # deleted: the next waypoint is now at i
                i += 1
        if not kept:
            break
    out = [[[float(x), float(y)] for x, y in _dedupe(p)[1:-1]] for p in paths]
    return out, float(p_flat @ pod_from_coverage(total, law))


def fly_around(router: ZoneRouter, path, fits, shape=None) -> np.ndarray:
    """``path`` (take-off, waypoints, landing) made flyable by ``router``
    (:meth:`~poc_env.sim.routing.ZoneRouter.reroute`: search legs clipped to searchable
    airspace, transit around the zones), keeping the longest prefix of its waypoints for which
    ``fits(rerouted path)`` holds (bisection; none kept: take-off then landing, rerouted).
    ``shape``: applied to each rerouted path before ``fits`` (the allocation planner's lanes
    round the zones, :func:`poc_env.agents.planning.deconflict.lanes`)."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)

    def route(q: np.ndarray) -> np.ndarray:
        r = router.reroute(q)
        return r if shape is None else shape(r)

    full = route(p)
    if len(p) <= 2 or fits(full):
        return full

    def cut(m: int) -> np.ndarray:
        return route(np.vstack([p[: m + 1], p[-1:]]))

    lo, hi = 0, len(p) - 3  # lo: inner waypoints known to fit (0 is the fallback)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if fits(cut(mid)):
            lo = mid
        else:
            hi = mid - 1
    return cut(lo)
