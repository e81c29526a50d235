"""The planner's objective: eq. 25-26 of the paper, vectorised over a whole DE population.

Encoding (§4.3)
---------------
Each UAV ``i`` is six numbers, ``x[6 i : 6 i + 6] = (x_c, y_c, l, w, theta, d)``: the search
rectangle ``Q_i(x_c, y_c, l, w, theta)`` of §3.1.6 (centre, the side ``l`` along direction
``theta`` from the x axis, the side ``w`` across it) and the spacing ``d`` of its parallel
(lawnmower) lines. ``PlanObjective.bounds`` gives, per UAV, in metres and radians:

========  ==============================  ==================================================
 x_c      ``[x_min, x_max]`` of the grid   the centre lies over the map
 y_c      ``[y_min, y_max]`` of the grid
 l, w     ``[W / 2, max(width, height)]``  no thinner than the smallest spacing (one pass of
                                           a strip narrower than W/2 wastes the sweep); no
                                           longer than the map's longer side
 theta    ``[0, pi]``                      a rectangle is symmetric: theta and theta + pi
                                           are the same rectangle
 d        ``[W / 2, 4 W]``                 eq. 10 saturates: at d = W/2 POD = 0.988, denser
                                           gains at most 1.2 %; at d = 4 W POD = 0.25, and
                                           Table 6's d/W lie in [1.2, 1.9]
========  ==============================  ==================================================

``l < w`` is allowed: the lines then run along ``w`` (the long side), as in
:func:`poc_env.theory.patterns.parallel_line_search`; ``(l, w, theta)`` and ``(w, l, theta + pi/2)``
encode the same rectangle.

Honest scoring
--------------
The paper's closed-form scoring has loopholes an optimiser exploits; all are closed here.

1. *Area-weighted membership.* ``POC_i`` is the prior mass inside ``Q_i`` weighted by the exact
   area fraction of every cell that ``Q_i`` covers (closed form for cells crossed by one pair
   of sides, a rotated rectangle clipped against the square cell near corners; a compiled
   kernel that visits only the cells the rectangle reaches), never "cell centre inside the
   rectangle". POC is therefore continuous in the rectangle's parameters: a rectangle whose
   edges sit on cell centres gains nothing over the same rectangle shifted by a hair.
   The overlap rule of §3.1.6 (a cell already allocated to an earlier UAV adds nothing) is
   applied to every *part* of a cell: UAV ``i``'s fraction of a cell is the exact area of
   ``cell ∩ Q_i`` minus ``Q_0 ∪ ... ∪ Q_{i-1}`` (:func:`exclusive_fractions`), and these
   exclusive memberships go through :func:`poc_env.theory.search_theory.swarm_pos` (whose capacity
   form ``min(m_i, 1 - allocated)`` is exact for them). With plain fractions the capacity form
   would credit a copy of a rectangle with half its boundary cells again -- a third loophole.
2. *Detection the flown track supports.* The lawnmower of ``Q_i`` is the one
   :func:`~poc_env.theory.patterns.parallel_line_search` flies: lines along the long side ``L``, the
   first ``d/2`` inside the far edge (from the centre, across the lines, on the ``+e_E`` side,
   see :func:`lawnmower`), one every ``d`` while inside; a rectangle narrower than ``d`` across
   the lines gets one line through its middle. Its line count over the short side ``E`` is

       n = max(1, ceil(E / d - 1/2)),

   the search legs total ``n L`` and the turns ``(n - 1) d``. The credited coverage is the
   effort the lines spend over the rectangle, never more than eq. 10's:

       C_i = W min(n / E, 1 / d),     POD_i = pod_from_coverage(C_i, law),

   so a rectangle wider than ``d`` but flown with a single pass (``d < E < 3 d / 2``) gets
   ``pod(W / E) < erf(sqrt(pi)/2 W/d)``, not eq. 10's POD. For the inverse-cube law
   ``pod_from_coverage`` is eq. 10 itself, so with ``n d >= E`` this is exactly eq. 15. A
   rectangle narrower than ``d`` (one line through its middle, effort ``W / E > W / d``) is
   capped at eq. 10's POD for ``d``.

Time (eq. 17): transit from the take-off to the first waypoint and from the last waypoint to
the landing field at the cruise speed; every leg between waypoints (lines and turns) at the
search speed. The first waypoint is the lawnmower corner nearest the take-off (the rule of
:func:`~poc_env.theory.patterns.parallel_search` with ``start=takeoff``); the last follows from the
line count. The closed form equals the generated track's ``length_m`` (tested).

Objective (eq. 25-26), to minimise:

    f = -J + M sum_i phi(t_i),   J = alpha sum_i POC_i POD_i - beta (1/n) sum_i t_i / (0.85 T),

with ``phi(t) = max(0, t - 0.85 T)`` in seconds (:func:`poc_env.theory.timing.overtime_s`) and ``M``
the scenario's ``planner.penalty_m``; ``alpha`` and ``beta`` are the scenario's ``planner.alpha``
and ``planner.beta`` (the planner's own, not the RL reward's). With ``M = 1000`` and ``alpha = 1``
a millisecond of overtime outweighs any POS difference, so every feasible plan beats every
infeasible one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from poc_env._kernels import rectangles
from poc_env.agents.planning import _kernels
from poc_env.agents.planning.geography import probability
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError
from poc_env.geometry import rectangle_polygon
from poc_env.theory.bound import physical_optimum, zone_reach
from poc_env.theory.patterns import MAX_LINES, parallel_line_search
from poc_env.theory.probability_map import Grid, build_prior
from poc_env.theory.regions import area_fractions, exclusive_fractions
from poc_env.theory.search_theory import pod_from_coverage, swarm_pos
from poc_env.theory.search_theory import pos as pos_of
from poc_env.theory.search_theory import posc as posc_of
from poc_env.theory.timing import flight_lengths, flight_time_from_lengths, is_feasible, overtime_s

__all__ = [
    "PARAMS_PER_UAV",
    "PlanObjective",
    "PlanScores",
    "area_fractions",
    "exclusive_fractions",
    "flown_rectangle",
    "lawnmower",
]

#: Numbers per UAV in the encoding: (x_c, y_c, l, w, theta, d).
PARAMS_PER_UAV = 6
PARAM_NAMES = ("x_c", "y_c", "l", "w", "theta", "d")


# --------------------------------------------------------------------------- lawnmower


@dataclass(frozen=True)
class Lawnmower:
    """Closed-form lawnmower of rectangles (arrays broadcast over the leading axes).

    ``n_lines`` lines of ``line_length_m`` (the long side) at ``spacing_m``; ``search_m`` the
    search legs (``n L``), ``track_m`` every leg between the first and last waypoint
    (``n L + (n - 1) d``), ``first_m``/``last_m`` (..., 2) the first and last waypoints.
    """

    n_lines: np.ndarray
    line_length_m: np.ndarray
    search_m: np.ndarray
    track_m: np.ndarray
    first_m: np.ndarray
    last_m: np.ndarray


def lawnmower(center, length, width, theta, spacing, start) -> Lawnmower:
    """The lawnmower :func:`~poc_env.theory.patterns.parallel_line_search` flies, in closed form.

    Long side ``L = max(l, w)`` along ``e_L`` (direction ``theta``, or ``theta + pi/2`` when
    ``w > l``), short side ``E = min(l, w)`` across, ``e_E = e_L`` turned +90 degrees. The
    generator rotates the rectangle counter-clockwise by the lines' bearing ``pi/2 - alpha``,
    which sends ``e_L`` to +y and ``-e_E`` to +x, and puts its lines ``d/2, 3d/2, ...`` from the
    rotated minimum x: at offsets ``v_k = E/2 - d/2 - k d`` along ``e_E``, ``k < n`` with
    ``n = max(1, ceil(E/d - 1/2))`` (one line at ``v = 0`` when ``E < d``). Of the four starts
    (first or last line, either end) the one nearest ``start`` is flown (ties: the generator's
    order); the track ends on the other outer line, at the far end for odd ``n``.
    """
    c = np.asarray(center, dtype=float)
    alpha, long_, short, d, n = _lines(length, width, theta, spacing)
    e_l = np.stack([np.cos(alpha), np.sin(alpha)], axis=-1)
    e_e = np.stack([-np.sin(alpha), np.cos(alpha)], axis=-1)
    v_first = np.where(short < d, 0.0, 0.5 * (short - d))
    v_last = v_first - (n - 1.0) * d
    # candidates in parallel_search's order: (reverse, first_up) = FT, FF, TT, TF
    vs = np.stack([v_first, v_first, v_last, v_last], axis=-1)
    us = np.stack([-0.5 * long_, 0.5 * long_, -0.5 * long_, 0.5 * long_], axis=-1)
    corners = (
        c[..., None, :] + vs[..., None] * e_e[..., None, :] + us[..., None] * e_l[..., None, :]
    )
    dist = np.linalg.norm(corners - np.asarray(start, dtype=float)[..., None, :], axis=-1)
    k = np.argmin(dist, axis=-1)
    v_s = np.take_along_axis(vs, k[..., None], axis=-1)[..., 0]
    u_s = np.take_along_axis(us, k[..., None], axis=-1)[..., 0]
    v_e = np.where(k < 2, v_last, v_first)
    u_e = np.where(n % 2 == 1, -u_s, u_s)
    first = c + v_s[..., None] * e_e + u_s[..., None] * e_l
    last = c + v_e[..., None] * e_e + u_e[..., None] * e_l
    search = n * long_
    return Lawnmower(n, long_, search, search + (n - 1.0) * d, first, last)


def _lines(length, width, theta, spacing):
    """The one rectangle rule: lines along the long side (direction ``alpha``), ``n = max(1,
    ceil(E/d - 1/2))`` of them across the short side ``E``. Returns (alpha, L, E, d, n)."""
    l_ = np.asarray(length, dtype=float)
    w_ = np.asarray(width, dtype=float)
    d = np.asarray(spacing, dtype=float)
    alpha = np.where(l_ >= w_, theta, np.asarray(theta, dtype=float) + 0.5 * np.pi)
    short = np.minimum(l_, w_)
    return alpha, np.maximum(l_, w_), short, d, np.maximum(1.0, np.ceil(short / d - 0.5))


def flown_rectangle(center, length, width, theta, spacing):
    """The strip the lawnmower of :func:`lawnmower` actually sweeps: ``(center, L, E', alpha)``.

    The rule of the project's rectangles (see docs/PLANNER.md): lines along the long side ``L``
    (direction ``alpha``), the first ``d/2`` inside the ``+e_E`` edge, one every ``d`` while
    inside, ``n = max(1, ceil(E/d - 1/2))`` lines. Their swaths tile the strip of width
    ``E' = n d`` starting at that edge, centred ``(E - n d)/2`` along ``e_E`` from the centre
    (a rectangle narrower than ``d`` has one line through its middle: the strip is centred and
    ``E' = min(d, L)``). Flying this strip with lines along ``alpha`` -- by the project's rule
    (:func:`~poc_env.theory.patterns.parallel_search`) or by the usual ``ceil(E'/d)`` lawnmower,
    which coincide here -- gives exactly the same lines, hence the same eq. 17 flight time.
    ``E'`` may exceed ``L`` (wide strips of short lines): the lines still run along ``alpha``,
    so a consumer must use the returned direction, not "the long side".

    Returns ``(center (..., 2), line_length L, strip_width E', lines_direction alpha)``.
    """
    c = np.asarray(center, dtype=float)
    alpha, long_, short, d, n = _lines(length, width, theta, spacing)
    narrow = short < d
    strip = np.where(narrow, np.minimum(d, long_), n * d)
    shift = np.where(narrow, 0.0, 0.5 * (short - n * d))
    e_e = np.stack([-np.sin(alpha), np.cos(alpha)], axis=-1)
    return c + shift[..., None] * e_e, long_, strip, alpha


def plan_rectangles(x, box, takeoff, landing, x0, y0, h, weights, geo, terms) -> None:
    """The planner's rectangles for a population ``x (P, 6 n)``: ``geo (P, n, 5)`` gets the
    repaired ``x_c, y_c, l, w, theta`` of :meth:`PlanObjective.split`, ``terms (P, n, 6)`` the
    line count, line length, search legs, track and transit of :func:`lawnmower`, and the
    prior mass of each rectangle less the ones before it (§3.1.6, exclusive, over ``weights``
    on the grid at ``(x0, y0)`` with cells of ``h``). Two compiled passes: the planner's
    (:func:`poc_env.agents.planning._kernels.plan_rectangles`), then the masses by boundary
    integrals (:func:`poc_env._kernels.rectangles.rectangle_masses`)."""
    n_ind, n_uav = geo.shape[0], geo.shape[1]
    rects = np.empty((6, n_ind * n_uav))
    _kernels.plan_rectangles(x, box, takeoff, landing, geo, terms, rects)
    mass = np.zeros((n_ind, n_uav))
    cx, cy, half_l, half_w, cos_t, sin_t = rects
    rectangles.rectangle_masses(
        cx, cy, half_l, half_w, cos_t, sin_t, x0, y0, h, weights, True, mass
    )
    terms[:, :, 5] = mass


# --------------------------------------------------------------------------- objective


@dataclass(frozen=True)
class PlanScores:
    """Every term of eq. 25-26 for a population: shapes (P,) or (P, n)."""

    objective: np.ndarray  # (P,) eq. 26, to minimise
    j: np.ndarray  # (P,) eq. 25's J
    posc: np.ndarray  # (P,) sum_i POC_i POD_i (eq. 16 with the overlap rule)
    poc: np.ndarray  # (P, n) credited POC_i
    pod: np.ndarray  # (P, n)
    pos: np.ndarray  # (P, n)
    time_s: np.ndarray  # (P, n) eq. 17
    overtime_s: np.ndarray  # (P, n) phi(t_i)
    n_lines: np.ndarray  # (P, n)
    search_length_m: np.ndarray  # (P, n) search legs
    track_length_m: np.ndarray  # (P, n) all legs between first and last waypoint
    transit_length_m: np.ndarray  # (P, n) take-off -> first, last -> landing


class PlanObjective:
    """Eq. 26 of the paper for a scenario and a prior, evaluated for a whole population at once.

    Parameters
    ----------
    scenario:
        A :class:`~poc_env.config.Scenario` or a built-in name / YAML path.
    prior:
        POC map (ny, nx); default: the scenario's own prior (:func:`build_prior`).
    uavs:
        Number of UAVs (default: the scenario's fleet; else spread over the airfields,
        :meth:`Scenario.with_uavs`).
    alpha, beta, penalty_m:
        Weights of eq. 25 and the penalty factor M of eq. 26 (default: the scenario's
        ``planner.alpha``, ``planner.beta`` and ``planner.penalty_m``; never the RL reward's).
    bound_prior:
        The prior :meth:`upper_bound` bounds (default ``prior``): the planner passes the
        undiscounted prior when ``prior`` carries its no-fly-zone discount, and the bound
        credits what the sensor detects from outside the zones
        (:func:`poc_env.theory.bound.zone_reach`).

    Raises
    ------
    ConfigError
        Zero UAVs, a prior of the wrong shape, negative weights, or a scenario in which no
        UAV can reach the search area and return within 0.85 T.

    Notes
    -----
    ``obj.bounds`` (6n, 2) is the box of the encoding (module docstring), ``obj.dim = 6n``.
    ``obj(X)`` with X (P, 6n) returns the (P,) objective values; with X (6n,) a float.
    :meth:`evaluate` returns every term (:class:`PlanScores`), :meth:`decode` the per-UAV plan,
    :meth:`scalar_score` an independent slow reference (generated tracks, shapely areas).
    """

    def __init__(
        self,
        scenario: Scenario | str = "paper_6_2",
        prior: np.ndarray | None = None,
        *,
        uavs: int | None = None,
        alpha: float | None = None,
        beta: float | None = None,
        penalty_m: float | None = None,
        bound_prior: np.ndarray | None = None,
    ) -> None:
        sc = load_scenario(scenario) if not isinstance(scenario, Scenario) else scenario
        if uavs is not None:
            if isinstance(uavs, bool) or not isinstance(uavs, (int, np.integer)) or uavs < 1:
                raise ConfigError("uavs", uavs, "an integer >= 1 (at least one UAV)")
            sc = sc.with_uavs(int(uavs))
        if sc.n_uavs < 1:
            raise ConfigError("uavs", sc.n_uavs, "an integer >= 1 (at least one UAV)")
        self.scenario = sc
        self.grid = Grid.from_config(sc.map)
        p = build_prior(sc.map) if prior is None else np.asarray(prior, dtype=float)
        if p.shape != self.grid.shape or not np.all(np.isfinite(p)) or np.any(p < 0):
            raise ConfigError(
                "prior", getattr(p, "shape", p), f"finite values >= 0 of shape {self.grid.shape}"
            )
        self.prior = p
        #: the prior :meth:`upper_bound` bounds (the planner's ``prior`` may be discounted
        #: for no-fly zones; the bound takes the undiscounted one and :func:`zone_reach`)
        self.bound_prior = p if bound_prior is None else np.asarray(bound_prior, dtype=float)
        self._prior_flat = np.ascontiguousarray(p, dtype=float).reshape(-1)
        self._prior_grid = np.ascontiguousarray(p, dtype=float)
        self._box = np.array(self.grid.bounds, dtype=float)
        self.n = sc.n_uavs
        self.dim = PARAMS_PER_UAV * self.n
        self.sweep_width_m = sc.sensor.sweep_width_m
        self.law = sc.sensor.law
        u = sc.uav
        self.cruise_speed_mps = u.cruise_speed_mps
        self.search_speed_mps = u.search_speed_mps
        self.endurance_s = u.endurance_s
        self.usable_fraction = u.usable_fraction
        self.takeoff_m = np.asarray(sc.takeoff_m, dtype=float)
        self.landing_m = np.asarray(sc.landing_m, dtype=float)
        self.alpha = float(sc.planner.alpha if alpha is None else alpha)
        self.beta = float(sc.planner.beta if beta is None else beta)
        self.penalty_m = float(sc.planner.penalty_m if penalty_m is None else penalty_m)
        for name in ("alpha", "beta", "penalty_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(name, v, "a finite number >= 0")
        self.bounds = self._bounds()
        self._check_reachable()

    # -- encoding ----------------------------------------------------------------------------
    def _bounds(self) -> np.ndarray:
        x0, y0, x1, y1 = self.grid.bounds
        w = self.sweep_width_m
        side = max(self.grid.width_m, self.grid.height_m)
        lo_side = 0.5 * w
        if lo_side >= side:
            raise ConfigError(
                "sensor.sweep_width_km", w / 1000, "less than twice the map's longer side"
            )
        diagonal = math.hypot(self.grid.width_m, self.grid.height_m)
        if diagonal / (0.5 * w) > MAX_LINES:  # a pattern at d >= W/2 across the map
            raise ConfigError(
                "sensor.sweep_width_km", w / 1000,
                f"at least {2 * diagonal / MAX_LINES / 1000:.3g} km for the DE plan on this map "
                f"(its lines at spacing W/2 or more, at most {MAX_LINES} across the map's "
                f"{diagonal / 1000:.4g} km diagonal)",
            )  # fmt: skip
        one = np.array(
            [[x0, x1], [y0, y1], [lo_side, side], [lo_side, side], [0.0, np.pi], [0.5 * w, 4 * w]]
        )
        return np.tile(one, (self.n, 1))

    def _check_reachable(self) -> None:
        """ConfigError when no UAV can even touch the map and come back within 0.85 T."""
        x0, y0, x1, y1 = self.grid.bounds

        def to_box(p):
            dx = np.maximum(np.maximum(x0 - p[:, 0], p[:, 0] - x1), 0.0)
            dy = np.maximum(np.maximum(y0 - p[:, 1], p[:, 1] - y1), 0.0)
            return np.hypot(dx, dy)

        direct = np.linalg.norm(self.landing_m - self.takeoff_m, axis=1)
        least = np.maximum(direct, to_box(self.takeoff_m) + to_box(self.landing_m))
        need_s = least / self.cruise_speed_mps
        usable = self.usable_fraction * self.endurance_s
        if np.all(need_s > usable):
            need_h = need_s.min() / self.usable_fraction / 3600
            raise ConfigError(
                "uav.endurance_h",
                self.endurance_s / 3600,
                f"enough for a UAV to reach the search area and return within "
                f"{self.usable_fraction:g} T: at least {need_h:.3g} h at the cruise speed",
            )

    def as_population(self, x) -> np.ndarray:
        """X as a (P, 6n) float array; ConfigError for another width."""
        arr = np.asarray(x, dtype=float)
        if arr.ndim not in (1, 2) or arr.shape[-1] != self.dim:
            raise ConfigError("x", arr.shape, f"shape (6n,) or (P, 6n) with 6n = {self.dim}")
        return arr.reshape(-1, self.dim)

    def split(self, x) -> dict[str, np.ndarray]:
        """The encoding's fields, each (P, n): ``x_c, y_c, l, w, theta, d``, repaired to the map.

        Repair (the map rule, docs/PLANNER.md): a rectangle whose axis-aligned bounding box
        (half-extents ``h_x = (|l cos θ| + |w sin θ|)/2``, ``h_y = (|l sin θ| + |w cos θ|)/2``)
        is wider or taller than the map is scaled about its centre until it fits, then its
        centre is moved to the nearest point that keeps the box inside the map. Every
        rectangle therefore lies in the map, and so do its lines and waypoints; a rectangle
        already inside is unchanged. Every evaluation and :meth:`decode` see the repaired
        fields, so a plan's rectangle is the one scored and flown.
        """
        v = self.as_population(x).reshape(-1, self.n, PARAMS_PER_UAV)
        f = {name: v[..., k] for k, name in enumerate(PARAM_NAMES)}
        x0, y0, x1, y1 = self.grid.bounds
        c, s = np.abs(np.cos(f["theta"])), np.abs(np.sin(f["theta"]))
        hx = 0.5 * (f["l"] * c + f["w"] * s)
        hy = 0.5 * (f["l"] * s + f["w"] * c)
        k = np.minimum(1.0, np.minimum(0.5 * (x1 - x0) / hx, 0.5 * (y1 - y0) / hy))
        f["l"], f["w"], hx, hy = f["l"] * k, f["w"] * k, hx * k, hy * k
        f["x_c"] = np.clip(f["x_c"], x0 + hx, np.maximum(x0 + hx, x1 - hx))
        f["y_c"] = np.clip(f["y_c"], y0 + hy, np.maximum(y0 + hy, y1 - hy))
        return f

    # -- vectorised evaluation ---------------------------------------------------------------
    def memberships(self, x) -> np.ndarray:
        """Exclusive exact area fractions (P, n, ny, nx) of the UAVs' rectangles (§3.1.6)."""
        f = self.split(x)
        center = np.stack([f["x_c"], f["y_c"]], axis=-1)
        return exclusive_fractions(self.grid, center, f["l"], f["w"], f["theta"])

    def evaluate(self, x) -> PlanScores:
        """Every term of eq. 25-26 for the population X (P, 6n), in one vectorised pass.

        The map repair, the lawnmower, the transit and each UAV's POC (its rectangle's prior
        mass less what the UAVs before it cover, §3.1.6, by boundary integrals) come from one
        compiled pass, :func:`plan_rectangles`, which performs the operations
        of :meth:`split` and :func:`lawnmower` in the same order (pinned to 1e-12 by
        ``test_compiled_plan_pass_equals_split_lawnmower_and_exclusive_masses``); eq. 17, the
        POD and eq. 25-26 stay in numpy."""
        pop = np.ascontiguousarray(self.as_population(x))
        geo = np.empty((len(pop), self.n, 5))
        terms = np.empty((len(pop), self.n, 6))
        x0, y0 = map(float, self.grid.origin_m)
        plan_rectangles(
            pop,
            self._box,
            self.takeoff_m,
            self.landing_m,
            x0,
            y0,
            self.grid.cell_m,
            self._prior_grid,
            geo,
            terms,
        )
        n_lines, search, track, transit, poc = (terms[..., k] for k in (0, 2, 3, 4, 5))
        t = flight_time_from_lengths(transit, track, self.cruise_speed_mps, self.search_speed_mps)
        short = np.minimum(geo[..., 2], geo[..., 3])
        d = pop.reshape(len(pop), self.n, PARAMS_PER_UAV)[..., PARAM_NAMES.index("d")]
        coverage = self.sweep_width_m * np.minimum(n_lines / short, 1.0 / d)
        pod = pod_from_coverage(coverage, self.law)
        centre = geo[..., :2]  # _combine reads the line count and lengths only
        mower = Lawnmower(n_lines, terms[..., 1], search, track, centre, centre)
        pos = pos_of(poc, pod)
        posc = posc_of(pos, axis=-1)
        return self._combine(poc, pod, pos, posc, t, mower, transit)

    def _combine(self, poc, pod, pos, posc, t, mower, transit) -> PlanScores:
        phi = overtime_s(t, self.endurance_s, self.usable_fraction)
        usable = self.usable_fraction * self.endurance_s
        j = self.alpha * posc - self.beta * np.mean(t / usable, axis=-1)
        obj = -j + self.penalty_m * np.sum(phi, axis=-1)
        return PlanScores(
            objective=obj,
            j=j,
            posc=posc,
            poc=poc,
            pod=pod,
            pos=pos,
            time_s=t,
            overtime_s=phi,
            n_lines=mower.n_lines,
            search_length_m=mower.search_m,
            track_length_m=mower.track_m,
            transit_length_m=transit,
        )

    def __call__(self, x):
        """Eq. 26 (to minimise): (P,) values for X (P, 6n); a float for one x (6n,)."""
        arr = np.asarray(x, dtype=float)
        values = self.evaluate(arr).objective
        return float(values[0]) if arr.ndim == 1 else values

    # -- reporting ---------------------------------------------------------------------------
    def decode(self, x) -> list[dict[str, Any]]:
        """The plan of one individual x (6n,): one dict per UAV, with the generated track."""
        arr = np.asarray(x, dtype=float)
        if arr.ndim != 1:
            raise ConfigError("x", arr.shape, f"one individual, shape ({self.dim},)")
        sc = self.evaluate(arr[None])
        f = {k: v[0] for k, v in self.split(arr).items()}
        out = []
        for i in range(self.n):
            track = parallel_line_search(
                (f["x_c"][i], f["y_c"][i]),
                f["l"][i],
                f["w"][i],
                f["theta"][i],
                f["d"][i],
                start=self.takeoff_m[i],
            )
            out.append(
                {
                    "id": i,
                    "center_m": [float(f["x_c"][i]), float(f["y_c"][i])],
                    "length_m": float(f["l"][i]),
                    "width_m": float(f["w"][i]),
                    "theta_rad": float(f["theta"][i]),
                    "theta_deg": float(np.degrees(f["theta"][i])),
                    "spacing_m": float(f["d"][i]),
                    "takeoff_m": self.takeoff_m[i].tolist(),
                    "landing_m": self.landing_m[i].tolist(),
                    "n_lines": int(sc.n_lines[0, i]),
                    "flown_rectangle": _flown_dict(
                        flown_rectangle(
                            (f["x_c"][i], f["y_c"][i]),
                            f["l"][i],
                            f["w"][i],
                            f["theta"][i],
                            f["d"][i],
                        )
                    ),
                    "waypoints_m": track.waypoints.tolist(),
                    "track_length_m": float(sc.track_length_m[0, i]),
                    "search_length_m": float(sc.search_length_m[0, i]),
                    "flight_time_s": float(sc.time_s[0, i]),
                    "feasible": bool(
                        is_feasible(sc.time_s[0, i], self.endurance_s, self.usable_fraction)
                    ),
                    "pod": probability(sc.pod[0, i]),  # sums may round to 1 + 2e-16
                    "poc": probability(sc.poc[0, i]),
                    "pos": probability(sc.pos[0, i]),
                }
            )
        return out

    def upper_bound(self, x) -> float:
        """The physical optimum (:func:`physical_optimum`) for the plan's total effort, on
        what a flight keeping eq. 20 can detect of :attr:`bound_prior` (:func:`zone_reach`:
        the whole prior without no-fly zones)."""
        sc = self.evaluate(np.asarray(x, dtype=float).reshape(1, -1))
        effort = float(self.sweep_width_m * np.sum(sc.search_length_m))
        mass, area = zone_reach(self.scenario, self.bound_prior)
        return physical_optimum(mass, area, effort, self.law).pos

    def scalar_score(self, x) -> float:
        """Eq. 26 for one individual, the slow obviously-correct way (the tests' reference).

        Per UAV: the track generated by :func:`parallel_line_search` (start nearest the
        take-off) gives the lengths (:func:`poc_env.theory.timing.flight_lengths`, eq. 17) and the
        search length; shapely gives the exact area of every cell inside the UAV's rectangle
        minus the union of the earlier UAVs' rectangles (§3.1.6); then :func:`swarm_pos`, the
        eq. 10 cap and eq. 25-26 as in the module docstring.
        """
        arr = np.asarray(x, dtype=float)
        if arr.shape != (self.dim,):
            raise ConfigError("x", arr.shape, f"one individual, shape ({self.dim},)")
        f = self.split(arr)  # the map repair is the encoding's, shared with evaluate()
        arr = np.stack([f[name][0] for name in PARAM_NAMES], axis=-1).reshape(-1)
        boxes = np.array(self.grid.cell_boxes(), dtype=object)
        w_sweep = self.sweep_width_m
        members: list[Any] = []
        pods: list[float] = []
        times: list[float] = []
        earlier: list[Any] = []
        for i in range(self.n):
            xc, yc, ln, wd, th, d = arr[PARAMS_PER_UAV * i : PARAMS_PER_UAV * (i + 1)]
            track = parallel_line_search((xc, yc), ln, wd, th, d, start=self.takeoff_m[i])
            transit, search = flight_lengths(self.takeoff_m[i], track.waypoints, self.landing_m[i])
            times.append(
                float(
                    flight_time_from_lengths(
                        transit, search, self.cruise_speed_mps, self.search_speed_mps
                    )
                )
            )
            # effort over the rectangle, never more than eq. 10's W/d
            coverage = min(w_sweep * track.search_length_m / (ln * wd), w_sweep / d)
            pods.append(float(pod_from_coverage(coverage, self.law)))
            rect = rectangle_polygon((xc, yc), ln, wd, th)
            own = rect.difference(shapely.union_all(earlier)) if earlier else rect
            earlier.append(rect)
            area = shapely.area(shapely.intersection(own, boxes)) / self.grid.cell_area_m2
            members.append(area.reshape(self.grid.shape))
        _, _, posc = swarm_pos(np.array(members), np.array(pods), self.prior)
        t = np.array(times)
        usable = self.usable_fraction * self.endurance_s
        j = self.alpha * float(posc) - self.beta * float(np.mean(t / usable))
        phi = overtime_s(t, self.endurance_s, self.usable_fraction)
        return -j + self.penalty_m * float(np.sum(phi))


def _flown_dict(fr) -> dict[str, object]:
    """A :func:`flown_rectangle` as plan.json-ready numbers."""
    c, line_length, strip, alpha = fr
    return {
        "center_m": [float(c[0]), float(c[1])],
        "line_length_m": float(line_length),
        "strip_width_m": float(strip),
        "lines_theta_rad": float(alpha),
        "rule": "lines along lines_theta_rad at spacing d, d/2 inside each long edge",
    }
