"""Polish: a local search on a route plan's waypoints scored by the environment's own sensor.

:func:`poc_env.agents.planning.refine.refine_routes` climbs W x length per cell (eq. 10 per
cell), which the environment does not honour: its sensor spreads a line's effort laterally
(the inverse-cube law's lateral range, cut off at ``cutoff_sweep_widths x W``) over the prior's
sample points, so where two lines lie within a sweep width of each other, or a line runs along
the edge of the mass, the cell score and the environment disagree (docs/PLANNER.md, "Where the
loss goes, link by link": the line-geometry link). :func:`polish_routes` climbs the planned POS
itself, the quantity the plan reports (``allocation.sampled_sweep``).

**The score.** Per sample point ``x`` of the prior's fine lattice (``grid.refine(prior, s)``,
``s = sensor.samples_per_cell``, mass ``p(x)``) the swarm's exposure ``E(x) = sum over every
leg of every UAV of -log(1 - p_leg(x))``, ``p_leg`` the law's POD of the leg for the point
(:func:`poc_env._kernels.sensing.leg_exposure`: the compiled scalars the environment's sweep
applies, with its cut-off; for the inverse-cube law ``-log(1 - p)`` is the segment's exponent
F, and exponents of segments add). The swarm's POS is ``sum p(x) (1 - exp(-E(x)))`` (eq. 14
applied leg by leg: ``1 - prod(1 - p)``), which is ``sampled_sweep``'s total of the same paths
to rounding (``tests/planning/test_polish.py``: rel. 1e-9). A move changes a few legs, so its
gain is computed over the points those legs reach only (old legs' exposures out, new legs' in:
:func:`poc_env._kernels.sensing.exposure_gains`), and ``E`` is updated in place when a move is
kept.

**The moves**, per UAV ``k`` and waypoint ``i`` in turn (take-off and landing fields fixed;
``r`` in ``radii`` sweep widths):

* **move** the waypoint by ``r`` in one of 8 directions;
* **slide** it by ``+-r`` along its incoming or outgoing leg (a leg lengthened or shortened:
  the time a shorter connection frees goes to a longer line);
* **shift** the leg from it to the next waypoint sideways: both ends moved by ``+-r``
  perpendicular to the leg (a lawnmower line moved: two UAVs' lines over a shared patch
  interleave, a UAV's own lines space as the sensor wants);
* **insert** a waypoint at the midpoint of the leg into it moved ``+-r`` across the leg (before
  the landing field too: a route extended when time is left);
* **delete** it;
* **grade** (not in :data:`MOVES`; ``moves`` must name it, i24-grade): the ``m`` waypoints
  from it on (``m`` in :data:`GRADE_WINDOWS`) squeezed or spread across the leg from it to the
  next waypoint -- every point's offset across that leg, measured from the first or from the
  last of them, scaled by a factor of :data:`GRADE_SCALES` -- so the spacing of a run of
  consecutive parallel lawnmower lines changes together: a graded lawnmower, denser where the
  mass is, built from the one spacing a box was laid at;
* **block** (not in :data:`MOVES`; ``moves`` must name it, i24-lines): the ``m`` waypoints
  from it on (``m`` in :data:`BLOCK_WINDOWS`) translated together by ``+-r`` across the leg
  from it to the next waypoint or along it -- a run of lawnmower lines moved as one (their
  offsets re-solved jointly where a single line's shift, against its neighbours' fixed
  offsets, does not gain) or slid along the lines (the part of the box they cover moved
  along the line direction, the connectors into and out of the run changed).
* **box** (not in :data:`MOVES`; ``moves`` must name it, i24-boxes): a whole box of a
  route -- its inner waypoints split at its :data:`BOX_SPLITS` longest inner legs (the transit
  between its boxes), every run of consecutive pieces -- translated as one by ``r`` in
  ``box_radii`` sweep widths in one of 8 directions, squeezed about its centre by each
  factor of :data:`BOX_FITS` (1: none) so that a box carried further from its airfield can
  still fit the time: the footprint moved towards the mass at km scale, which the waypoint
  moves (radii of a few sweep widths) cannot do;
* **stretch** (likewise, i24-boxes): such a box scaled by a factor of
  :data:`STRETCH_SCALES` along or across its lines (its legs' length-weighted principal
  direction) about its centre or either edge: wider spacing over a larger area where the
  mass is thin, denser where it is rich, the time kept by ``route_fits``.
* **rotate** (likewise, i24-boxes): such a box turned by an angle of :data:`ROTATIONS`
  about the waypoint before it or the one after it: the leg into (or out of) the box keeps
  its length, so a box -- a route's whole search part, turned about its airfield -- is aimed
  at the mass at almost the same time (the one other connecting leg changes), where a
  translation towards a far mass would not fit the time;
* **trim** (likewise, i24-boxes; not in :data:`BOX_KINDS`): a box translated as the box
  move translates it (no squeeze) with its first or last one or two waypoints dropped -- the
  time the translation costs paid by the box's end lines;
* **group** (likewise, i24-boxes): the search parts (every inner waypoint) of all the UAVs
  that share a take-off and a landing field translated together, as the box move translates
  one box (the same offsets and squeeze factors, about the group's centre): a group's
  interleaved lines carried towards the mass as one, which no move of one UAV's box makes
  without breaking the interleave; kept if the group's gain exceeds :data:`TOL`, every
  member's route fits and, with ``airspace``, the swarm's violations do not rise.

The move of highest gain is tried first; it is kept if it gains more than :data:`TOL` and the
route stays as :func:`~poc_env.agents.planning.refine.refine_routes` keeps it: eq. 17-18 time
with turns within the budget and reserve (:func:`~poc_env.agents.planning.refine.route_fits`),
moved and inserted waypoints inside the map, and, with ``airspace``, no more eq. 21 / 24
violations at the planned positions (:class:`~poc_env.agents.planning.refine.AirspaceCount`,
the best :data:`~poc_env.agents.planning.refine.TRIES` fitting candidates tried in turn). The
search stops after ``passes`` passes over all waypoints or a pass without a kept move:
deterministic (no clock, no random draw).

**No-fly zones** (i24-zonepolish; eq. 20): with a ``router`` (the plan's
:class:`~poc_env.sim.routing.ZoneRouter`) a candidate is also rejected if its legs enter a zone
or cross the router's obstacle (the zones grown by the clearance ``c``, where the router's own
ways round run outside) more often than the legs it replaces (:func:`zone_guard`), so the
polished routes keep ``c`` from every zone as the router's routes do; eq. 21 is held as
without zones, by the airspace count at the planned positions. Without a router (or without
zones) nothing changes, bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from poc_env._kernels import sensing as _sensing
from poc_env.agents.planning import _kernels
from poc_env.agents.planning.refine import (
    TRIES,
    TURN_SHARE,
    Airspace,
    AirspaceCount,
    _dedupe,
    route_fits,
    track,
)
from poc_env.errors import ConfigError
from poc_env.theory.detection import detection_law
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import _reach

#: least gain in planned POS for a move to be kept.
TOL = 1e-7
#: default move radii, in sweep widths.
RADII = (0.25, 0.5, 1.0, 2.0)
#: the kinds of move (module docstring).
MOVES = ("move", "slide", "shift", "insert", "delete")
#: every kind of move (``grade`` too: tried only if ``moves`` names it).
KINDS = (*MOVES, "grade")
#: the kinds a ``moves`` argument may name (``block`` too, i24-lines; ``box`` and
#: ``stretch`` too, i24-boxes).
ALL_KINDS = (*KINDS, "block", "box", "stretch", "rotate", "group", "trim")
#: the box moves (i24-boxes): what ``PlanOptions.polish_boxes``'s third polish tries.
BOX_KINDS = ("box", "stretch", "rotate", "group")
#: a rotate move's angles, in degrees (i24-boxes).
ROTATIONS = (-20.0, -10.0, -5.0, -2.5, 2.5, 5.0, 10.0, 20.0)
#: default box translation radii, in sweep widths (i24-boxes).
BOX_RADII = (2.0, 4.0, 8.0, 16.0)
#: the factors a translated box is squeezed by about its centre (so a box carried further from
#: its airfield can still fit the time), and a stretch move's factors.
BOX_FITS = (1.0, 0.9, 0.8, 0.7)
STRETCH_SCALES = (0.7, 0.85, 1.15, 1.3)
#: inner legs a route's box windows are split at (the longest ones: transit between boxes).
BOX_SPLITS = 2
#: waypoints a block move translates together (1 to 4 lawnmower lines).
BLOCK_WINDOWS = (2, 4, 6, 8)
#: waypoints a grade move scales together (2, 3 and 4 lawnmower lines), and its factors.
GRADE_WINDOWS = (4, 6, 8)
GRADE_SCALES = (0.8, 0.9, 1.1, 1.25)
_DIRS = np.array(
    [[np.cos(a), np.sin(a)] for a in np.arange(8) * np.pi / 4], dtype=float
)  # unit steps of the move


@dataclass
class Exposure:
    """The swarm's exposure ``E`` on the fine lattice of ``grid`` (module docstring) and the
    sensor it is computed with; coordinates relative to the grid's origin inside."""

    grid: Grid
    samples: int
    sweep_width_m: float
    law: str
    cutoff_m: float
    mass: np.ndarray  # (ny s, nx s): the prior spread on the sample points
    expo: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.code = int(detection_law(self.law).code)
        self.reach = float(_reach(self.grid, self.law, self.sweep_width_m, self.cutoff_m))
        self.h = self.grid.cell_m / self.samples
        self.origin = np.asarray(self.grid.origin_m, dtype=float)
        self.mass = np.ascontiguousarray(self.mass, dtype=float)
        self.expo = np.zeros_like(self.mass)
        self.live = self.mass.copy()  # mass exp(-E): not yet found
        self._base = np.zeros_like(self.mass)
        self._work = np.zeros_like(self.mass)
        #: candidate steps scored by :meth:`gains` so far (the polish's work budget counts
        #: them: i24-bigpolish).
        self.scored = 0
        self._reaches: dict[float, float] = {}  # a screen's cut-off -> its reach (i24-fast2s)

    def steps(self, a, b) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The legs ``a -> b`` (L, 2) cut into steps no longer than a cell, as
        ``sampled_sweep`` flies them (:func:`~poc_env.theory.search_theory.sweep_track` with
        ``step_m`` the cell: the cut-off applies per step), relative to the grid's origin:
        (starts, ends, steps per leg)."""
        return _sensing.cut_steps(  # i24-cheapolish: compiled, the same steps bit for bit
            np.asarray(a, dtype=float).reshape(-1, 2),
            np.asarray(b, dtype=float).reshape(-1, 2),
            self.origin[0],
            self.origin[1],
            float(self.grid.cell_m),
        )

    def add(self, a, b, sign: float = 1.0) -> None:
        """Add (``sign`` 1) or take out (-1) the exposure of the legs ``a -> b`` (L, 2)."""
        sa, sb, _ = self.steps(a, b)
        _sensing.legs_exposure(
            self.code, sa, sb, self.sweep_width_m, self.cutoff_m,
            self.reach, self.grid.cell_m, self.h, float(sign), self.expo,
        )  # fmt: skip
        self.live = self.mass * np.exp(-self.expo)

    def pos(self) -> float:
        """The swarm's POS ``sum p (1 - exp(-E))``."""
        return float(np.sum(self.mass * -np.expm1(-self.expo)))

    def gains(self, old_a, old_b, new_a, new_b, first, cutoff_m=None) -> np.ndarray:
        """Gain in POS of each candidate (its legs ``new_a[l] -> new_b[l]``, ``first[c] <= l <
        first[c + 1]``) replacing the legs ``old_a -> old_b``. ``cutoff_m`` (None: the
        sensor's): a shorter cut-off for a cheaper, approximate score (i24-fast2s, the screen
        of :func:`polish_routes`: the same kernel over the points within it of each step)."""
        out = np.empty(len(first) - 1)
        cut, reach = self.cutoff_m, self.reach
        if cutoff_m is not None and cutoff_m < self.cutoff_m:
            cut = float(cutoff_m)
            if cut not in self._reaches:
                self._reaches[cut] = float(_reach(self.grid, self.law, self.sweep_width_m, cut))
            reach = self._reaches[cut]
        oa, ob, _ = self.steps(old_a, old_b)
        na, nb, per_leg = self.steps(new_a, new_b)
        self.scored += len(na)
        cum = np.concatenate([[0], np.cumsum(per_leg)])
        _sensing.exposure_gains(
            self.live, oa, ob, na, nb, cum[np.asarray(first, dtype=np.int64)],
            self.code,
            self.sweep_width_m, cut, reach, self.grid.cell_m, self.h,
            self._base, self._work, out,
        )  # fmt: skip
        return out


