"""The §6.2 time-limited plan: optimise eq. 26 and write ``plan.json`` (schema 2) and a figure.

The plan also records (optional fields, see :mod:`poc_env.agents.mission.plan`) the UAV's
speeds and altitudes (``flight``), the operating area of eq. 20 (``operating_area_m``, the
bounding box of the grid and the airfields grown by ``episode.boundary_margin_km``, as in
:func:`poc_env.sim.core.make_params`), the no-fly zones and the airfields, and, when
``origin_deg`` is given, its coordinate reference system (``crs``: azimuthal equidistant at
that origin by default, UTM with ``projection="utm"``).

:func:`make_plan` runs an optimiser of :mod:`~poc_env.agents.planning.optimizers` (default the
paper's
adaptive DE with NP = 100, G = 300, F0 = 0.2, CR = 0.1 from the scenario's ``planner`` section)
on :class:`~poc_env.agents.planning.objective.PlanObjective` and returns the plan as the schema-2
dict
documented in :mod:`poc_env.agents.mission.plan` (every field there, plus a few extras such as
the
convergence history). The ``de_plan`` policy (:mod:`poc_env.agents.policies.de_plan`) makes such a
plan at the start of every episode and flies it.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

import poc_env.limits as limits
from poc_env.agents.mission.plan import RECTANGLE_RULE, SCHEMA
from poc_env.agents.planning.geography import (
    check_terrain,
    plan_geography,
    scenario_crs,
    zone_prior,
)
from poc_env.agents.planning.objective import PlanObjective
from poc_env.agents.planning.optimizers import get_optimizer, preset_settings
from poc_env.agents.planning.options import PlanOptions
from poc_env.agents.planning.refine import route_time
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, as_int
from poc_env.geometry import polyline_length
from poc_env.sim.routing import ZoneRouter
from poc_env.theory.probability_map import build_prior


class _Speeds(NamedTuple):
    """Eq. 17's speeds of a DE plan's path (``route_time``): out, on the pattern, home."""

    out: float
    line: float
    home: float


def make_plan(
    scenario: Scenario | str = "paper_6_2",
    *,
    prior: np.ndarray | None = None,
    map_source: str = "builtin",
    uavs: int | None = None,
    optimizer: str = "adaptive_de",
    seed: int = 0,
    popsize: int | None = None,
    maxiter: int | None = None,
    progress: bool = False,
    init: np.ndarray | None = None,
    origin_deg: tuple[float, float] | str | None = None,
    projection: str = "aeqd",
    zone: int | None = None,
    preset: str = "paper",
    planner: str = "de",
    speed: str | None = None,
    refine: int | None = None,
    effort: str | None = None,
    gain_per_hour: float | None = None,
) -> dict[str, Any]:
    """Optimise the plan and return it as a schema-2 dict (see the module docstring).

    ``planner``: ``de`` (this optimiser-based plan) or ``allocation``
    (:func:`poc_env.agents.planning.allocation.make_allocation_plan`, routes from the reach-aware
    optimal allocation; the optimiser arguments do not apply to it). ``speed`` (``max`` or
    ``paper``) and ``refine`` (passes of the waypoint refinement, 0 for straight lines only) are
    the allocation planner's (None: its defaults), and so is ``effort`` (``default`` or
    ``thorough``, :meth:`poc_env.agents.planning.options.PlanOptions.preset`) and
    ``gain_per_hour`` (``PlanOptions.gain_per_hour``, the least a flying UAV adds per flight
    hour as a share of the prior's mass; 0: every route flies); the DE plan refuses them.

    ``preset`` (:func:`poc_env.agents.planning.optimizers.preset_settings`): ``paper`` runs the
    scenario's ``planner`` settings (the paper's), ``tuned`` the same budget with the measured
    DE constants :data:`~poc_env.agents.planning.optimizers.TUNED_DE` (F0, CR; DE optimisers only);
    ``popsize`` and ``maxiter`` override the preset's budget. Recorded in
    ``optimizer.settings.preset``.

    ``origin_deg``: (lat, lon) of the map's (0, 0); with it the plan records its ``crs``
    (``projection`` ``aeqd`` or ``utm`` in UTM ``zone``, see
    :func:`poc_env.agents.mission.crs.make_crs`) and exports need no ``--origin``.

    ``init`` (adaptive and classic DE): individuals of the 6n encoding that seed the initial
    population (a warm start); the plan's ``x`` (the best individual) is returned as ``"x"``.
    """
    if planner not in ("de", "allocation"):
        raise ConfigError("planner", planner, "de or allocation")
    crs = scenario_crs(load_scenario(scenario), origin_deg, projection, zone)
    if planner == "allocation":
        from poc_env.agents.planning.allocation import REFINE, SPEED, make_allocation_plan

        sc_a = load_scenario(scenario)
        return check_terrain(
            make_allocation_plan(
                scenario,
                prior=prior,
                map_source=map_source,
                uavs=uavs,
                seed=seed,
                crs=crs,
                speed=SPEED if speed is None else speed,
                refine=REFINE if refine is None else refine,
                options=plan_options(effort, gain_per_hour),
            ),
            sc_a,
            build_prior(sc_a.map) if prior is None else np.asarray(prior, dtype=float),
        )
    for name, value in (("speed", speed), ("refine", refine), ("effort", effort),
                        ("gain_per_hour", gain_per_hour)):  # fmt: skip
        if value is not None:
            raise ConfigError(name, value, "only with planner allocation (leave it out for de)")
    sc = load_scenario(scenario)
    opt = get_optimizer(optimizer)
    if prior is None:
        prior = build_prior(sc.map)
    full_prior = np.asarray(prior, dtype=float)
    router = ZoneRouter.for_scenario(sc)
    # POC inside a zone counts as far as the sensor reaches it from outside (W/2, eq. 20)
    prior = zone_prior(sc, full_prior, router)
    obj = PlanObjective(sc, prior, uavs=uavs, bound_prior=full_prior)
    pl = preset_settings(preset, sc.planner)
    settings: dict[str, Any] = {
        "popsize": pl["popsize"]
        if popsize is None
        else as_int("popsize", popsize, 4, limits.POPSIZE_MAX),
        "maxiter": pl["maxiter"]
        if maxiter is None
        else as_int("maxiter", maxiter, 1, limits.MAXITER_MAX),
    }
    limits.check_memory(
        "popsize",
        settings["popsize"],
        limits.plan_bytes(settings["popsize"], obj.n, prior.size),
        f"population of {settings['popsize']} plans of {obj.n} UAVs over {prior.size} cells",
    )
    kwargs: dict[str, Any] = dict(settings)
    settings["preset"] = preset
    if optimizer in ("adaptive_de", "classic_de"):
        kwargs.update(f0=pl["f0"], cr=pl["cr"])
        settings.update(f0=pl["f0"], cr=pl["cr"])
        if init is not None:
            kwargs["init"] = init
            settings["warm_start"] = int(np.atleast_2d(init).shape[0])
    elif init is not None:
        raise ConfigError("init", optimizer, "adaptive_de or classic_de (warm starts)")
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=settings["maxiter"], desc=optimizer, unit="gen")

    def callback(res):
        if bar is not None:
            bar.update(1)
            bar.set_postfix(objective=f"{res.fun:.4f}")
        return False

    t0 = time.perf_counter()
    res = opt(obj, obj.bounds, rng=seed, callback=callback, **kwargs)
    runtime = time.perf_counter() - t0
    if bar is not None:
        bar.close()
    x = np.asarray(res.x, dtype=float)
    per_uav = obj.decode(x)
    uav_out = []
    u_cfg = obj.scenario.uav
    speeds = _Speeds(u_cfg.cruise_speed_mps, u_cfg.search_speed_mps, u_cfg.cruise_speed_mps)
    for u in per_uav:
        if router.active:  # transit around the zones, search legs clipped to flyable airspace
            path = router.reroute([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]])
            u["waypoints_m"] = [[float(a), float(b)] for a, b in path[1:-1]]
            u["track_length_m"] = polyline_length(path)
            u["flight_time_s"] = route_time(path, speeds, u_cfg.max_turn_rate_rad_s)
            u["feasible"] = bool(u["feasible"] and u["flight_time_s"] <= u_cfg.usable_endurance_s)
        uav_out.append(
            {
                "id": u["id"] + 1,
                "rectangle": {
                    "center_m": u["center_m"],
                    "length_m": u["length_m"],
                    "width_m": u["width_m"],
                    "theta_deg": u["theta_deg"],
                },
                "flown_rectangle": u["flown_rectangle"],
                "spacing_m": u["spacing_m"],
                "takeoff_m": u["takeoff_m"],
                "landing_m": u["landing_m"],
                "waypoints_m": u["waypoints_m"],
                "track_length_m": u["track_length_m"],
                "flight_time_s": u["flight_time_s"],
                "pod": u["pod"],
                "poc": u["poc"],
                "pos": u["pos"],
                "feasible": u["feasible"],
            }
        )
    _infeasible_warning(uav_out, u_cfg.usable_endurance_s, settings)
    return check_terrain(
        {
            "schema": SCHEMA,
            "scenario": sc.name,
            "seed": int(seed),
            "map_source": map_source,
            "optimizer": {"name": optimizer, "settings": settings},
            "runtime_s": runtime,
            "posc": float(sum(u["pos"] for u in uav_out)),
            "upper_bound": float(obj.upper_bound(x)),
            "objective": float(res.fun),
            "history": [float(v) for v in np.asarray(getattr(res, "history", []), dtype=float)],
            "x": [float(v) for v in x],
            "rectangle_rule": RECTANGLE_RULE,
            "uavs": uav_out,
            # the bounds of the fleet planned (uavs=n may differ from the scenario's fleet)
            **plan_geography(obj.scenario, full_prior, crs),
        },
        obj.scenario,
        full_prior,
    )


def _infeasible_warning(uavs: list[dict[str, Any]], usable_s: float, settings: dict) -> None:
    """Warn (UserWarning) when a DE plan's UAVs are infeasible: the optimiser's budget found no
    rectangle whose flight fits the usable endurance 0.85 T (eq. 18) for them. The plan is
    returned as it is (its table says "NO"); the warning names the UAVs, so that ``plan`` and
    ``replan`` do not write missions that cannot be flown without a word (scale-audit)."""
    bad = [(k, u) for k, u in enumerate(uavs) if not u["feasible"]]
    if not bad:
        return
    import warnings

    k, u = max(bad, key=lambda ku: ku[1]["flight_time_s"])
    names = ", ".join(f"plan.uavs[{j}] (UAV {v['id']})" for j, v in bad[:6])
    more = f" and {len(bad) - 6} more" if len(bad) > 6 else ""
    warnings.warn(
        f"{names}{more}: flight time {u['flight_time_s'] / 3600:.2f} h (the longest, "
        f"plan.uavs[{k}]) beyond the usable endurance {usable_s / 3600:.2f} h (0.85 T, eq. 18): "
        f"{len(bad)} of {len(uavs)} UAVs' missions cannot be flown. The optimiser's budget "
        f"(popsize {settings['popsize']}, maxiter {settings['maxiter']}) found no feasible "
        "plan for them: raise --maxiter or --popsize, or plan with --planner allocation",
        UserWarning,
        stacklevel=3,
    )


def moving_target_warning(sc: Scenario, replanned: bool = False) -> str | None:
    """The warning ``plan``, ``replan`` and ``survey`` print when ``sc``'s target moves (issue
    25 audit): they plan a standing target on the prior, and the bounds they print hold for a
    standing target only. None for a static target."""
    if not sc.target.moves:
        return None
    swept = (
        "; the flights so far are swept on the prior where it was, not moved over the "
        "elapsed sortie"
        if replanned
        else ""
    )
    return (
        f"target.model {sc.target.model!r} moves the target, but this plan is for a standing "
        f"one: it searches the prior at take-off{swept}, and the bounds above hold for a "
        "standing target only. For a moving target evaluate the policies spacetime_plan or "
        "spacetime_receding (docs/PLANNER.md, Moving targets)"
    )


def lattice_warning(sc: Scenario) -> str | None:
    """The warning ``plan`` and ``replan`` print when the sensor's sample points are farther
    apart than the sweep width (config-audit): eq. 14 is applied at the sample points, so a
    track sweeps only the rows it passes, and a plan laid on those rows scores more than a
    flight can (on a 180 x 20 km map of 20 km cells: planned 0.883 against a rule-aware bound
    of 0.856, flown 0.852). None when the lattice is at most one sweep width apart."""
    s = sc.sensor.samples_per_cell
    h, w = sc.map.cell_m / s, sc.sensor.sweep_width_m
    if h <= w * (1.0 + 1e-9):
        return None
    need = math.ceil(sc.map.cell_m / w - 1e-9)
    return (
        f"sensor.samples_per_cell {s}: the sensor's sample points are {h / 1e3:g} km apart, "
        f"wider than the sweep width {w / 1e3:g} km; eq. 14 sees a track only where it passes "
        "a row of them, so the planned POS can exceed what the flight finds (and the bounds); "
        f"samples_per_cell >= {need} gives points at most one sweep width apart"
    )


def effort_skip_note(plan: dict[str, Any], effort: str | None) -> str | None:
    """One line for ``plan``'s and ``replan``'s summary when ``--effort standard`` or
    ``thorough`` skipped its polish (a map above ``polish_max_cells`` a side, or no-fly zones
    with ``PlanOptions.polish_zones=False``: docs/PLANNER.md, effort levels), naming why, or
    None. Only plan.json recorded it before (scale audit): a standard
    plan so skipped is exactly the default plan, a thorough one lacks its polish stages.
    i24-bigpolish: also when the polish stopped at its work budget (``polish_big_work``, maps
    above the cell limit), saying so and that ``thorough`` polishes further."""
    if effort not in ("standard", "thorough"):
        return None
    polish = plan.get("optimizer", {}).get("settings", {}).get("polish") or {}
    why = polish.get("skipped")
    if polish.get("spent"):
        return (
            f"note: --effort {effort} stopped its polish at its work budget (a map above "
            f"polish_max_cells cells a side: {polish['work']:,} candidate steps scored, "
            f"{polish['passes']} passes); --effort thorough polishes further, for minutes"
        )
    if not why:
        return None
    what = (
        "this is the default plan (the polish is all standard adds)"
        if effort == "standard"
        else "its other settings apply, its polish stages do not"
    )
    return f"note: --effort {effort} skipped its polish ({why}): {what}"


def plan_options(effort: str | None = None, gain_per_hour: float | None = None) -> PlanOptions:
    """The allocation planner's options of an effort level (None: ``default``;
    :meth:`PlanOptions.preset`) with ``gain_per_hour`` (None: the level's), as ``plan`` asks.

    Raises
    ------
    ConfigError
        Naming ``gain_per_hour`` (``plan --gain-per-hour``) unless it is a number in [0, 0.01].
    """
    opt = PlanOptions.preset("default" if effort is None else effort)
    if gain_per_hour is None:
        return opt
    try:
        return dataclasses.replace(opt, gain_per_hour=gain_per_hour)
    except ConfigError as e:
        raise ConfigError("gain_per_hour", gain_per_hour, f"{e.allowed} (a share of the prior's "
                          "mass per flight hour; 0: every route flies)") from None  # fmt: skip


def home_note(plan: dict[str, Any]) -> str | None:
    """The lines for ``plan``'s and ``replan``'s summary naming the UAVs that stay home (no
    search route: empty ``waypoints_m``) and why, or None when every UAV flies (i24-dayaudit2:
    their table rows read 0.00 h and ``ok yes``, and only the export named them).

    The allocation planner's UAVs kept home by its floor per flight hour
    (``PlanOptions.gain_per_hour``; i24-gainhour, G3; plan.json's
    ``optimizer.settings.home``) are listed with what each would add and in how many hours,
    and the hours saved for the POS given up in all; the others got no route from the
    planner (none that adds its floor and keeps clear of the other routes).

    Parameters
    ----------
    plan : dict
        A plan as :func:`make_plan` returns it (or its plan.json).

    Returns
    -------
    str or None
        ``stay home: UAVs 2, 3 (2 of 3, no search route): ...``, then a line per reason; None
        when no UAV is idle or none flies (the plan's ``reason`` says why then).
    """
    uavs = plan["uavs"]
    home = [u["id"] for u in uavs if not u["waypoints_m"]]
    if not home or len(home) == len(uavs):
        return None

    def who(ids: list) -> str:
        return f"UAV{'s' if len(ids) > 1 else ''} {', '.join(str(i) for i in ids)}"

    head = f"stay home: {who(home)} ({len(home)} of {len(uavs)}, no search route)"
    if plan.get("planner") != "allocation":
        return f"{head}: the planner gave them no search route"
    settings = plan.get("optimizer", {}).get("settings", {})
    gain = settings.get("options", {}).get("gain_per_hour", PlanOptions.gain_per_hour)
    rule = [r for r in settings.get("home", []) if r["id"] in home]
    lines = [f"{head}:"]
    if rule:
        each = ", ".join(f"UAV {r['id']} {r['pos']:.1e} in {r['hours']:.2f} h" for r in rule)
        hours, pos = sum(r["hours"] for r in rule), sum(r["pos"] for r in rule)
        lines.append(
            f"  {who([r['id'] for r in rule])}: each would add less than {gain:g} of the "
            f"prior's mass per flight hour (--gain-per-hour, PlanOptions.gain_per_hour; 0: every "
            f"route flies): {each}; {hours:.1f} flight hours saved for {pos:.1e} of POS_C in all"
        )
    others = [i for i in home if i not in {r["id"] for r in rule}]
    if others:
        off = gain == 0 or settings.get("options", {}).get("nothing", PlanOptions.nothing) == 0
        adds = "" if off else f"adds at least {gain:g} of the prior's mass per flight hour and "
        lines.append(
            f"  {who(others) if rule else 'all'}: no route the planner found for them {adds}"
            "keeps clear of the other routes (eq. 21, PlanOptions.fill_apart)"
        )
    return "\n".join(lines)


def plan_table(plan: dict[str, Any]) -> str:
    """Table 6 analog: rectangles, spacing and angle per UAV, with POD, POC, POS and time."""
    head = (
        f"{'No.':>3} {'(x_c, y_c)/km':>16} {'(l, w)/km':>14} {'theta/deg':>9} {'d/km':>6} "
        f"{'POD':>6} {'POC':>6} {'POS':>6} {'time/h':>6} {'ok':>3}"
    )
    lines = [head, "-" * len(head)]
    for u in plan["uavs"]:
        r = u["rectangle"]
        if r is None:  # a route plan (schema 2): no decision rectangle
            c, lw, theta = "-", "-", "-"
        else:
            c = f"({r['center_m'][0] / 1e3:.1f}, {r['center_m'][1] / 1e3:.1f})"
            lw = f"({r['length_m'] / 1e3:.1f}, {r['width_m'] / 1e3:.1f})"
            theta = f"{r['theta_deg']:.1f}"
        lines.append(
            f"{u['id']:>3} {c:>16} {lw:>14} {theta:>9} {u['spacing_m'] / 1e3:>6.2f} "
            f"{u['pod']:>6.3f} {u['poc']:>6.3f} {u['pos']:>6.3f} "
            f"{u['flight_time_s'] / 3600:>6.2f} {'yes' if u['feasible'] else 'NO':>3}"
        )
    lines.append("-" * len(head))
    lines.append(
        f"POS_C = {plan['posc']:.4f}   physical optimum for the same effort: "
        f"{plan['upper_bound']:.4f}   ({plan['optimizer']['name']}, seed {plan['seed']}, "
        f"{plan['runtime_s']:.2f} s)"
    )
    if plan.get("reason"):  # an allocation plan that reaches nothing says why (not just 0s)
        lines.append(f"no search planned: {plan['reason']}")
    else:
        home = home_note(plan)
        if home:
            lines.append(home)
    b = plan.get("bounds")
    if b:
        ratio = f" (POS_C / reach {plan['posc'] / b['reach']:.3f})" if b["reach"] > 0 else ""
        lines.append(
            f"bounds for the environment: honest {b['honest']:.4f}, "
            f"reach-aware {b['reach']:.4f}{ratio}"
        )
    rule = plan.get("bound_rule")
    if rule:
        lines.append(
            f"rule-aware bound (back by 0.85 T, home at v_c): {rule:.4f} "
            f"(POS_C / rule {plan['posc'] / rule:.3f})"
        )
    spill = plan.get("bound_spill")
    if spill:
        lines.append(
            f"spill-charged bound (the rule-aware one, the sensor's spill charged by its "
            f"lateral law): {spill:.4f} (POS_C / spill {plan['posc'] / spill:.3f})"
        )
    if plan.get("reason") and (rule or (b and b["reach"] > 0)):  # G4 (results/audit/dayaudit2)
        lines.append(
            "(the bounds are relaxations: they credit what the sensor could detect from "
            "anywhere a UAV can fly, up to its lateral reach beyond, with no whole search line "
            "needed, so they can stay above 0 where the planner finds no search to plan)"
        )
    return "\n".join(lines)


def plot_plan(plan: dict[str, Any], scenario: Scenario, prior, path) -> Path:
    """Fig. 21 analog: prior, search areas (the flown strips, :func:`search_rings`), tracks and
    airfields."""
    from poc_env.agents.mission.plan import search_rings
    from poc_env.theory.probability_map import Grid
    from poc_env.viz.plots import _figure, draw_airfields, draw_prior, save_figure_atomic

    grid = Grid.from_config(scenario.map)
    fig = _figure((9.0, 6.5))
    ax = fig.add_subplot()
    draw_prior(ax, grid, prior)
    for k, u in enumerate(plan["uavs"]):
        for _, ring_m, _ in search_rings(u):
            ring = np.asarray(ring_m) / 1e3
            ax.plot(ring[:, 0], ring[:, 1], color="w", lw=1.4)
        route = np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]) / 1e3
        ax.plot(route[:, 0], route[:, 1], color=f"C{k % 10}", lw=0.8, label=f"UAV {u['id']}")
    pts = np.unique(np.array([u["takeoff_m"] for u in plan["uavs"]]), axis=0)
    draw_airfields(ax, pts)
    x0, y0, x1, y1 = grid.bounds
    ax.set_xlim(min(x0, pts[:, 0].min()) / 1e3 - 10, x1 / 1e3 + 10)
    ax.set_ylim(min(y0, pts[:, 1].min()) / 1e3 - 10, y1 / 1e3 + 5)
    ax.set_title(
        f"{plan['scenario']}: POS_C {plan['posc']:.4f} (bound {plan['upper_bound']:.4f}), "
        f"{plan['optimizer']['name']}"
    )
    ax.legend(loc="upper right", fontsize=7, ncols=2)
    return save_figure_atomic(fig, path)
