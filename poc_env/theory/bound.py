"""Upper bounds on the POS of a search: the physical optimum, honest, reach-aware, rule-aware.

**The allocation bound.** For a prior (cell masses ``m_j``, cell areas ``a_j``), a detection
law ``POD(C)`` as a function of the coverage ``C`` (:func:`poc_env.theory.search_theory.
pod_from_coverage`) and a total effort ``Z = W x track length`` (m^2), the Koopman/Stone
optimal allocation solves

    maximise  sum_j m_j POD(C_j)   subject to   sum_j a_j C_j = Z,  C_j >= 0.

The objective is concave, so the KKT conditions are sufficient: every searched cell has the same
marginal return ``(m_j / a_j) POD'(C_j) = lambda``. Each law's entry in the table
(:mod:`poc_env.theory.detection`) gives that coverage as ``optimal_coverage(g)`` with
``g = ln(m_j / (a_j lambda))`` for ``m_j / a_j > lambda`` (0 elsewhere): for the inverse-cube law
(POD' = exp(-pi C^2 / 4)) ``C_j = sqrt(4/pi g)``, for the exponential law ``C_j = g``;
``lambda`` is found by bisection so that the effort is spent exactly. A law without one (the
definite-range law, linear up to C = 1) fills the densest cells first
(:func:`physical_optimum`).

**The honest plain bound** (:func:`honest_optimum`, :func:`env_limits`). The environment
(:mod:`poc_env.sim.core`) moves a UAV by ``v dt`` per step with ``v <= max_speed`` (the old
speed, clipped to ``[min_speed, max_speed]``; pitch only shortens the horizontal segment it
sweeps), senses the whole segment, and keeps a UAV flying until it lands, crashes (flight time
reaching the endurance T -- the 0.85 T of eq. 18 is only penalised) or the horizon ends. So a UAV
sweeps at most ``W v_max`` m^2/s for at most :func:`sensing_time_s` (``dt`` x the steps until T
or the horizon), and the plain bound takes ``Z = sum_i W v_max t_sense``. (The earlier bound,
every UAV at the search speed v_s for 0.85 T, is smaller and a policy flying faster or longer can
exceed it.)

Why a flown episode stays below it, per law:

- ``exponential``: a step detects a sample point only through the length of the step inside the
  point's own cell (``p = 1 - exp(-W L_j / a_j)``, the same for every sample point of cell j),
  and exponents of successive steps add; so cell j's POD is exactly ``1 - exp(-C_j)`` with
  ``C_j = W x (track length in j) / a_j`` and ``sum a_j C_j <= Z``: the bound is rigorous
  (cells are half-open in the kernel, so a track exactly along a cell edge counts once).
- ``definite_range``: a step detects the points within W/2 of it (foot on the step), a set of
  area ``W L``; the detected area of the whole flight is at most ``W x track length = Z``. With
  ``c_j`` the detected share of cell j (at most 1), POS = ``sum m_j c_j`` with
  ``sum a_j c_j <= Z`` -- the allocation bound for ``POD = min(C, 1)``. This is rigorous for
  targets uniform in their cells; the environment counts ``s x s`` sample points per cell
  instead of area, and a track laid exactly along a row of sample points catches
  ``floor(W / h) + 1`` rows instead of ``W / h`` (``h`` the sample spacing; tracks 2 W apart
  along the rows: POD 0.75 instead of 0.5): a measure-zero alignment, noted, not excluded.
- ``inverse_cube``: ``erf(sqrt(pi)/2 C)`` is what parallel tracks at spacing ``W / C`` give
  (eq. 10); it is the bound's model of the best a given local effort can do (uneven spacing is
  worse by concavity, crossing or circling tracks spend effort where the exponent is already
  high). It is not a theorem for every path, and sample points differ from the area average:
  tracks along the sample rows at the best offset exceed eq. 10 by up to 1.2 % (S = W = 2 h,
  default cut-off: 0.7921 against 0.7899; C = 2: 1.0000 against 0.9878), tracks at a generic
  angle stay below it (``tests/theory/test_bound_lattice.py``). The adversarial flights of
  ``tests/experiments/test_bound_env.py`` stay below both bounds.

**The reach-aware bound** (:func:`reach_bound`, :func:`reach_optimum`). A UAV starts at its
take-off field ``s`` and flies at most at ``v = v_max``. *Claim:* the track length it flies at
points farther than ``d`` from ``s`` is at most ``v (t_sense - d / v)^+``. *Proof:* the first time
the UAV is farther than ``d`` is at least ``d / v`` (straight lines are the shortest paths), and
from then on it flies at most ``v`` per second until ``t_sense``. A sample point of cell j can
only be detected from track within ``rho`` of it (``rho``, :attr:`EnvLimits.spill_m`: W/2 for
the definite range, the lateral cut-off for the inverse cube, 0 for the exponential law whose
effort and detection share a cell), so the effort that serves cells at distance at least
``d_j`` (nearest point of the cell) lies at distance at least ``d_j - rho`` from ``s``: with
``tau_ij = (d_ij - rho)^+ / v`` and ``r = W v``, for every UAV i and time t

    sum_{j : tau_ij >= t} a_j C_ij <= r (t_sense - t)^+,   C_j = sum_i C_ij,

and the bound maximises ``sum_j m_j POD(C_j)`` under these nested constraints (a relaxation of
every flight, so an upper bound; without transit it is the plain bound, so it is never above
it). Effort spent while flying out is itself effort in the nearer cells it crosses, which the
constraint for the nearer threshold already counts. The environment does not make a UAV come
back (it may sense until it crashes at T), so the default bound has no return leg;
``round_trip=True`` (for plans that must land within the usable endurance 0.85 T) uses
``tau = 2 (min(d(take-off, j), d(landing, j)) - rho)^+ / v`` and the usable endurance: the UAV
must also be back, so the track at distance ``>= d`` from both fields is at most
``v T_usable - 2 d``.

**The rule-aware bound** (:func:`rule_bound`). The plan rules on top: back within 0.85 T and
the way home at the cruise speed ``v_c`` (eq. 18's return rule), so ``tau = (d(take-off, j) -
rho)^+ / v_max + (d(landing, j) - rho)^+ / v_c`` with the usable endurance as budget. It bounds
what a plan that keeps the rules can reach and normalises plans (``plan`` and ``evaluate`` print
it beside the honest and reach-aware bounds).

**With no-fly zones** (:func:`zone_reach`). A flight that keeps eq. 20 never enters a zone,
so it detects a sample point only from track outside the zones, within the law's reach ``rho``
(:attr:`DetectionLaw.reach <poc_env.theory.detection.DetectionLaw>`: W/2 for the definite
range, the lateral cut-off ``cutoff_sweep_widths x W`` for the inverse cube, the cell's
diagonal for the exponential law). A cell's sample points deeper than ``rho`` inside the zones
are never detected; the rest, a share ``s_j`` of its points, is a sub-cell of mass ``s_j m_j``
and area ``s_j a_j`` (the cell's density). Every bound above on those sub-cells bounds every
flight that keeps eq. 20: the hidden points add nothing to its POS and the sub-cell is no
larger than where its detections happen. The planners' own zone discount
(:meth:`poc_env.sim.routing.ZoneRouter.reach_share` at ``W/2`` of the keep-out area, by area)
is smaller -- a conservative planning model, not a bound: the inverse-cube sensor detects up to
its cut-off (4 W by default) from a zone's edge. Bounds that ignore the zones (honest,
reach-aware, rule-aware) stay valid, looser, and also bound flights that enter zones.

The solver (:func:`reach_optimum`) is exact: the feasible efforts form a polymatroid (its rank is
``g(A) = sum_i r (t_i - min_{j in A} tau_ij)^+``) and the decomposition algorithm for separable
concave objectives over a polymatroid reduces it to water-fillings (:func:`physical_optimum`)
and a search for the most violated cell set, which for one or two distinct take-off points is a
scan over thresholds (more are merged into two, and on grids above ~7000 cells two into one:
valid relaxations, which :func:`rule_bound` tightens by sums over blocks of at most two fields).
A Lagrangian dual value at
the allocation's marginal returns certifies it (``ReachBound.upper``, gap below 1e-9 on the
shipped scenarios). 0.1 s on ``paper_6_2`` (40 x 30 cells, 6 UAVs).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import shapely
from scipy.optimize import brentq

from poc_env.config import Scenario
from poc_env.errors import ConfigError, check_positive
from poc_env.geometry import as_polygon
from poc_env.theory.detection import DetectionLaw, detection_law
from poc_env.theory.probability_map import Grid
from poc_env.theory.regions import reach_share
from poc_env.theory.search_theory import pod_from_coverage


@dataclass(frozen=True)
class Bound:
    """Result of :func:`physical_optimum`: the POS bound and the optimal coverage per cell."""

    pos: float
    coverage: np.ndarray
    multiplier: float
    effort_m2: float
    law: str


def _coverage_at(lam: float, density: np.ndarray, law: DetectionLaw) -> np.ndarray:
    """The KKT coverage of every cell for the multiplier ``lam`` (the law's table entry)."""
    assert law.optimal_coverage is not None
    with np.errstate(divide="ignore"):
        g = np.log(np.where(density > 0, density, 1e-300) / lam)
    return law.optimal_coverage(np.maximum(g, 0.0))


def physical_optimum(prior, cell_area_m2, effort_m2: float, law: str = "inverse_cube") -> Bound:
    """Maximum POS reachable with ``effort_m2`` of sweep-width x track length (see module doc).

    ``prior`` is any array of cell masses; ``cell_area_m2`` a scalar or an array of its shape.

    Examples
    --------
    Three 5 km cells holding 0.5, 0.3 and 0.2 of the target, and one cell's area of effort
    (sweep width x track length): the optimum spends it on the two densest cells only.

    >>> from poc_env.theory.bound import physical_optimum
    >>> best = physical_optimum([0.5, 0.3, 0.2], cell_area_m2=25e6, effort_m2=25e6)
    >>> round(best.pos, 4), best.coverage.round(3).tolist()
    (0.4015, [0.825, 0.175, 0.0])
    """
    entry = detection_law(law)
    law = entry.name
    m = np.asarray(prior, dtype=float)
    if m.size == 0 or not np.all(np.isfinite(m)) or np.any(m < 0):
        raise ConfigError("prior", "array", "finite cell masses >= 0")
    effort = check_positive("effort_m2", effort_m2, allow_zero=True)
    area = np.broadcast_to(np.asarray(cell_area_m2, dtype=float), m.shape)
    if np.any(area <= 0):
        raise ConfigError("cell_area_m2", "array", "cell areas > 0")
    density = m / area
    if effort == 0 or not np.any(m > 0):
        return Bound(0.0, np.zeros_like(m), float(density.max(initial=0)), effort, law)
    if entry.optimal_coverage is None:  # POD linear up to saturation: densest cells first
        order = np.argsort(-density, axis=None, kind="stable")
        a = area.ravel()[order]
        filled = np.cumsum(a)
        cov = np.zeros(m.size)
        full = filled <= effort
        cov[order[full]] = 1.0
        k = int(full.sum())
        if k < m.size:
            cov[order[k]] = (effort - (filled[k - 1] if k else 0.0)) / a[k]
        cov_map = cov.reshape(m.shape)
        return Bound(
            float(np.sum(m * cov_map)),
            cov_map,
            float(density.ravel()[order[min(k, m.size - 1)]]),
            effort,
            law,
        )
    # root of spent(log lambda) = effort (Brent's method): spent effort decreases monotonically
    # in lambda, from above the effort at ``lo`` to 0 above the densest cell's density
    pos_cells = density > 0
    d, a = density[pos_cells], area[pos_cells]

    def excess(mu: float) -> float:
        return float(np.sum(a * _coverage_at(np.exp(mu), d, entry))) - effort

    lo = np.log(d.min()) - 60.0
    hi = np.log(d.max()) + 1.0  # every cell's KKT coverage is 0 there: excess = -effort < 0
    mu = lo if excess(lo) <= 0 else brentq(excess, lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)
    lam = np.exp(mu)
    cov = _coverage_at(lam, density, entry)
    spent = float(np.sum(area * cov))
    step = 1e-12
    while spent <= 0:  # an effort below the rounding of log(lambda): the densest cells only
        cov = _coverage_at(np.exp(mu - step), density, entry)
        spent = float(np.sum(area * cov))
        step *= 10.0
    cov = cov * (effort / spent)  # spend exactly the effort (removes the root's rounding)
    value = float(np.sum(m * pod_from_coverage(cov, law)))
    return Bound(value, cov, float(lam), effort, law)


# ---------------------------------------------------------------- the environment's limits


def sensing_time_s(endurance_s: float, dt_s: float, horizon_steps: int) -> float:
    """Longest time a UAV of the environment can sense: ``dt`` x the steps it can fly.

    :func:`poc_env.sim.core.step` moves (and sweeps with) every UAV that is flying at the start
    of a step; its compiled bookkeeping adds ``dt`` to the flight time after the step and crashes
    the UAV once that reaches the endurance T (eq. 17); landing only ends a flight earlier, and no
    step runs after the horizon. This replays the same float additions, so the count is exact
    even when T / dt is not an integer (the UAV then senses ``ceil(T / dt)`` steps, a little
    more than T).
    """
    elapsed, done = 0.0, 0
    while done < horizon_steps:  # sequential sums (np.add.accumulate), in chunks
        n = min(1 << 16, horizon_steps - done)
        acc = np.cumsum(np.concatenate(([elapsed], np.full(n, float(dt_s)))))[1:]
        hit = np.flatnonzero(acc >= endurance_s)
        if hit.size:
            return float((done + int(hit[0]) + 1) * dt_s)
        elapsed, done = float(acc[-1]), done + n
    return float(horizon_steps * dt_s)


@dataclass(frozen=True)
class EnvLimits:
    """What the environment lets each UAV do at most (see :func:`env_limits`)."""

    #: (n, 2) take-off positions (every episode starts there).
    takeoff_m: np.ndarray
    #: (n, 2) landing positions.
    landing_m: np.ndarray
    #: the largest speed, ``uav.max_speed`` (m/s).
    speed_mps: float
    #: effort rate ``W v_max`` of one UAV (m^2/s).
    rate_m2_s: float
    #: :func:`sensing_time_s` (s), the same for every UAV.
    time_s: float
    #: sweep width W (m).
    sweep_width_m: float
    #: farthest distance between a point and the track that detected it (m): definite range
    #: W / 2, inverse cube the lateral cut-off; 0 for laws whose effort and detection share a
    #: cell (exponential: a step detects in a cell only through its length inside that cell).
    spill_m: float
    law: str

    @property
    def effort_m2(self) -> float:
        """The plain bound's effort: every UAV sweeping at v_max for its whole sensing time."""
        return float(len(self.takeoff_m) * self.rate_m2_s * self.time_s)


def field_key(takeoff_m, landing_m) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The airfield of a UAV: its take-off and landing points to the millimetre. UAVs of equal
    keys share a field (the bounds' and the planners' one rule for "field-mates")."""
    return (
        tuple(float(v) for v in np.round(np.asarray(takeoff_m, dtype=float), 3)),
        tuple(float(v) for v in np.round(np.asarray(landing_m, dtype=float), 3)),
    )


def env_limits(scenario: Scenario) -> EnvLimits:
    """The environment's limits for ``scenario`` (a :class:`poc_env.config.Scenario`)."""
    sc = scenario
    entry = detection_law(sc.sensor.law)
    w = sc.sensor.sweep_width_m
    cutoff = sc.sensor.cutoff_sweep_widths * w
    spill = 0.0 if entry.needs_cell else float(entry.reach(w, cutoff, sc.map.cell_m))
    v = sc.uav.max_speed_mps
    return EnvLimits(
        takeoff_m=np.asarray(sc.takeoff_m, dtype=float).reshape(-1, 2),
        landing_m=np.asarray(sc.landing_m, dtype=float).reshape(-1, 2),
        speed_mps=float(v),
        rate_m2_s=float(w * v),
        time_s=sensing_time_s(sc.uav.endurance_s, sc.episode.dt_s, sc.horizon_steps),
        sweep_width_m=float(w),
        spill_m=spill,
        law=entry.name,
    )


def zone_reach(scenario: Scenario, prior) -> tuple[np.ndarray, np.ndarray]:
    """The cell masses and cell areas a flight keeping eq. 20 can detect (module docstring,
    "With no-fly zones"): ``(s m, s a)`` with ``s`` the share of each cell's sample points
    within the detection law's reach of the zones' outside
    (:func:`poc_env.theory.regions.reach_share`); cells with ``s = 0`` keep their
    area (and no mass). Without zones: ``(prior, cell area)`` unchanged, so every bound on
    them is the zone-free bound to the last digit.

    Parameters
    ----------
    scenario:
        A :class:`poc_env.config.Scenario` (its zones, sensor law, sweep width, cut-off and
        samples per cell).
    prior:
        Cell masses of the scenario's grid shape.

    Returns
    -------
    tuple of numpy.ndarray
        The masses and the areas (m^2), both of the grid's shape; pass them as ``prior`` and
        ``cell_area_m2`` to :func:`physical_optimum` or :func:`reach_optimum`.
    """
    grid = Grid.from_config(scenario.map)
    m = np.asarray(prior, dtype=float)
    if m.shape != grid.shape:
        raise ConfigError("prior", m.shape, f"an array of the grid's shape {grid.shape}")
    area = np.full(grid.shape, grid.cell_area_m2)
    polys = scenario.map.no_fly_zones_m
    if not len(polys):
        return m, area
    zones = shapely.union_all(  # as the router builds them (ZoneRouter.zones)
        [as_polygon(z, f"no_fly_zones[{i}]") for i, z in enumerate(polys)]
    )
    sen = scenario.sensor
    w = float(sen.sweep_width_m)
    rho = float(detection_law(sen.law).reach(w, sen.cutoff_sweep_widths * w, grid.cell_m))
    share = reach_share(zones, grid, rho, samples_per_cell=sen.samples_per_cell)
    return m * share, np.where(share > 0, area * share, area)


def honest_optimum(scenario: Scenario, prior, sorties: int = 1) -> Bound:
    """The plain bound with the environment's limits: :func:`physical_optimum` for the effort
    of every UAV sweeping at ``max_speed`` for its whole sensing time (:func:`env_limits`).

    ``sorties = k``: the bound on the cumulative POS of ``k`` sorties of the fleet on
    ``prior`` (``poc-env replan``), the same bound for ``k`` times the effort (every UAV with
    ``k`` times the endurance). Why it holds: each sortie's effort is at most ``Z`` (the
    argument above, per sortie), so the sorties together spend at most ``k Z``; the belief
    update of eq. 14 is multiplicative (a point's non-detection probabilities multiply, and so
    do the cells' ``1 - POD`` under the exponential law; the definite range detects the union of
    the swept areas), so the cumulative POS of the sorties is the POS of one flight made of all
    their tracks, whose effort is at most ``k Z``; and the allocation bound holds for any flight
    of that effort (with the same caveat for the inverse-cube law as above). Take-offs,
    landings and turnarounds between sorties only use up effort, so the bound is not tight.
    """
    if isinstance(sorties, bool) or not isinstance(sorties, int) or sorties < 1:
        raise ConfigError("sorties", sorties, "an integer >= 1")
    lim = env_limits(scenario)
    grid = Grid.from_config(scenario.map)
    return physical_optimum(prior, grid.cell_area_m2, sorties * lim.effort_m2, lim.law)


# ------------------------------------------------------------------- the reach-aware bound


@dataclass(frozen=True)
class ReachBound:
    """Result of :func:`reach_optimum`.

    ``pos`` is the value of the allocation found; ``upper`` the dual (Lagrangian) value at the
    allocation's marginal returns, a certified upper bound on the problem's optimum
    (``upper - pos`` is the optimality gap). Report ``upper``.
    """

    pos: float
    upper: float
    coverage: np.ndarray
    effort_m2: float
    law: str

    @property
    def gap(self) -> float:
        return self.upper - self.pos


def cell_distances(grid: Grid, points) -> np.ndarray:
    """(k, ny, nx) distance from each of ``points`` (k, 2) to the nearest point of each cell."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    ox, oy = grid.origin_m
    c = grid.cell_m
    x0 = ox + c * np.arange(grid.nx)
    y0 = oy + c * np.arange(grid.ny)
    dx = np.maximum(np.maximum(x0[None] - p[:, :1], p[:, :1] - (x0[None] + c)), 0.0)
    dy = np.maximum(np.maximum(y0[None] - p[:, 1:], p[:, 1:] - (y0[None] + c)), 0.0)
    return np.hypot(dy[:, :, None], dx[:, None, :])


def _capacity(rate: np.ndarray, budget: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Capacity ``R(t) = sum_k rate_k (budget_k - t)^+`` of one group (hinges ``k``) at ``t``."""
    return np.sum(rate[:, None] * np.maximum(budget[:, None] - t[None, :], 0.0), axis=0)


def _rank(tau: np.ndarray, rate: np.ndarray, budget: np.ndarray, cells: np.ndarray) -> float:
    """g(A) = sum_g R_g(min_{j in A} tau_gj) for the cells ``A`` (indices)."""
    if cells.size == 0:
        return 0.0
    near = tau[:, cells].min(axis=1)
    return float(sum(_capacity(rate[g], budget[g], near[g : g + 1])[0] for g in range(len(near))))


def _most_violated(
    tau: np.ndarray, rate: np.ndarray, budget: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, float]:
    """min over cell sets A of g(A) - x(A), and a minimiser (boolean mask).

    g(A) depends on A only through the nearest cell of A per group, and x >= 0, so a minimiser
    is among the "upper sets" {j : tau_gj >= t_g for every g} with each t_g a value of tau_g: for
    one group a scan of the sorted values, for two a table of suffix sums over both ranks.
    """
    keys = []
    caps = []
    for g in range(tau.shape[0]):
        u, inv = np.unique(tau[g], return_inverse=True)
        keys.append(inv)
        caps.append(_capacity(rate[g], budget[g], u))
    if len(keys) == 1:
        s = np.bincount(keys[0], weights=x, minlength=caps[0].size)[::-1].cumsum()[::-1]
        val = caps[0] - s
        k = int(np.argmin(val))
        return keys[0] >= k, float(val[k])
    # two groups: val[a, b] = cap0[a] + cap1[b] - x({key0 >= a, key1 >= b}), by blocks of rows
    # (from the last row down; ``carry`` is the suffix sum of the rows below the block)
    k1, k2 = caps[0].size, caps[1].size
    block = max(1, min(k1, _TABLE_CELLS // k2))
    carry = np.zeros(k2)
    best, where = np.inf, (0, 0)
    for hi in range(k1, 0, -block):
        lo = max(0, hi - block)
        sel = (keys[0] >= lo) & (keys[0] < hi)
        table = np.zeros((hi - lo, k2))
        np.add.at(table, (keys[0][sel] - lo, keys[1][sel]), x[sel])
        suffix = table[::-1, ::-1].cumsum(axis=0).cumsum(axis=1)[::-1, ::-1] + carry
        val = caps[0][lo:hi, None] + caps[1][None, :] - suffix
        k = int(np.argmin(val))
        if val.flat[k] < best:
            best, where = float(val.flat[k]), (lo + k // k2, k % k2)
        carry = suffix[0]
    a, b = where
    return (keys[0] >= a) & (keys[1] >= b), best


#: Cells of one block of the two-group threshold table (memory ~ 8 bytes each).
_TABLE_CELLS = 1 << 22
#: Above this many threshold pairs, two transit rows are merged into one (a valid relaxation)
#: so that the search for the most violated set stays fast.
_MAX_PAIRS = 50_000_000


def _merge_groups(tau, rate, budget):
    """Groups as (transit row, hinge rates, hinge budgets). Groups with the same transit row
    share one capacity function (exact: their hinges add). Beyond two distinct rows, the later
    groups are merged into the second with the smaller transit of the two (a relaxation: a cell
    set's capacity can only grow, the total effort stays the same; the bound stays valid,
    looser); on grids of more than ``sqrt(_MAX_PAIRS)`` cells, two rows are merged into one."""
    groups = {}  # dict[bytes, list]: transit row -> its groups
    for g in range(tau.shape[0]):
        key = tau[g].tobytes()
        if key in groups:
            groups[key][1].append(rate[g])
            groups[key][2].append(budget[g])
        else:
            groups[key] = [tau[g].copy(), [rate[g]], [budget[g]]]
    items = list(groups.values())
    limit = 1 if tau.shape[1] ** 2 > _MAX_PAIRS else 2
    while len(items) > limit:
        t1, r1, b1 = items.pop()
        t0, r0, b0 = items[-1]
        items[-1] = [np.minimum(t0, t1), r0 + r1, b0 + b1]
    return (
        np.array([i[0] for i in items]),
        [np.array(i[1], dtype=float) for i in items],
        [np.array(i[2], dtype=float) for i in items],
    )


def reach_optimum(
    prior, cell_area_m2, transit_s, rate_m2_s, budget_s, law: str = "inverse_cube"
) -> ReachBound:
    """Most POS reachable when group ``g`` of searchers sweeps ``rate_m2_s[g]`` m^2/s for
    ``budget_s[g]`` s and needs ``transit_s[g]`` (shape ``(G, *prior.shape)``) to reach each cell
    (see the module docstring for the model and the proof of validity).

    Maximises ``sum_j m_j POD(C_j)`` over ``C >= 0`` such that, for every group g and time t,
    the effort of g in cells with transit >= t is at most ``rate_g (budget_g - t)^+``. The
    feasible efforts ``x_j = a_j C_j`` form a polymatroid of rank
    ``g(A) = sum_g rate_g (budget_g - min_{j in A} transit_gj)^+``; the objective is separable
    and concave, so the decomposition algorithm (Fujishige, *Submodular functions and
    optimization*, §8.2) is exact: spend the whole rank by water-filling (:func:`physical_optimum`);
    if some set A holds more effort than g(A), the optimum fills A exactly, so solve A with rank
    g restricted to it and the rest with the contracted rank g(A u B) - g(A) (the same form with
    ``budget_g`` lowered to A's nearest transit), recursively. The returned ``upper`` is the
    Lagrangian dual at the allocation's marginal returns, a certificate.
    """
    entry = detection_law(law)
    m = np.asarray(prior, dtype=float)
    if m.size == 0 or not np.all(np.isfinite(m)) or np.any(m < 0):
        raise ConfigError("prior", "array", "finite cell masses >= 0")
    area = np.broadcast_to(np.asarray(cell_area_m2, dtype=float), m.shape).ravel()
    if np.any(area <= 0):
        raise ConfigError("cell_area_m2", "array", "cell areas > 0")
    tau = np.asarray(transit_s, dtype=float).reshape(-1, m.size)
    rate = np.asarray(rate_m2_s, dtype=float).ravel()
    budget = np.asarray(budget_s, dtype=float).ravel()
    if not (tau.shape[0] == rate.size == budget.size) or tau.shape[0] == 0:
        raise ConfigError("transit_s", tau.shape, "one row per group, as many as rates and budgets")
    if not (np.all(np.isfinite(tau)) and np.all(tau >= 0)):
        raise ConfigError("transit_s", "array", "finite transit times >= 0")
    for name, arr in (("rate_m2_s", rate), ("budget_s", budget)):
        if not (np.all(np.isfinite(arr)) and np.all(arr >= 0)):
            raise ConfigError(name, "array", "finite values >= 0")
    mf = m.ravel()
    tau, rates, budgets = _merge_groups(tau, rate, budget)
    x = np.zeros(m.size)
    level = np.zeros(m.size)  # the multiplier of the subproblem that settled each cell
    reach = np.zeros(m.size, dtype=bool)
    for g in range(tau.shape[0]):
        reach |= _capacity(rates[g], budgets[g], tau[g]) > 0
    reach &= mf > 0
    stack = [(np.flatnonzero(reach), budgets)]
    while stack:
        cells, bud = stack.pop()
        total = _rank(tau, rates, bud, cells)
        if cells.size == 0 or total <= 0:
            continue
        xi = area[cells] * physical_optimum(mf[cells], area[cells], total, entry.name).coverage
        mask, val = _most_violated(tau[:, cells], rates, bud, xi)
        if val >= -1e-12 * total or mask.all() or not mask.any():
            x[cells] = xi
            unfilled = xi < area[cells] * (1.0 - 1e-12)
            level[cells] = np.max(mf[cells][unfilled] / area[cells][unfilled], initial=0.0)
            continue
        inner = cells[mask]
        stack.append((inner, bud))
        near = tau[:, inner].min(axis=1)
        stack.append((cells[~mask], [np.minimum(b, a) for b, a in zip(bud, near, strict=True)]))
    cov = x / area
    pos = float(np.sum(mf * entry.pod(cov)))
    # dual certificate: for any feasible y, sum phi(y) <= sum phi(x) + p.(y - x) (concavity),
    # and max_y p.y over the polymatroid is its greedy value sum_g rate_g int_0^budget max p dt
    # (definite range: at C = 1 any slope in [0, m/a] is a supergradient; the settling
    # subproblem's multiplier -- its densest unfilled cell -- makes the certificate tight)
    if entry.optimal_coverage is None:
        p = np.minimum(mf / area, level)
    else:
        p = mf / area * entry.pod_slope(cov)
    best = 0.0
    for g in range(tau.shape[0]):
        order = np.argsort(tau[g], kind="stable")
        run = np.maximum.accumulate(p[order])
        # int_0^inf max_{tau_j <= t} p_j (-R_g'(t)) dt, R_g piecewise linear: on each interval
        # between consecutive transits the running maximum is constant
        t = tau[g][order]
        cap = _capacity(rates[g], budgets[g], t)
        best += float(np.sum(run * (cap - np.append(cap[1:], 0.0))))
    upper = max(pos, pos - float(p @ x) + best)
    return ReachBound(pos, upper, cov.reshape(m.shape), float(x.sum()), entry.name)


#: most partitions of the fields into blocks of at most two that :func:`rule_bound` tries.
MAX_PARTITIONS = 32


@dataclass(frozen=True)
class RuleBound(ReachBound):
    """Result of :func:`rule_bound`: a :class:`ReachBound` (report ``upper``) that says how it
    was obtained. ``how``: ``"exact"`` (one relaxation, exact: at most two airfields),
    ``"merged"`` (the fleet's relaxation with merged airfields was the least), ``"first=F"``
    (the relaxation with field ``F`` first) or ``"blocks=(F, F)+(F,)"`` (the sum over blocks of
    fields; ``pos``, ``coverage`` and ``effort_m2`` are then the blocks' sums, and ``pos`` is
    not the POS of that ``coverage``); fields ``F`` numbered in order of first appearance in
    the fleet. ``merged``: the fleet's relaxation alone (``upper`` of the merged airfields)."""

    how: str
    merged: float


def _pairings(items: list[int]) -> list[list[tuple[int, ...]]]:
    """Partitions of ``items`` into pairs (and one single when odd), in a fixed order."""
    if len(items) <= 1:
        return [[tuple(items)]] if items else [[]]
    first, rest = items[0], items[1:]
    out: list[list[tuple[int, ...]]] = []
    if len(items) % 2:  # first may be the single
        out += [[(first,), *p] for p in _pairings(rest)]
    for i, other in enumerate(rest):
        left = rest[:i] + rest[i + 1 :]
        if len(left) % 2 and len(items) % 2 == 0:
            continue
        out += [[(first, other), *p] for p in _pairings(left)]
    return [p for p in out if sum(len(b) == 1 for b in p) <= len(items) % 2]


def rule_bound(scenario: Scenario, prior, spill_m: float | None = None) -> RuleBound:
    """The rule-aware bound of ``scenario`` on ``prior``: the reach-aware bound for a flight
    that keeps the plan rules -- out and searching at ``v_max``, back on the ground within the
    usable endurance 0.85 T (eq. 18), the way home flown at the cruise speed ``v_c`` (eq. 18's
    return rule budgets it at ``v_c``, :func:`poc_env.agents.planning.flight_rules.plan_speeds`).

    *Claim:* the track a UAV flies at points at least ``d_o`` from its take-off field and
    ``d_l`` from its landing field is at most ``v_max (T_u - d_o / v_max - d_l / v_c)^+``.
    *Proof:* it reaches such a point no earlier than ``d_o / v_max`` and must leave the last
    one at least ``d_l / v_c`` before ``T_u`` to land in time; in between it flies at most
    ``v_max`` per second. So the transit to cell j is ``tau_j = (d_o - rho)^+ / v_max +
    (d_l - rho)^+ / v_c`` (``rho`` the detection spill, as in :func:`reach_bound`) with budget
    ``T_u`` and rate ``W v_max``, solved by :func:`reach_optimum`. With ``v_c = v_max`` it is
    :func:`reach_bound` with ``round_trip=True``; a slower way home only lowers it. Where the
    episode ends first (its sensing time, :func:`env_limits`, below ``T_u``: a short
    ``episode.horizon_steps``), the track sensed by then is also at most ``v_max (t_sense -
    d_o / v_max)^+`` and the relaxation is the least of the two. Plans that
    keep the rules (the allocation planner's, the greedy rectangles') stay below it; the
    environment itself lets a UAV sense until T, so :func:`reach_bound` stays the bound of any
    policy.

    ``spill_m`` replaces ``rho`` (None: the environment's). ``spill_m=0`` bounds the *planned*
    POS of the planners' coverage model (:func:`poc_env.agents.planning.flight_rules.
    path_coverage`: effort only in the cells the track crosses), not the flown one.

    *More than two airfields.* :func:`reach_optimum` is exact for at most two distinct transit
    rows (airfields); beyond two it merges the later fields into the second with the smaller
    transit of the two (valid, loose: a UAV is credited the nearer field's reach), and on grids
    of more than ``sqrt(_MAX_PAIRS)`` cells it merges two into one. There the result is the
    least of these valid bounds of the same quantity (:attr:`RuleBound.how` says which):

    * the relaxation with each field first in the fleet's order (the merge differs);
    * for each partition of the fields into blocks of at most two (at most
      :data:`MAX_PARTITIONS`), and for the partition into single fields, the sum over the
      blocks of the relaxation of the block's UAVs alone.

    *Why the sum is an upper bound.* Any fleet's efforts split by field as ``x = sum_b x_b``,
    ``x_b`` in block ``b``'s feasible set (the polymatroid above for its UAVs). The objective
    ``phi(x) = sum_j m_j POD(x_j / a_j)`` is separable, concave in each ``x_j >= 0`` and
    ``phi(0) = 0``, so it is subadditive: ``phi(x) <= sum_b phi(x_b) <= sum_b max_b phi``.
    With one field, or two on a grid where the relaxation is exact, the result is the
    relaxation itself (bit for bit). On ``large_400`` (three fields) this takes ~10 solves
    instead of one.
    """
    lim = env_limits(scenario)
    rho = lim.spill_m if spill_m is None else float(spill_m)
    if not (rho >= 0 and np.isfinite(rho)):
        raise ConfigError("spill_m", spill_m, "a distance >= 0 m, or None for the environment's")
    full = _rule_relaxation(scenario, prior, rho)
    groups = list(scenario.fleet)
    # the field (take-off, landing) of each fleet group, in order of first appearance
    keys: list[tuple] = []
    field_of: list[int] = []
    k = 0
    for g in groups:
        key = field_key(lim.takeoff_m[k], lim.landing_m[k])
        if key not in keys:
            keys.append(key)
        field_of.append(keys.index(key))
        k += g.count
    n = len(keys)
    grid = Grid.from_config(scenario.map)
    exact = (grid.nx * grid.ny) ** 2 <= _MAX_PAIRS
    if n == 1 or (n == 2 and exact):
        return RuleBound(full.pos, full.upper, full.coverage, full.effort_m2, full.law, "exact",
                         full.upper)  # fmt: skip

    def sub(fields: tuple[int, ...]) -> Scenario:
        fleet = tuple(g for f in fields for g, fo in zip(groups, field_of, strict=True) if fo == f)
        return dataclasses.replace(scenario, fleet=fleet)

    best, how = full, "merged"
    for f in range(n):
        order = (f, *(x for x in range(n) if x != f))
        one = sub(order)
        if one.fleet == scenario.fleet:
            continue  # the relaxation above
        val = _rule_relaxation(one, prior, rho)
        if val.upper < best.upper:
            best, how = val, f"first={f}"
    cache: dict[tuple[int, ...], ReachBound] = {}
    singles: list[tuple[int, ...]] = [(f,) for f in range(n)]
    for part in [*_pairings(list(range(n)))[:MAX_PARTITIONS], singles]:
        for block in part:
            if block not in cache:
                cache[block] = _rule_relaxation(sub(block), prior, rho)
        total = sum(cache[b].upper for b in part)
        if total < best.upper:
            how = "blocks=" + "+".join(str(b) for b in part)
            best = ReachBound(
                float(sum(cache[b].pos for b in part)), float(total),
                sum((cache[b].coverage for b in part), np.zeros_like(full.coverage)),
                float(sum(cache[b].effort_m2 for b in part)), full.law,
            )  # fmt: skip
    return RuleBound(best.pos, best.upper, best.coverage, best.effort_m2, best.law, how,
                     full.upper)  # fmt: skip


def _rule_relaxation(scenario: Scenario, prior, rho: float) -> ReachBound:
    """:func:`rule_bound`'s relaxation for ``scenario``'s whole fleet: one :func:`reach_optimum`
    (exact for at most two airfields, merged beyond, see :func:`_merge_groups`)."""
    lim = env_limits(scenario)
    grid = Grid.from_config(scenario.map)
    v_home = min(float(scenario.uav.cruise_speed_mps), lim.speed_mps)
    out = np.maximum(cell_distances(grid, lim.takeoff_m) - rho, 0.0) / lim.speed_mps
    home = np.maximum(cell_distances(grid, lim.landing_m) - rho, 0.0) / v_home
    n = len(lim.takeoff_m)
    budget = scenario.uav.usable_endurance_s
    rate = np.full(n, lim.rate_m2_s)
    rule = reach_optimum(prior, grid.cell_area_m2, out + home, rate, np.full(n, budget), lim.law)
    if lim.time_s >= budget:
        return rule
    # an episode that ends before 0.85 T (a short horizon): what a flight senses by then at
    # points d_o from its take-off field is at most v_max (t_sense - (d_o - rho)^+ / v_max)^+,
    # whatever its way home; the least of the two relaxations bounds it
    cut = reach_optimum(prior, grid.cell_area_m2, out, rate, np.full(n, lim.time_s), lim.law)
    return cut if cut.upper < rule.upper else rule


def reach_bound(scenario: Scenario, prior, round_trip: bool = False) -> ReachBound:
    """The reach-aware bound of ``scenario`` on ``prior`` (see the module docstring).

    Default (the environment): each UAV sweeps at most ``W v_max`` from its take-off field for
    its sensing time (:func:`env_limits`) and need not come back (the environment lets it sense
    until it crashes at T); the transit to cell j is ``(d(take-off, cell j) - spill)^+ / v_max``.
    ``round_trip=True`` (a plan that must land): the budget is the usable endurance 0.85 T and
    the transit ``2 (min(d(take-off, j), d(landing, j)) - spill)^+ / v_max``.
    """
    lim = env_limits(scenario)
    grid = Grid.from_config(scenario.map)
    d = cell_distances(grid, lim.takeoff_m)
    budget = lim.time_s
    if round_trip:
        d = 2.0 * np.minimum(d, cell_distances(grid, lim.landing_m))
        budget = scenario.uav.usable_endurance_s
    spill = (2.0 if round_trip else 1.0) * lim.spill_m
    tau = np.maximum(d - spill, 0.0) / lim.speed_mps
    n = len(lim.takeoff_m)
    return reach_optimum(
        prior, grid.cell_area_m2, tau, np.full(n, lim.rate_m2_s), np.full(n, budget), lim.law
    )
