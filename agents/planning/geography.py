"""The geography every plan records: its CRS, the UAV's flight, the operating area, the no-fly
zones, the airfields, the terrain (a DEM resampled onto the scenario) and the environment's two
bounds (the optional fields of
:mod:`poc_env.agents.mission.plan`), one implementation for the DE planner
(:mod:`~poc_env.agents.planning.planner`), the allocation planner
(:mod:`~poc_env.agents.planning.allocation`) and region surveys
(:mod:`~poc_env.agents.planning.survey`).
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import numpy as np

from poc_env.agents.mission.crs import make_crs
from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.geometry import polyline_length, zone_crossed


def scenario_crs(
    sc: Scenario, origin_deg: Any, projection: str, zone: int | None
) -> dict[str, Any] | None:
    """The plan's CRS: from ``origin_deg`` (``--origin``), else from the scenario's
    ``map.origin_deg``/``projection``/``utm_zone``; both given must name the same origin."""
    m = sc.map
    if origin_deg is None:
        if m.origin_deg is None:
            return None
        return make_crs(m.projection, m.origin_deg, zone=m.utm_zone)
    crs = make_crs(projection, origin_deg, zone=zone)
    if m.origin_deg is not None and tuple(crs["origin_deg"]) != tuple(m.origin_deg):
        raise ConfigError(
            "origin", origin_deg, f"nothing (the scenario's map.origin_deg "
            f"{list(m.origin_deg)} is used) or that same origin",
        )  # fmt: skip
    return crs


def zone_prior(sc: Scenario, prior: np.ndarray, router: Any, zone_reach: float | None = None):
    """The prior as the planners count it on a map with no-fly zones (eq. 20): each cell's
    mass times its share within ``zone_reach`` sweep widths of the keep-out area's outside
    (:meth:`~poc_env.sim.routing.ZoneRouter.reach_share`), the one place of that discount for
    the allocation, greedy rectangle and DE planners (i24-smallfix; the greedy and DE planners
    had W/2 written in).

    Parameters
    ----------
    sc : Scenario
        Its map (the grid) and its sensor's sweep width W.
    prior : ndarray
        The cell masses, of the grid's shape.
    router : ZoneRouter
        The scenario's router; without zones (``router.active`` false) ``prior`` is returned.
    zone_reach : float, optional
        The lateral reach in sweep widths; default
        :attr:`~poc_env.agents.planning.options.PlanOptions.zone_reach` (0.5: W/2, the eq. 10
        model).

    Returns
    -------
    ndarray
        The discounted prior (``prior`` itself without zones).
    """
    from poc_env.agents.planning.options import PlanOptions
    from poc_env.theory.probability_map import Grid

    if not router.active:
        return prior
    reach = PlanOptions.zone_reach if zone_reach is None else zone_reach
    grid = Grid.from_config(sc.map)
    return prior * router.reach_share(grid, reach_m=reach * sc.sensor.sweep_width_m)


def probability(value: float) -> float:
    """``value`` as a probability of plan.json: clamped to [0, 1] (sums of cell masses round
    to ``1 + 2e-16``; the export checks [0, 1])."""
    return float(min(max(float(value), 0.0), 1.0))


def found_scores(prior: np.ndarray, pos: float, found: np.ndarray) -> dict[str, float]:
    """A UAV's ``pos``, ``poc`` and ``pod`` of plan.json from what its flight path finds
    (:func:`~poc_env.agents.planning.flight_rules.sampled_sweep`'s POS and mass per cell):
    POC the ``prior`` mass of the cells it finds anything in, POD = POS / POC (§3.1.6), each a
    :func:`probability`."""
    poc = float(np.sum(prior * (found > 0)))
    return {
        "pod": probability(pos / poc) if poc > 0 else 0.0,  # sums round to 1 + 2e-16
        "poc": probability(poc),
        "pos": probability(pos),
    }


def _check_extent(sc: Scenario, area: tuple[float, float, float, float]) -> None:
    """ConfigError naming the scenario when eq. 20's operating area ``area`` reaches past the
    points plan.json holds (:data:`~poc_env.agents.mission.plan.MAX_EXTENT_M` from the map
    origin; a scenario allows more), before a plan is made that could not be written."""
    from poc_env.agents.mission.plan import MAX_EXTENT_M

    if max(abs(v) for v in area) <= MAX_EXTENT_M:
        return
    margin = sc.episode.boundary_margin_m
    core = max(abs(v) for v in area) - margin  # the map and airfields' box
    lim = f"within +-{MAX_EXTENT_M / 1e3:g} km of the map origin (the points a plan.json holds)"
    if core <= MAX_EXTENT_M:
        raise ConfigError(
            "episode.boundary_margin_km", margin / 1e3,
            f"at most {(MAX_EXTENT_M - core) / 1e3:.4g} km for a plan here: the operating area "
            f"(the map and airfields' box grown by it) must lie {lim}",
        )  # fmt: skip
    raise ConfigError(
        "map", [round(v / 1e3, 3) for v in area],
        f"a map and airfields {lim}, for a plan (the environment takes them farther out)",
    )  # fmt: skip


def plan_geography(sc: Scenario, prior: np.ndarray, crs: dict[str, Any] | None) -> dict[str, Any]:
    """The optional plan.json fields an export reads: flight, area, zones, airfields, crs, and
    the two bounds of the plan's prior (``bounds``: :func:`~poc_env.theory.bound.honest_optimum`
    and :func:`~poc_env.theory.bound.reach_bound`'s certified upper value) and the rule-aware
    bound (``bound_rule``: :func:`~poc_env.theory.bound.rule_bound`'s certified upper value,
    for the plan's whole endurance whatever ``episode.horizon_steps`` cuts the episodes to)."""
    from poc_env.sim.core import make_params
    from poc_env.theory.bound import honest_optimum, reach_bound, rule_bound

    x0, y0, x1, y1 = (float(v) for v in make_params(sc, prior).bounds)  # eq. 20's boundary
    _check_extent(sc, (x0, y0, x1, y1))
    out: dict[str, Any] = {
        "flight": {
            "cruise_speed_mps": sc.uav.cruise_speed_mps,
            "search_speed_mps": sc.uav.search_speed_mps,
            "altitude_m": sc.uav.cruise_altitude_m,
            "max_altitude_m": sc.uav.max_altitude_m,
        },
        "operating_area_m": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
        "no_fly_zones_m": [[[float(v) for v in p] for p in z] for z in sc.map.no_fly_zones_m],
        "airfields": [
            {"name": a.name, "position_m": [float(v) for v in a.position_m]} for a in sc.airfields
        ],
    }
    if sc.map.no_fly_names:
        out["no_fly_zone_names"] = list(sc.map.no_fly_names)
    if float(np.sum(prior)) > 0:  # an empty prior (a route plan's stated reason) has no bounds
        out["bounds"] = {  # probabilities: rounding may give 1 + 2e-16
            "honest": probability(honest_optimum(sc, prior).pos),
            "reach": probability(reach_bound(sc, prior).upper),
        }
        # the rule-aware bound (plan rules: back by 0.85 T, home at v_c) beside them; its own
        # field, as plan.json's ``bounds`` holds the environment's two. The plan's: the
        # planners plan the endurance, so a short episode.horizon_steps (the environment's
        # truncation) does not cut it (config-audit: it did, far below the planned POS_C)
        whole = dataclasses.replace(sc.episode, horizon_steps=None)
        out["bound_rule"] = probability(
            rule_bound(dataclasses.replace(sc, episode=whole), prior).upper
        )
    if crs is not None:
        out["crs"] = crs
    if sc.terrain.given:  # the DEM resampled onto the scenario: exports need no DEM
        from poc_env.agents.mission.terrain import load_terrain, terrain_record

        t = load_terrain(sc)
        assert t is not None
        out["terrain"] = terrain_record(t)
    return out


#: Halvings of the last leg :func:`fit_orbits` keeps flying: within 1/256 of its length.
BISECT_STEPS = 8


def fit_orbits(plan: dict[str, Any], sc: Scenario, prior: np.ndarray) -> dict[str, Any]:
    """``plan`` with time left for each UAV's orbits (issue 24, i24-orbitfit): a UAV whose
    take-off climb spiral or descent orbit (:func:`poc_env.agents.mission.terrain.plan_profiles`,
    the export's own profile) takes its flight beyond eq. 18's 0.85 T, though the flight alone
    fits, loses its last waypoints by the allocation's trim rule
    (:func:`poc_env.agents.planning.refine.route_fits`, the budget 0.85 T less the orbits' time,
    the orbits read again after each cut, since the last waypoint places the approach) until
    flight + orbits fit; then the plan's POS is scored again by the allocation planner's own
    scorer (:func:`poc_env.agents.planning.allocation.sampled_sweep`, eq. 14 along every
    flight path; the DE plan's POS of a trimmed plan too, since its rectangles are no longer
    flown whole) and the trim recorded in ``orbit_fit``. A trimmed DE plan's metadata of the
    untrimmed decision is moved there, not left stale (i24-missionfix): a trimmed UAV's
    ``rectangle`` and ``flown_rectangle`` (``null`` in the plan; its search is drawn from the
    ``areas_m`` its kept lines sweep, as an allocation plan's) and the plan's ``x`` and
    ``objective`` (the optimiser's, of routes no longer flown; the allocation's ``objective``
    is recomputed, ``-POS_C``). ``upper_bound`` (the bound of the untrimmed effort) is kept:
    still an upper bound. Nothing changes (the same object is returned) without terrain or
    when every UAV's orbits fit.

    Parameters
    ----------
    plan : dict
        A schema-2 plan of :func:`poc_env.agents.planning.planner.make_plan` (either planner).
    sc : Scenario
        The scenario planned (speeds, turn rate, sensor, grid).
    prior : numpy.ndarray
        The map's prior the plan was scored on (the whole map, zones included).
    """
    from poc_env.agents.mission.terrain import profiles_once

    # each unchanged UAV's profile computed once; its warnings (a steep final glide) are the
    # plan's, said once by check_terrain's own reading of the fitted plan, not here as well
    with profiles_once(), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return _fit_orbits(plan, sc, prior)


def _fit_orbits(plan: dict[str, Any], sc: Scenario, prior: np.ndarray) -> dict[str, Any]:
    """:func:`fit_orbits`, within :func:`~poc_env.agents.mission.terrain.profiles_once`."""
    from poc_env.agents.mission.terrain import orbit_time_s, plan_profiles

    profs = plan_profiles(plan, charge=False)
    if profs is None:
        return plan
    usable = sc.uav.usable_endurance_s
    eps = 1e-6

    def over(u: dict[str, Any], p: Any) -> bool:
        f = float(u["flight_time_s"])
        return f <= usable + eps and f + orbit_time_s(p) > usable + eps

    bad = [k for k, (u, p) in enumerate(zip(plan["uavs"], profs)) if over(u, p)]
    if not bad:
        return plan
    import shapely

    from poc_env.agents.planning.flight_rules import Speeds, _swept_areas, reserve_s, sampled_sweep
    from poc_env.agents.planning.refine import route_fits, route_time
    from poc_env.sim.core import takeoff_heading
    from poc_env.theory.probability_map import Grid

    grid = Grid.from_config(sc.map)
    u_cfg = sc.uav
    if plan.get("speeds_mps"):  # the allocation's (plan_speeds), with its take-off headings
        v = Speeds(**plan["speeds_mps"])
        heads: list[Any] = takeoff_heading(
            grid.bounds, np.array([u["takeoff_m"] for u in plan["uavs"]])
        ).tolist()
    else:  # the DE plan's eq. 17 (planner._Speeds), no take-off heading
        v = Speeds(u_cfg.cruise_speed_mps, u_cfg.search_speed_mps, u_cfg.cruise_speed_mps)
        heads = [None] * len(plan["uavs"])
    uavs = [dict(u) for u in plan["uavs"]]
    out = {**plan, "uavs": uavs}
    dropped: dict[str, dict[str, Any]] = {}
    turn, reserve = u_cfg.max_turn_rate_rad_s, reserve_s(sc)
    zones = [shapely.Polygon(z) for z in plan.get("no_fly_zones_m") or []]

    def trial(k: int, wps: list) -> tuple[dict[str, Any], Any, bool]:
        """UAV ``k`` flying ``wps``: its record, profile, and whether flight + orbits fit
        (eq. 18 and the return rule's reserve at every waypoint, as ``_trim``'s)."""
        path = np.array([uavs[k]["takeoff_m"], *wps, uavs[k]["landing_m"]], dtype=float)
        u = {
            **uavs[k],
            "waypoints_m": [list(w) for w in wps],
            "flight_time_s": route_time(path, v, turn, heads[k]) if wps else 0.0,
            "track_length_m": polyline_length(path) if wps else 0.0,
        }
        # named plan.uavs[k] if refused; the UAVs before it read from the memo
        try:
            p = plan_profiles({**out, "uavs": [*uavs[:k], u]}, charge=False)[k]  # type: ignore[index]
        except ConfigError:  # this end of the route lands nowhere: not a fit
            return u, None, False
        mission = [*path[:-1].tolist(), p.points_m[-1].tolist(), list(u["landing_m"])]
        ok = (
            not over(u, p)
            and zone_crossed(mission, zones) is None  # the export's geofence (check_fences)
            and (not wps or route_fits(path, v, turn, usable - orbit_time_s(p), reserve, heads[k]))
        )
        return u, p, ok

    for k in bad:
        wps = [[float(a), float(b)] for a, b in uavs[k]["waypoints_m"]]
        n0 = len(wps)
        u, ok = uavs[k], False
        last, lo = None, 0.0
        while wps and not ok:  # the allocation's _trim: the last waypoints dropped
            last = wps.pop()
            u, _, ok = trial(k, wps)
        if not ok:  # no waypoint left and still over: the orbit check names it
            continue
        if last is not None:  # and the last leg flown as far as it fits (bisection)
            a = np.asarray(wps[-1] if wps else u["takeoff_m"], dtype=float)
            hi = 1.0
            for _ in range(BISECT_STEPS):
                mid = 0.5 * (lo + hi)
                q = (a + mid * (np.asarray(last) - a)).tolist()
                cand = trial(k, [*wps, q])
                if cand[2]:
                    lo, u = mid, cand[0]
                else:
                    hi = mid
            wps = u["waypoints_m"]
        uavs[k] = u
        lead = min(int(u.get("transit_waypoints", 0)), len(wps))
        legs = np.array([wps[i : i + 2] for i in range(lead, len(wps) - 1)]).reshape(-1, 2, 2)
        if "transit_waypoints" in u:
            u["transit_waypoints"] = lead
        cut: dict[str, Any] = {}
        if u.get("rectangle") is not None or u.get("flown_rectangle") is not None:
            # a DE rectangle no longer flown whole: its lines kept are drawn as areas instead,
            # the rectangles it had moved to orbit_fit (i24-missionfix: they were left stale)
            cut = {"rectangle_before": u["rectangle"], "flown_rectangle_before":
                   u.get("flown_rectangle")}  # fmt: skip
            u["rectangle"], u["flown_rectangle"] = None, None
            u["areas_m"] = u.get("areas_m") or []
        if "pos_flown" in u:  # a survey's Table 4 figure, of the whole pattern
            cut["pos_flown_before"] = u.pop("pos_flown")
        if "areas_m" in u:
            u["areas_m"] = _swept_areas(legs, u["spacing_m"]) if len(legs) else []
        u["feasible"] = bool(u["flight_time_s"] <= usable)
        dropped[str(u["id"])] = {"waypoints_before": n0, "waypoints_after": len(wps),
                                 "last_leg_kept": lo, **cut}  # fmt: skip
    if not dropped:
        return plan
    pos, found = sampled_sweep(
        sc, grid, prior, [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]
                          if u["waypoints_m"] else [] for u in uavs],
    )  # fmt: skip
    for u, pos_k, f_k in zip(uavs, pos, found):
        u.update(found_scores(prior, pos_k, f_k))
    out["orbit_fit"] = {
        "uavs": dropped,
        "posc_before": float(plan["posc"]),
        "scorer": "sampled_sweep",
    }
    out["posc"] = float(sum(pos))
    if "objective" in out and plan.get("speeds_mps"):
        out["objective"] = -out["posc"]
    elif "x" in out:  # a DE plan: its optimiser's x and objective are the untrimmed plan's
        out["orbit_fit"]["x_before"] = out.pop("x")  # (no x flies the trimmed routes)
        if "objective" in out:
            out["orbit_fit"]["objective_before"] = out.pop("objective")
    return out


def check_terrain(
    plan: dict[str, Any], sc: Scenario | None = None, prior: np.ndarray | None = None
) -> dict[str, Any]:
    """``plan``, after checking that every UAV's mission keeps the terrain clearance within
    the ceiling (:func:`poc_env.agents.mission.terrain.plan_profiles`, the export's own
    profile): a plan the planner writes is one the export accepts. With ``sc`` and the
    ``prior``, a UAV whose orbits do not fit in 0.85 T is trimmed first (:func:`fit_orbits`).

    With the scenario ``sc`` and a sensor model whose W depends on the height (``camera``,
    :meth:`poc_env.config.SensorConfig.sweep_width_at`, resolved at ``uav.cruise_altitude_m``):
    a UserWarning per UAV whose search legs (first to last waypoint) the profile flies lower
    above the ground than that height (the ceiling or the glide to the field hold it down), with
    the least height and the model's W there, since the plan's POS assumes the planned W.

    Raises
    ------
    ConfigError
        Naming the UAV: clearance impossible within the UAV's ceiling.
    """
    from poc_env.agents.mission.terrain import plan_profiles

    if sc is not None and prior is not None:
        plan = fit_orbits(plan, sc, prior)
    profs = plan_profiles(plan)
    if profs is None or sc is None or sc.sensor.model == "fixed":
        return plan
    h = sc.uav.cruise_altitude_m
    for u, p in zip(plan["uavs"], profs):
        n = len(u["waypoints_m"])
        if n == 0:
            continue
        first, last = (int(np.flatnonzero(p.vertex == v)[0]) for v in (1, n))
        agl = float(np.min((p.amsl_m - p.ground_m)[first : last + 1]))
        if agl < h - 1.0:
            warnings.warn(
                f"UAV {u['id']}: its search legs fly as low as {agl:.0f} m above the ground "
                f"(the ceiling uav.max_altitude_m = {sc.uav.max_altitude_m:g} m AMSL or the "
                f"glide to the field hold them below uav.cruise_altitude_m = {h:g} m): the "
                f"{sc.sensor.model} sensor's W {sc.sensor.sweep_width_at(max(agl, 1e-3)):.0f} m "
                f"there, against the {sc.sensor.sweep_width_m:.0f} m the plan's POS assumes",
                UserWarning,
                stacklevel=3,
            )
    return plan