def screened_gains(
    ex: Exposure, old_a, old_b, starts, ends, first, top: int | None, cutoff_m: float
) -> np.ndarray:
    """The candidates' gains (:meth:`Exposure.gains`) as the screened polish uses them
    (i24-fast2s): with ``top`` (None: every candidate scored exactly, as before) and more
    candidates than ``top``, every candidate is first scored with the shorter cut-off
    ``cutoff_m`` (the same kernel over fewer points: an approximate gain), and only the
    ``top`` best of those are scored exactly; the others get ``-inf`` (never tried). A kept
    move's gain is therefore always the exact one; what the screen can change is which
    candidates are tried.

    Parameters
    ----------
    ex:
        The swarm's exposure.
    old_a, old_b:
        The legs the candidates replace, (L, 2) each.
    starts, ends, first:
        The candidates' legs (``first[c] <= l < first[c + 1]``: candidate ``c``'s).
    top:
        Candidates scored exactly after the screen, or None (no screen).
    cutoff_m:
        The screen's cut-off, metres.

    Returns
    -------
    numpy.ndarray
        (C,) gains: exact for the candidates kept by the screen, ``-inf`` for the others.
    """
    first = np.asarray(first, dtype=np.int64)
    n_c = len(first) - 1
    if top is None or n_c <= top:
        return ex.gains(old_a, old_b, starts, ends, first)
    rough = ex.gains(old_a, old_b, starts, ends, first, cutoff_m=cutoff_m)
    keep = np.sort(np.argsort(-rough, kind="stable")[:top])
    idx = np.concatenate([np.arange(first[c], first[c + 1]) for c in keep])
    sub = np.zeros(len(keep) + 1, dtype=np.int64)
    sub[1:] = np.cumsum(first[keep + 1] - first[keep])
    out = np.full(n_c, -np.inf)
    out[keep] = ex.gains(old_a, old_b, starts[idx], ends[idx], sub)
    return out


