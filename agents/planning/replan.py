"""The next sortie (issue 24, deliverable 4): ``poc-env replan``.

A search that ends without finding the target leaves a belief: the prior less what the flights
searched. :func:`searched_belief` sweeps the flown paths over the prior's sample points and
updates it by eq. 14 (:func:`poc_env.theory.search_theory.sweep_track`, the environment's
detection law and cut-off, the one implementation of the update); :func:`next_sortie` plans
the next sortie on what is left (the allocation planner by default). The flown paths are
either the previous plan's routes (take-off, waypoints, landing: what the plan said would be
flown) or the tracks actually flown, as GeoJSON LineStrings in WGS 84 longitude/latitude
(RFC 7946), put into the map's metres with the previous plan's CRS record (or ``--origin``)
(:func:`read_tracks`).

The belief is not renormalised: the next plan's POS is then a share of the original prior, and
the sorties' POS add up to the cumulative POS (eq. 13) -- ``searched`` plus the next plan's
``posc``.

Bad input is a :class:`~poc_env.errors.ConfigError` naming the field: a track point outside
the operating area (the map grown to its airfields, eq. 20's boundary), a GeoJSON ``crs``
member that is not WGS 84, a geometry that is not a LineString, a plan of another scenario's
map.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from poc_env.config import Scenario
from poc_env.errors import ConfigError
from poc_env.io import read_json
from poc_env.theory.probability_map import Grid
from poc_env.theory.search_theory import sweep_track

#: GeoJSON ``crs`` names accepted (WGS 84 longitude/latitude, the RFC 7946 default).
WGS84_NAMES = (
    "urn:ogc:def:crs:OGC:1.3:CRS84",
    "urn:ogc:def:crs:OGC::CRS84",
    "urn:ogc:def:crs:EPSG::4326",
    "EPSG:4326",
    "CRS84",
)


def operating_area(sc: Scenario, prior: np.ndarray) -> tuple[float, float, float, float]:
    """Eq. 20's boundary of ``sc``: the map grown to hold its airfields (x0, y0, x1, y1, m)."""
    from poc_env.sim.core import make_params

    x0, y0, x1, y1 = (float(v) for v in make_params(sc, prior).bounds)
    return x0, y0, x1, y1


def check_paths(sc: Scenario, prior: np.ndarray, paths, names) -> list[np.ndarray]:
    """``paths`` as (k, 2) arrays, each point inside the operating area; else a ConfigError
    naming ``names[i]`` and the point's index."""
    x0, y0, x1, y1 = operating_area(sc, prior)
    tol = 1e-6 * max(x1 - x0, y1 - y0)
    out = []
    for i, path in enumerate(paths):
        pts = np.asarray(path, dtype=float).reshape(-1, 2)
        bad = ~(
            np.isfinite(pts).all(axis=1)
            & (pts[:, 0] >= x0 - tol)
            & (pts[:, 0] <= x1 + tol)
            & (pts[:, 1] >= y0 - tol)
            & (pts[:, 1] <= y1 + tol)
        )
        if bad.any():
            j = int(np.argmax(bad))
            raise ConfigError(
                f"{names[i]}[{j}]",
                [round(float(v), 1) for v in pts[j]],
                f"a point in metres inside the operating area x {x0:g}..{x1:g}, y {y0:g}..{y1:g} "
                f"of scenario {sc.name!r} (the map and its airfields)",
            )
        out.append(pts)
    return out


def plan_paths(plan: dict[str, Any]) -> list[np.ndarray]:
    """The flights a plan says: per UAV take-off, waypoints, landing (UAVs without waypoints
    did not fly)."""
    out = []
    for u in plan["uavs"]:
        if u["waypoints_m"]:
            out.append(np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]], dtype=float))
    return out


def read_tracks(path: str | os.PathLike[str], crs: Any) -> list[tuple[str, np.ndarray]]:
    """The LineStrings of a GeoJSON file (WGS 84 lon/lat) in map metres, by ``crs`` (a plan's
    CRS record or a (lat, lon) origin, :func:`poc_env.agents.mission.crs.to_local`), each with
    the field that holds its coordinates."""
    from poc_env.agents.mission.crs import to_local

    where = "tracks"
    data = read_json(path, where)  # malformed, NaN constants, deep nesting: a ConfigError
    if not isinstance(data, dict):
        raise ConfigError(where, type(data).__name__, "a GeoJSON object")
    crs_member = data.get("crs")
    props = crs_member.get("properties") if isinstance(crs_member, dict) else None
    name = props.get("name") if isinstance(props, dict) else None
    if "crs" in data and (not isinstance(name, str) or name not in WGS84_NAMES):
        raise ConfigError(
            f"{where}.crs",
            name if name is not None else data.get("crs"),
            "WGS 84 longitude/latitude (RFC 7946: leave crs out, or "
            + ", ".join(WGS84_NAMES[:3]) + ")",
        )  # fmt: skip
    if data.get("type") == "FeatureCollection":
        feats = data.get("features")
        if not isinstance(feats, list):
            raise ConfigError(f"{where}.features", feats, "a list of features")
        geoms = [
            (f"{where}.features[{i}].geometry", f.get("geometry") if isinstance(f, dict) else f)
            for i, f in enumerate(feats)
        ]
    elif data.get("type") == "Feature":
        geoms = [(f"{where}.geometry", data.get("geometry"))]
    else:
        geoms = [(where, data)]
    lines = []
    for field, g in geoms:
        if not isinstance(g, dict) or g.get("type") not in ("LineString", "MultiLineString"):
            kind = g.get("type") if isinstance(g, dict) else g
            raise ConfigError(f"{field}.type", kind, "LineString or MultiLineString")
        parts = [g.get("coordinates")] if g["type"] == "LineString" else g.get("coordinates")
        for p, coords in enumerate(parts or []):
            f = f"{field}.coordinates" + (f"[{p}]" if g["type"] == "MultiLineString" else "")
            try:
                arr = np.asarray(coords, dtype=float)
            except (TypeError, ValueError, OverflowError):  # 10**400 is a JSON integer
                arr = np.zeros((0,))
            if arr.ndim != 2 or arr.shape[1] < 2 or len(arr) < 2:
                raise ConfigError(f, coords if arr.size < 6 else "array", "2 or more [lon, lat]")
            lon, lat = arr[:, 0], arr[:, 1]
            ok = np.isfinite(arr[:, :2]).all(axis=1) & (np.abs(lat) <= 90) & (np.abs(lon) <= 180)
            bad = ~ok
            if bad.any():
                j = int(np.argmax(bad))
                raise ConfigError(f"{f}[{j}]", arr[j, :2].tolist(), "[lon, lat] in WGS 84 degrees")
            lines.append((f, np.array(to_local(np.stack([lat, lon], axis=1), crs))))
    if not lines:
        raise ConfigError(where, os.fspath(path), "at least one LineString")
    return lines


