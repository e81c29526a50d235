"""GeoJSON (RFC 7946): one FeatureCollection of the routes, search areas, approaches and fences."""

from __future__ import annotations

import json
from itertools import pairwise
from pathlib import Path
from typing import Any

from poc_env.agents.mission.crs import crs_text, to_geographic
from poc_env.agents.mission.features import (
    altitudes,
    antimeridian_parts,
    layer_of,
    overlays,
    r6,
    routes_3d,
)
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.plan import Plan, flight, search_rings, sortie_figures
from poc_env.io import write_text_atomic


def geojson(
    plan: Plan,
    crs: Any,
    altitude_m: float | None = None,
    altitude_ref: str = "home",
    field_elevation_m: float = 0.0,
) -> dict:
    """A FeatureCollection: per UAV the route (LineString) and its search areas (Polygons).

    Coordinates [lon, lat, z] rounded to 1e-6 degrees (about 0.1 m); z is the altitude in the
    reference ``altitude_ref`` (the same numbers as the QGC mission and the KML); properties in
    km, minutes, km/h and %.
    """
    alt, ground = altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
    fl = flight(plan)
    feats = []
    for u, (xy, zs) in zip(plan["uavs"], routes_3d(plan, alt, ground)):
        pts = to_geographic(xy, crs)
        props = {
            "id": u["id"],
            "kind": "route",
            "spacing_km": round(u["spacing_m"] / 1e3, 3),
            "track_km": round(u["track_length_m"] / 1e3, 3),
            "flight_time_min": round(u["flight_time_s"] / 60, 1),
            "pod_pct": round(100 * u["pod"], 2),
            "poc_pct": round(100 * u["poc"], 2),
            "pos_pct": round(100 * u["pos"], 2),
            "feasible": u["feasible"],
            **_altitude_properties(plan, alt, zs, u),
            "altitude_ref": altitude_ref,
            "cruise_speed_kmh": round(fl["cruise_speed_mps"] * 3.6, 1),
            "search_speed_kmh": round(fl["search_speed_mps"] * 3.6, 1),
            "transit_speed_kmh": round(fl["transit_speed_mps"] * 3.6, 1),
        }
        feats.append(
            {
                "type": "Feature",
                "geometry": line_geometry(pts, zs),
                "properties": props,
            }
        )
        for kind, ring_m, ring_props in search_rings(u):
            feats.append(
                {
                    "type": "Feature",
                    "geometry": polygon_geometry(to_geographic(ring_m, crs)),
                    "properties": {"id": u["id"], "kind": kind, **ring_props},
                }
            )
    for o in overlays(plan, crs, alt, ground):
        if o["geometry"] == "Polygon":
            geometry = polygon_geometry(o["latlon"])
        elif o["geometry"] == "LineString":
            geometry = line_geometry(o["latlon"], o["z"])
        else:
            (lat, lon), z = o["latlon"][0], o["z"][0]
            geometry = {"type": "Point", "coordinates": [r6(lon), r6(lat), z]}
        feats.append(
            {
                "type": "Feature",
                "geometry": geometry,
                "properties": o["properties"],
            }
        )
    about: dict[str, Any] = {
        "scenario": plan["scenario"],
        "posc_pct": round(100 * plan["posc"], 2),
        "local_crs": crs_text(crs) if isinstance(crs, dict) else None,
        "altitude_ref": altitude_ref,
    }
    if layers := plan.get("altitude_layers"):  # with_layers: the export's vertical separation
        about["altitude_layers"] = dict(layers)
    if sortie := sortie_figures(plan):  # a replanned sortie: what it finds, the search's POS
        about["sortie"] = int(sortie["sortie"])
        about["sortie_posc_pct"] = round(100 * sortie["sortie_posc"], 2)
        about["cumulative_posc_pct"] = round(100 * sortie["cumulative_posc"], 2)
    return {"type": "FeatureCollection", "features": feats, "properties": about}