def zone_guard(router: Any) -> Callable[[np.ndarray, np.ndarray], bool] | None:
    """Eq. 20 for a local search (i24-zonepolish): ``bad(old, new)`` is True if the polyline
    ``new`` (a candidate's points, (P, 2)) enters a no-fly zone, or crosses ``router``'s
    obstacle (the zones grown by the clearance, :meth:`~poc_env.sim.routing.ZoneRouter.crosses`:
    compiled segment tests on prepared edges) on more legs than ``old`` (the points it
    replaces) does -- a route already inside the clearance ring (an airfield near a zone) may
    keep, not deepen, that. None (nothing to check) without a router or without zones.

    Parameters
    ----------
    router:
        A :class:`~poc_env.sim.routing.ZoneRouter` or None.

    Returns
    -------
    callable or None
        ``bad(old, new) -> bool``.
    """
    if router is None or not router.active:
        return None

    def bad(old: np.ndarray, new: np.ndarray) -> bool:
        a, b = new[:-1], new[1:]
        if router.enters_zones(a, b).any():
            return True
        n_new = int(router.crosses(a, b).sum())  # the old legs counted only if needed
        return n_new > 0 and n_new > int(router.crosses(old[:-1], old[1:]).sum())

    return bad


def _legs(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return points[:-1], points[1:]


def _framed_array(head: np.ndarray, body: np.ndarray, tail: np.ndarray) -> np.ndarray:
    """Candidates ``[head, body[c], tail]`` (``body`` (C, L, 2), ``tail`` (T, 2)) as one array
    (C, 1 + L + T, 2): per candidate the points ``np.vstack([head, body[c], tail])`` gives,
    built in one pass (i24-fastpolish: no array per candidate)."""
    c, n = body.shape[0], body.shape[1]
    out = np.empty((c, 1 + n + len(tail), 2))
    out[:, 0] = head
    out[:, 1 : 1 + n] = body
    out[:, 1 + n :] = tail
    return out


def _framed(head: np.ndarray, body: np.ndarray, tail: np.ndarray) -> list[np.ndarray]:
    """:func:`_framed_array` as a list of views, one per candidate."""
    return list(_framed_array(head, body, tail))


def _graded(pts: np.ndarray, tan: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The grade moves' windows (module docstring; (2 len(GRADE_SCALES), len(pts), 2)): the
    window ``pts`` squeezed or spread across its first leg (unit direction ``tan``) about its
    first or its last point by each factor of :data:`GRADE_SCALES`, clipped to ``[lo, hi]``
    (i24-cheapolish: one expression for the list of one array per pivot and factor, the same
    operations per point)."""
    nrm = np.array([-tan[1], tan[0]])
    off = (pts - pts[0]) @ nrm  # offsets across the first leg
    f = np.asarray(GRADE_SCALES, dtype=float) - 1.0
    pivot = np.array([0.0, float(off[-1])])
    scaled = (f[None, :, None] * (off[None, None, :] - pivot[:, None, None])).reshape(-1, len(off))
    return np.clip(pts[None] + scaled[:, :, None] * nrm[None, None], lo, hi)


@dataclass
class Start:
    """What a local search on a plan's routes starts from (:func:`start`): the swarm's
    exposure ``ex`` of every flying UAV's legs, the map's inner corners ``lo``, ``hi`` (points
    are kept inside), which UAVs fly, their ``paths`` (take-off, waypoints, landing), headings
    ``h0`` and the airspace's count of the planned positions (``count``; None without one)."""

    ex: Exposure
    w: float
    lo: np.ndarray
    hi: np.ndarray
    flying: list[bool]
    paths: list[np.ndarray]
    h0: list
    count: AirspaceCount | None
    times: np.ndarray | None


def start(
    routes, takeoff, landing, prior, grid: Grid, sensor, speeds, budget: float,
    turn_rate: float, headings=None, airspace: Airspace | None = None,
) -> Start:  # fmt: skip
    """The :class:`Start` of :func:`polish_routes` and of the regrade
    (:func:`poc_env.agents.planning.regrade.regrade_routes`): the arguments as theirs."""
    takeoff = np.asarray(takeoff, dtype=float).reshape(-1, 2)
    landing = np.asarray(landing, dtype=float).reshape(-1, 2)
    n = len(takeoff)
    w = float(sensor.sweep_width_m)
    s = int(sensor.samples_per_cell)
    ex = Exposure(
        grid,
        s,
        w,
        sensor.law,
        float(sensor.cutoff_sweep_widths) * w,
        grid.refine(np.asarray(prior, dtype=float), s),
    )
    x0, y0, x1, y1 = grid.bounds
    c = grid.cell_m
    lo = np.array([x0 + 1e-6 * c, y0 + 1e-6 * c])
    hi = np.array([x1 - 1e-6 * c, y1 - 1e-6 * c])
    flying = [len(r) > 0 for r in routes]
    paths = [
        np.vstack([takeoff[k], np.asarray(routes[k], dtype=float).reshape(-1, 2), landing[k]])
        if flying[k]
        else np.zeros((0, 2))
        for k in range(n)
    ]
    h0 = [None] * n if headings is None else [float(h) for h in headings]
    for k in range(n):
        if flying[k]:
            ex.add(*_legs(paths[k]))
    count, times = None, None
    if airspace is not None:
        times = np.arange(int(np.ceil(budget / airspace.dt_s)) + 1) * airspace.dt_s
        pos = np.zeros((len(times), n, 2))
        act = np.zeros((len(times), n), dtype=bool)
        for k in range(n):
            if flying[k]:
                pos[:, k], act[:, k] = track(paths[k], speeds, turn_rate, times, h0[k])
        count = AirspaceCount(airspace, pos, act)
    return Start(ex, w, lo, hi, flying, paths, h0, count, times)


def polish_routes(
    routes: Sequence[Sequence[Sequence[float]]],
    takeoff,
    landing,
    prior: np.ndarray,
    grid: Grid,
    sensor,
    speeds,
    budget: float,
    turn_rate: float,
    reserve: float,
    passes: int = 1,
    radii: Sequence[float] = RADII,
    headings=None,
    airspace: Airspace | None = None,
    moves: Sequence[str] = MOVES,
    box_radii: Sequence[float] = BOX_RADII,
    trace: Callable[..., None] | None = None,
    block_windows: Sequence[int] = BLOCK_WINDOWS,
    block_radii: Sequence[float] | None = None,
    focus: int | None = None,
    router: Any = None,
    work: int | None = None,
    screen: int | None = None,
    screen_cutoff: float = 2.0,
) -> tuple[list[list[list[float]]], float, dict]:
    """Polished waypoints per UAV, their planned POS and counts (module docstring).
    ``routes[k]``: UAV ``k``'s waypoints between ``takeoff[k]`` and ``landing[k]``; ``prior``
    the cell masses (the grid's shape); ``sensor`` the scenario's
    (:class:`poc_env.config.SensorConfig`: sweep width, law, samples per cell, cut-off);
    ``radii`` in sweep widths; ``headings`` (n,) the UAVs' headings at take-off (rad) or None;
    ``moves`` the kinds of move tried (:data:`ALL_KINDS`; default :data:`MOVES`).
    A route that does not fit ``budget`` to begin with is only changed by moves after which
    it does. ``box_radii``: the box moves' translations, in sweep widths. Returns ``(routes,
    pos, {"passes", "moves"})`` (and ``"block_moves"``, ``"box_moves"``, the kept moves that
    were block moves, box or stretch moves, where ``moves`` names them). ``trace`` (profiling
    only; no effect on the result): called after every choice of a set of candidates as
    ``trace(kind, pass, k, i, window, candidates, kept, gain)`` (``kind`` ``"waypoint"``,
    ``"grade"``, ``"block"`` or ``"box"``; ``kept`` the index of the kept
    candidate or -1, ``gain`` its gain or 0). i24-cheapolish: ``block_windows`` the block
    moves' windows (waypoints; default :data:`BLOCK_WINDOWS`), ``block_radii`` their radii in
    sweep widths (None: ``radii``); ``focus`` (None: off) -- after the first pass, the grade
    and block moves only at waypoints within ``focus`` of those a move kept in the pass before
    changed (measured not to pay on ``paper_6_2``: docs/PLANNER.md, "Cheaper candidates").
    ``router`` (i24-zonepolish): the plan's :class:`~poc_env.sim.routing.ZoneRouter`; with
    zones, candidates are checked by :func:`zone_guard` (module docstring, "No-fly zones").
    ``work`` (i24-bigpolish; None: no budget): the search also stops once it has scored this
    many candidate steps (the candidates' legs cut into steps of at most a cell, as
    ``sampled_sweep`` flies them: the scoring kernel's work), checked before each set of
    candidates is scored -- a count, not a clock, so the result is reproducible; the stats
    then hold ``"work"`` (the steps scored) and ``"spent"`` (True if the budget stopped it).
    ``screen`` (i24-fast2s; None: off, every candidate scored exactly): a waypoint's or a
    window's candidates are first scored with the cut-off ``screen_cutoff`` sweep widths
    (cheaper, approximate) and only the ``screen`` best of them exactly
    (:func:`screened_gains`); the group moves are scored exactly. With ``work`` the
    screen's steps count as scored too."""
    if not isinstance(passes, int) or isinstance(passes, bool) or passes < 0:
        raise ConfigError("passes", passes, "an integer >= 0")
    rad = tuple(radii)
    if not rad or any(not np.isfinite(r) or r <= 0 for r in rad):
        raise ConfigError("radii", radii, "positive numbers (sweep widths), not empty")
    brad = tuple(box_radii)
    if not brad or any(not np.isfinite(r) or r <= 0 for r in brad):
        raise ConfigError("box_radii", box_radii, "positive numbers (sweep widths), not empty")
    bwin = tuple(block_windows)
    if not bwin or any(isinstance(m_, bool) or not isinstance(m_, int | np.integer) or m_ < 1
                       for m_ in bwin):  # fmt: skip
        raise ConfigError("block_windows", block_windows, "integers >= 1 (waypoints), not empty")
    if block_radii is not None and (
        not tuple(block_radii) or any(not np.isfinite(r) or r <= 0 for r in block_radii)
    ):
        raise ConfigError("block_radii", block_radii, "positive numbers (sweep widths), not empty")
    if focus is not None and (isinstance(focus, bool) or not isinstance(focus, int) or focus < 0):
        raise ConfigError("focus", focus, "None or an integer >= 0 (waypoints)")
    if work is not None and (isinstance(work, bool) or not isinstance(work, int | np.integer)
                             or work < 0):  # fmt: skip
        raise ConfigError("work", work, "None or an integer >= 0 (candidate steps)")
    if screen is not None and (isinstance(screen, bool) or not isinstance(screen, int | np.integer)
                               or screen < 1):  # fmt: skip
        raise ConfigError("screen", screen, "None or an integer >= 1 (candidates)")
    if (isinstance(screen_cutoff, bool)
            or not isinstance(screen_cutoff, int | float | np.integer | np.floating)
            or not np.isfinite(screen_cutoff) or screen_cutoff <= 0):  # fmt: skip
        raise ConfigError("screen_cutoff", screen_cutoff, "a positive number (sweep widths)")
    kinds = set(moves)
    if not kinds or not kinds <= set(ALL_KINDS):
        raise ConfigError("moves", moves, f"some of {', '.join(ALL_KINDS)}")
    st = start(routes, takeoff, landing, prior, grid, sensor, speeds, budget, turn_rate,
               headings, airspace)  # fmt: skip
    ex, lo, hi, flying, paths, h0 = st.ex, st.lo, st.hi, st.flying, st.paths, st.h0
    count: Any = st.count  # used only where ``airspace`` is given, as ``times``
    times: Any = st.times
    n, w = len(paths), st.w
    value = ex.pos()
    zone_bad = zone_guard(router)
    screen_cut = float(screen_cutoff) * w  # i24-fast2s: the screen's cut-off, metres

    tag: list = ["waypoint", 0, 0]  # for ``trace``: the kind, pass and window being chosen
    spent = [False]  # the work budget used up (i24-bigpolish): no more candidates scored

    def over() -> bool:
        """Whether the work budget is used up (then no further set of candidates is scored)."""
        if work is not None and ex.scored >= work:
            spent[0] = True
        return spent[0]

    turn_cost = TURN_SHARE / turn_rate  # ``route_fits``' turn cost (eq. 17 with the turns)

    def choose(k: int, i0: int, i1: int, seqs: list[np.ndarray] | np.ndarray) -> bool:
        """Keep the best of the candidates ``seqs`` for ``paths[k][i0 : i1 + 1]`` (same first
        and last points; a list, or one array (C, P, 2) of candidates of P points) that gains
        more than :data:`TOL` and keeps the route flyable."""
        nonlocal value
        if over():
            return False
        path = paths[k]
        old = path[i0 : i1 + 1]
        if isinstance(seqs, np.ndarray):  # i24-cheapolish: the same steps, no list
            first = np.arange(len(seqs) + 1, dtype=np.int64) * (seqs.shape[1] - 1)
            starts = seqs[:, :-1].reshape(-1, 2)
            ends = seqs[:, 1:].reshape(-1, 2)
            pts = seqs.reshape(-1, 2)
            off = np.arange(len(seqs) + 1, dtype=np.int64) * seqs.shape[1]
        else:
            first = np.zeros(len(seqs) + 1, dtype=np.int64)
            first[1:] = np.cumsum([len(q) - 1 for q in seqs])
            starts = np.concatenate([q[:-1] for q in seqs])
            ends = np.concatenate([q[1:] for q in seqs])
            pts = np.concatenate(seqs)
            off = first + np.arange(len(seqs) + 1, dtype=np.int64)
        gain = screened_gains(ex, old[:-1], old[1:], starts, ends, first, screen, screen_cut)
        order = np.argsort(-gain, kind="stable")
        ok = gain[order] > TOL  # the candidates tried: those before the first that gains no more
        n_ok = len(ok) if ok.all() else int(np.argmin(ok))
        heading = np.nan if h0[k] is None else float(h0[k])
        t, tried = 0, 0
        while tried < TRIES:
            # i24-budget: the next candidate in order that keeps the route flyable
            # (``route_fits`` of each in turn, in one compiled call)
            t = _kernels.first_fitting(
                path, i0, i1, pts, off, order, t, n_ok, speeds.out, speeds.line, speeds.home,
                turn_cost, budget, reserve, heading,
            )  # fmt: skip
            if t >= n_ok:
                break
            cj = int(order[t])
            t += 1
            cand = np.concatenate([path[:i0], seqs[cj], path[i1 + 1 :]])
            if zone_bad is not None and zone_bad(old, seqs[cj]):
                continue
            if airspace is not None:
                tried += 1
                v_new, state = count.move(k, *track(cand, speeds, turn_rate, times, h0[k]))
                if v_new > count.value:
                    continue
                count.keep(state)
            ex.add(old[:-1], old[1:], -1.0)
            ex.add(seqs[cj][:-1], seqs[cj][1:], 1.0)
            value += float(gain[cj])
            paths[k] = cand
            if trace is not None:
                trace(tag[0], tag[1], k, i0 + 1, tag[2], len(seqs), int(cj), float(gain[cj]))
            hot_now[k].append((i0 + 1, i1 - 1))
            return True
        if trace is not None:
            trace(tag[0], tag[1], k, i0 + 1, tag[2], len(seqs), -1, 0.0)
        return False

    def windows(k: int, i: int, sizes, moved) -> int:
        """The window moves at waypoint ``i`` of UAV ``k``: for each window of ``sizes``
        consecutive inner waypoints, ``moved(pts, tan)`` gives its candidate positions (``tan``
        the unit direction of the window's first leg) and the best fitting one is kept if it
        gains; the number kept."""
        got = 0
        for m_ in sizes:
            path = paths[k]
            if i + m_ > len(path) - 1:  # the window's points are inner waypoints
                break
            d = path[i + 1] - path[i]
            ln = float(np.hypot(*d))
            if ln <= 1e-3:
                break
            body = moved(path[i : i + m_], d / ln)
            tag[2] = m_
            got += int(
                choose(
                    k, i - 1, i + m_, _framed_array(path[i - 1], body, path[i + m_ : i + m_ + 1])
                )
            )
        return got

    def graded(pts: np.ndarray, tan: np.ndarray) -> np.ndarray:
        """Grade moves (module docstring): :func:`_graded`."""
        return _graded(pts, tan, lo, hi)

    def blocked(pts: np.ndarray, tan: np.ndarray) -> np.ndarray:
        """Block moves (module docstring): the window translated across or along its first
        leg by each signed radius (``(2 len(bsigned), len(pts), 2)``)."""
        shifts = np.concatenate(
            [bsigned[:, None] * u[None] for u in (np.array([-tan[1], tan[0]]), tan)]
        )
        return np.clip(pts[None] + shifts[:, None], lo, hi)

    def box_windows(k: int) -> list[tuple[int, int]]:
        """The boxes of UAV ``k``'s route: first and last inner waypoint of every run of
        consecutive pieces of its inner waypoints split at its :data:`BOX_SPLITS` longest
        inner legs (module docstring)."""
        m = len(paths[k])
        if m < 3:
            return []
        inner = np.hypot(*np.diff(paths[k][1 : m - 1], axis=0).T) if m > 3 else np.zeros(0)
        cut = sorted(int(j) for j in np.argsort(-inner, kind="stable")[:BOX_SPLITS])
        edges = [1, *(j + 2 for j in cut), m - 1]  # piece p: edges[p] .. edges[p + 1] - 1
        return [
            (edges[a], edges[b] - 1)
            for a in range(len(edges) - 1)
            for b in range(a + 1, len(edges))
        ]

    def boxed(pts: np.ndarray) -> list[np.ndarray]:
        """Box moves (module docstring): the box translated in 8 directions by each box
        radius, squeezed about its centre by each factor of :data:`BOX_FITS`."""
        c = pts.mean(axis=0)
        rel = pts - c
        return [np.clip(c + f * rel + o[None], lo, hi) for o in box_offsets for f in BOX_FITS]

    def trimmed(pts: np.ndarray) -> list[np.ndarray]:
        """Trim moves (module docstring): the box translated with an end cut off."""
        cuts = [sl for j in (1, 2) if len(pts) > j for sl in (slice(j, None), slice(None, -j))]
        return [np.clip(pts[sl] + o[None], lo, hi) for o in box_offsets for sl in cuts]

    def stretched(pts: np.ndarray) -> list[np.ndarray]:
        """Stretch moves (module docstring): the box scaled along or across its lines about
        its centre or either edge."""
        d = np.diff(pts, axis=0)
        ln = np.hypot(d[:, 0], d[:, 1])
        if len(pts) < 2 or float(ln.sum()) <= 1e-3:
            return []
        ang = 0.5 * np.arctan2(np.sum(ln * np.sin(2 * np.arctan2(d[:, 1], d[:, 0]))),
                               np.sum(ln * np.cos(2 * np.arctan2(d[:, 1], d[:, 0]))))  # fmt: skip
        main = np.array([np.cos(ang), np.sin(ang)])
        out = []
        for u in (main, np.array([-main[1], main[0]])):
            t = pts @ u
            for pivot in (0.5 * (t.min() + t.max()), t.min(), t.max()):
                for f in STRETCH_SCALES:
                    out.append(np.clip(pts + ((f - 1.0) * (t - pivot))[:, None] * u[None], lo, hi))
        return out

    def rotated(pts: np.ndarray, pivots) -> list[np.ndarray]:
        """Rotate moves (module docstring): the box turned about each pivot."""
        out = []
        for pv in pivots:
            rel = pts - pv
            for cs, sn in rot:
                out.append(np.clip(pv + rel @ np.array([[cs, sn], [-sn, cs]]), lo, hi))
        return out

    def boxes(k: int) -> int:
        """The box and stretch moves of UAV ``k``'s boxes: the number kept."""
        got = 0
        for i0, i1 in box_windows(k):
            path = paths[k]
            pts = path[i0 : i1 + 1]
            seqs: list[np.ndarray] = []
            if "box" in kinds:
                seqs += boxed(pts)
            if "trim" in kinds:
                seqs += trimmed(pts)
            if "stretch" in kinds and i1 > i0:
                seqs += stretched(pts)
            if "rotate" in kinds:
                seqs += rotated(pts, (path[i0 - 1], path[i1 + 1]))
            seqs = [np.vstack([path[i0 - 1], q, path[i1 + 1]]) for q in seqs]
            if seqs:
                tag[0], tag[2] = "box", 0
                got += int(choose(k, i0 - 1, i1 + 1, seqs))
            if len(paths[k]) != len(path):  # trimmed: the windows are the next pass's
                break
        return got

    def group_move(ks: list[int]) -> bool:
        """The group move (module docstring) of the UAVs ``ks``: the best fitting candidate
        kept if it gains."""
        nonlocal value
        if over():
            return False
        inner = [paths[k][1:-1] for k in ks]
        c = np.vstack(inner).mean(axis=0)
        cands = [
            [np.clip(c + f * (q - c) + o[None], lo, hi) for q in inner]
            for o in box_offsets
            for f in BOX_FITS
        ]
        for pv in dict.fromkeys(map(tuple, (paths[ks[0]][0], paths[ks[0]][-1]))):
            cands += [list(z) for z in zip(*(rotated(q, (np.asarray(pv),)) for q in inner))]
        full = [[np.vstack([paths[k][0], q, paths[k][-1]]) for k, q in zip(ks, cd)] for cd in cands]
        old_a = np.vstack([paths[k][:-1] for k in ks])
        old_b = np.vstack([paths[k][1:] for k in ks])
        first = np.zeros(len(full) + 1, dtype=np.int64)
        first[1:] = np.cumsum([sum(len(p) - 1 for p in fp) for fp in full])
        starts = np.vstack([p[:-1] for fp in full for p in fp])
        ends = np.vstack([p[1:] for fp in full for p in fp])
        gain = ex.gains(old_a, old_b, starts, ends, first)
        tried = 0
        for cj in np.argsort(-gain, kind="stable"):
            if not gain[cj] > TOL or tried >= TRIES:
                break
            fp = full[cj]
            if not all(
                route_fits(p, speeds, turn_rate, budget, reserve, h0[k]) for k, p in zip(ks, fp)
            ):
                continue
            if zone_bad is not None and any(zone_bad(paths[k], p) for k, p in zip(ks, fp)):
                continue
            if airspace is not None:
                tried += 1
                before = count.value
                undo = [(k, count.pos[:, k].copy(), count.act[:, k].copy()) for k in ks]
                for k, p in zip(ks, fp):
                    count.keep(count.move(k, *track(p, speeds, turn_rate, times, h0[k]))[1])
                if count.value > before:
                    for k, pk, ak in undo:
                        count.keep(count.move(k, pk, ak)[1])
                    continue
            for k, p in zip(ks, fp):
                ex.add(paths[k][:-1], paths[k][1:], -1.0)
                ex.add(p[:-1], p[1:], 1.0)
                paths[k] = p
            value += float(gain[cj])
            return True
        return False

    groups: list[list[int]] = []
    for k in range(n):
        if flying[k] and len(paths[k]) > 2:
            for g in groups:
                if np.array_equal(takeoff[g[0]], takeoff[k]) and np.array_equal(
                    landing[g[0]], landing[k]
                ):
                    g.append(k)
                    break
            else:
                groups.append([k])
    rot = [(np.cos(a), np.sin(a)) for a in np.radians(ROTATIONS)]
    box_offsets = (np.asarray(brad, dtype=float)[:, None, None] * w * _DIRS[None]).reshape(-1, 2)
    steps = np.asarray(rad, dtype=float) * w
    offsets = (steps[:, None, None] * _DIRS[None]).reshape(-1, 2)
    signed = np.concatenate([steps, -steps])
    bsteps = steps if block_radii is None else np.asarray(tuple(block_radii), dtype=float) * w
    bsigned = np.concatenate([bsteps, -bsteps])
    bwin = tuple(int(m_) for m_ in bwin)
    # focus (i24-cheapolish): after the first pass, the window moves only near the waypoints
    # changed in the pass before (``hot``: per UAV the ranges of inner waypoints kept moves
    # changed, in that pass's numbering)
    hot: list[list[tuple[int, int]]] = [[] for _ in range(n)]
    hot_now: list[list[tuple[int, int]]] = [[] for _ in range(n)]

    def near(k: int, i: int) -> bool:
        return focus is None or done == 1 or any(a - focus <= i <= b + focus for a, b in hot[k])

    n_moves = 0
    n_block = 0  # of them block moves
    n_box = 0  # of them box or stretch moves
    done = 0
    for _ in range(max(0, int(passes))):
        kept = 0
        done += 1
        tag[1] = done
        hot, hot_now = hot_now, [[] for _ in range(n)]
        if "group" in kinds:  # i24-boxes: the groups' search parts first
            for g in groups:
                if len(g) > 1:
                    got = int(group_move(g))
                    kept += got
                    n_box += got
        for k in range(n):
            if not flying[k] or spent[0]:
                continue
            if kinds & {"box", "stretch", "rotate", "trim"}:  # i24-boxes: whole boxes first
                got = boxes(k)
                kept += got
                n_box += got
            i = 1
            # i: the waypoint changed (inserts go before it)
            while i < len(paths[k]) and not spent[0]:
                path = paths[k]
                m = len(path)
                j_end = min(i + 2, m - 1)  # the legs path[i-1] .. path[j_end] may change
                tail = path[i + 1 : j_end + 1]  # after waypoint i, in the window
                seqs: list[np.ndarray] = []  # each candidate's points from path[i-1] to path[j_end]
                a, b = path[i - 1], path[i]
                if i < m - 1:  # an inner waypoint: move, slide, shift, delete
                    nxt = path[i + 1]
                    qs = [b + offsets] if "move" in kinds else []
                    for u in (b - a, nxt - b) if "slide" in kinds else ():
                        ln = float(np.hypot(*u))
                        if ln > 1e-3:
                            qs.append(b + signed[:, None] * (u / ln)[None])
                    if qs:
                        seqs += _framed(a, np.clip(np.vstack(qs), lo, hi)[:, None], tail)
                    if m > 3 and "delete" in kinds:  # a route keeps a waypoint (sampled_sweep)
                        seqs.append(np.vstack([a, tail]))
                    if i + 1 < m - 1 and "shift" in kinds:  # leg i -> i+1, two inner waypoints
                        d = nxt - b
                        ln = float(np.hypot(*d))
                        if ln > 1e-3:
                            across = signed[:, None] * (np.array([-d[1], d[0]]) / ln)[None]
                            q12 = np.stack(
                                [np.clip(b + across, lo, hi), np.clip(nxt + across, lo, hi)], axis=1
                            )
                            seqs += _framed(a, q12, path[i + 2 : j_end + 1])
                d = b - a  # insert before i
                ln = float(np.hypot(*d))
                if ln > 1e-3 and "insert" in kinds:
                    across = signed[:, None] * (np.array([-d[1], d[0]]) / ln)[None]
                    q = np.clip(0.5 * (a + b) + across, lo, hi)
                    seqs += _framed(a, np.stack([q, np.broadcast_to(b, q.shape)], axis=1), tail)
                tag[0], tag[2] = "waypoint", 0
                if seqs and choose(k, i - 1, j_end, seqs):
                    kept += 1
                    if len(paths[k]) < m:
                        continue  # deleted: the next waypoint is now at i
                hot_i = near(k, i)
                if "grade" in kinds and hot_i:
                    tag[0] = "grade"
                    kept += windows(k, i, GRADE_WINDOWS, graded)
                if "block" in kinds and hot_i:
                    tag[0] = "block"
                    got = windows(k, i, bwin, blocked)
                    kept += got
                    n_block += got
                i += 1
        n_moves += kept
        if not kept or spent[0]:
            break
    out = [
        [[float(x), float(y)] for x, y in _dedupe(p)[1:-1]] if flying[k] else []
        for k, p in enumerate(paths)
    ]
    stats = {"passes": done, "moves": n_moves}
    if "block" in kinds:
        stats["block_moves"] = n_block
    if kinds & {"box", "stretch", "rotate", "group", "trim"}:
        stats["box_moves"] = n_box
    if work is not None:
        stats["work"] = int(ex.scored)
        stats["spent"] = bool(spent[0])
    return out, ex.pos(), stats


def polish_for(
    sc,
    routes: Sequence[Sequence[Sequence[float]]],
    prior: np.ndarray,
    passes: int = 1,
    *,
    speeds=None,
    separation_margin: float = 2.0,
    range_margin: float = 0.9,
    airspace: bool = True,
    routine=None,
    **kw,
) -> tuple[list[list[list[float]]], float, dict]:
    """:func:`polish_routes` (or ``routine``, which takes its arguments: i24-regrade's
    :func:`~poc_env.agents.planning.regrade.regrade_routes`) of scenario ``sc``'s routes as the
    allocation planner calls it:
    its map, fields, sensor, usable endurance, turn rate and reserve, the headings at take-off,
    ``speeds`` (default :func:`~poc_env.agents.planning.flight_rules.plan_speeds`) and, with
    ``airspace``, eq. 21 / 24 counted with ``separation_margin`` on d_s and ``range_margin`` on
    the range (:class:`~poc_env.agents.planning.options.PlanOptions`' defaults); ``kw``:
    ``radii``, ``moves``, ``box_radii``."""
    from poc_env.agents.planning.flight_rules import plan_speeds, reserve_s
    from poc_env.sim.core import takeoff_heading

    grid = Grid.from_config(sc.map)
    takeoff = np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2)
    landing = np.asarray(sc.landing_m, dtype=float).reshape(-1, 2)
    air = Airspace(
        sc.episode.dt_s,
        separation_margin * sc.constraints.safety_distance_m,
        range_margin * sc.comms.range_m,
        sc.comms.min_neighbours,
    )
    u = sc.uav
    return (polish_routes if routine is None else routine)(
        routes,
        takeoff,
        landing,
        prior,
        grid,
        sc.sensor,
        plan_speeds(sc) if speeds is None else speeds,
        u.usable_endurance_s,
        u.max_turn_rate_rad_s,
        reserve_s(sc),
        passes=passes,
        headings=takeoff_heading(grid.bounds, takeoff),
        airspace=air if airspace else None,
        **kw,
    )