def searched_belief(sc: Scenario, prior: np.ndarray, paths) -> tuple[np.ndarray, float]:
    """The prior less what ``paths`` (flights in map metres) searched, by eq. 14 on the sample
    points (:func:`poc_env.theory.search_theory.sweep_track`), summed back to cells; and the
    POS the flights achieved (eq. 13: the sum of their POS)."""
    grid = Grid.from_config(sc.map)
    s = sc.sensor.samples_per_cell
    belief = np.ascontiguousarray(grid.refine(prior, s))
    w = sc.sensor.sweep_width_m
    cutoff = sc.sensor.cutoff_sweep_widths * w
    found = 0.0
    for path in paths:
        if len(path) >= 2:
            found += sweep_track(belief, grid, s, path, w, sc.sensor.law, cutoff, grid.cell_m)
    return grid.coarsen(belief, s), float(found)


def next_sortie(
    sc: Scenario,
    prior: np.ndarray,
    plans: list[dict[str, Any]],
    tracks: list[tuple[str, np.ndarray]] | None = None,
    *,
    planner: str = "allocation",
    seed: int = 0,
) -> dict[str, Any]:
    """The plan of the next sortie after ``plans`` (the sorties so far, in order: their routes,
    or the flown ``tracks`` of all of them when given) on ``prior``: eq. 14 along every flight
    (:func:`searched_belief`), then the planner on what is left. Extra fields: ``sortie``
    (``len(plans) + 1``), ``searched_pos`` (what the flights so far found, eq. 13) and
    ``cumulative_posc`` (that plus the new plan's ``posc``)."""
    from poc_env.agents.planning.planner import make_plan

    names: list[str] = []
    flights: list[np.ndarray] = []
    for i, plan in enumerate(plans):
        where = f"plan[{i}]" if len(plans) > 1 else "plan"
        if plan.get("scenario") != sc.name:
            raise ConfigError(
                f"{where}.scenario", plan.get("scenario"), f"the scenario replanned, {sc.name!r} "
                "(the flights are in its map's metres)",
            )  # fmt: skip
        uavs = enumerate(plan["uavs"])
        names += [f"{where}.uavs[{k}].waypoints_m" for k, u in uavs if u["waypoints_m"]]
        flights += plan_paths(plan)
    if tracks is not None:
        names, flights = [f for f, _ in tracks], [t for _, t in tracks]
    paths = check_paths(sc, prior, flights, names)
    belief, searched = searched_belief(sc, prior, paths)
    nxt = make_plan(sc, prior=belief, planner=planner, seed=seed)
    if plans and plans[-1].get("crs") is not None:
        nxt["crs"] = plans[-1]["crs"]  # the same map, the same frame
    nxt["sortie"] = len(plans) + 1
    nxt["searched_pos"] = searched
    nxt["cumulative_posc"] = min(searched + float(nxt["posc"]), 1.0)
    return nxt


def cli_main(args: Any) -> int:
    """``poc-env replan``: read, check, plan, then write ``--out`` (nothing written on error)."""
    from poc_env.agents.mission.plan import load_plan, write_plan
    from poc_env.agents.planning.planner import plan_table
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.theory.probability_map import build_prior

    plans = [dict(load_plan(p)) for p in args.plan]
    name = args.scenario or str(plans[0]["scenario"])
    sc = load_scenario(name, parse_overrides(args.overrides or []))
    prior = build_prior(sc.map, args.map_file)
    tracks = None
    if args.tracks:
        crs = plans[-1].get("crs") or args.origin
        if crs is None:
            raise ConfigError(
                "origin", None, "LAT,LON of the map's (0, 0): the plan records no crs, and the "
                "tracks are in longitude/latitude",
            )  # fmt: skip
        tracks = []
        for t in args.tracks:
            tracks += read_tracks(t, crs)
    nxt = next_sortie(sc, prior, plans, tracks, planner=args.planner, seed=args.seed)
    print(plan_table(nxt))
    print(
        f"sortie {nxt['sortie']}: the flights so far found {nxt['searched_pos']:.4f}; this plan "
        f"{nxt['posc']:.4f}; cumulative {nxt['cumulative_posc']:.4f}"
    )
    write_plan(nxt, args.out)
    print(f"wrote {args.out}")
    return 0