def _altitude_properties(plan: Plan, alt: float, zs: list[float], u: Any) -> dict[str, float]:
    """What a route's altitudes are, in the words the line flies.

    Flat: ``altitude_m``, the search altitude every airborne point has. With the plan's
    ``terrain`` the z follow the DEM, so no single altitude describes the line: the search
    height above the ground (``search_height_m``, the UAV's cruise altitude, where the climb and
    the ceiling allow), the least clearance and the AMSL range the airborne points span
    (``altitude_min_m``, ``altitude_max_m``; the fields are at their own elevations). With
    altitude layers (:func:`~poc_env.agents.mission.features.with_layers`) the UAV's
    ``layer_m`` too, included in the altitudes.
    """
    t = plan.get("terrain")
    layer = {"layer_m": round(layer_of(u), 1)} if "layer_m" in u else {}
    if t is None:
        return {"altitude_m": round(alt + layer_of(u), 1), **layer}
    air = zs[1:-1]
    return {
        **layer,
        "search_height_m": round(float(t["search_height_m"]), 1),
        "min_clearance_m": round(float(t["min_clearance_m"]), 1),
        "altitude_min_m": round(min(air), 1),
        "altitude_max_m": round(max(air), 1),
    }


def line_geometry(latlon: Any, zs: list[float]) -> dict[str, Any]:
    """A LineString of ``[lon, lat, z]`` (degrees rounded to 1e-6), or a MultiLineString of its
    parts on each side when it crosses the antimeridian (RFC 7946 section 3.1.9:
    :func:`~poc_env.agents.mission.features.antimeridian_parts`)."""
    parts = antimeridian_parts([(lat, lon, z) for (lat, lon), z in zip(latlon, zs)])
    coords = [[[r6(lon), r6(lat), z] for lat, lon, z in part] for part in parts]
    if len(coords) == 1:
        return {"type": "LineString", "coordinates": coords[0]}
    return {"type": "MultiLineString", "coordinates": coords}


def polygon_geometry(latlon: Any) -> dict[str, Any]:
    """A Polygon (:func:`exterior_ring`), or a MultiPolygon of its parts on each side when it
    crosses the antimeridian (RFC 7946 section 3.1.9)."""
    rings = [exterior_ring(part) for part in antimeridian_parts(latlon, ring=True)]
    if len(rings) == 1:
        return {"type": "Polygon", "coordinates": rings}
    return {"type": "MultiPolygon", "coordinates": [[r] for r in rings]}


def exterior_ring(latlon: Any) -> list[list[float]]:
    """A polygon's exterior ring as RFC 7946 wants it: [lon, lat] rounded to 1e-6 degree,
    closed (last position = first) and counter-clockwise (section 3.1.6: exterior rings
    follow the right-hand rule); a ring with no area keeps its order."""
    ring = _unfolded([[r6(lon), r6(lat)] for lat, lon in latlon])
    if ring and ring[0] != ring[-1]:
        ring.append(list(ring[0]))
    if ring_area(ring) < 0:
        ring.reverse()
    return ring


def _unfolded(ring: list[list[float]]) -> list[list[float]]:
    """``ring`` (not closed) without the folds the rounding makes: a vertex equal to the one
    before it, and a spike ``a, b, a`` (out to ``b`` and back) whose two ``a`` were apart by
    less than the rounding (an allocation plan's cut line: 2e-12 m in its metres) and would
    make the ring cross itself, invalid as a simple feature (export-audit)."""
    out = [list(p) for p in ring]
    if len(out) > 1 and out[0] == out[-1]:
        out.pop()
    i = 0
    while len(out) > 3 and i < len(out):
        n = len(out)
        a, b, c = out[i - 1], out[i], out[(i + 1) % n]
        if a == b:
            del out[i]
        elif a == c:
            del out[max(i, (i + 1) % n)], out[min(i, (i + 1) % n)]
        else:
            i += 1
            continue
        i = max(i - 1, 0)
    return out


def ring_area(ring: list[list[float]]) -> float:
    """Signed area (shoelace, in square degrees of [lon, lat]) of a closed ring: positive when
    counter-clockwise."""
    return 0.5 * sum(x0 * y1 - x1 * y0 for (x0, y0, *_), (x1, y1, *_) in pairwise(ring))


def write(job: ExportJob) -> list[Path]:
    """``<stem>.geojson`` (strict JSON: no NaN)."""
    doc = geojson(job.plan, job.crs, job.altitude_m, job.altitude_ref, job.ground_m)
    return [write_text_atomic(job.path(".geojson"), json.dumps(doc, indent=1, allow_nan=False))]
