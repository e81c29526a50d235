"""KML (Google Earth): per UAV a folder with its route, search areas and landing approach.

Beside the KML, ``<stem>_prior.png`` (:mod:`poc_env.agents.mission.overlay`) is the plan's
prior as a GroundOverlay: an image evenly spaced in latitude and longitude, drawn under
everything else. Without a prior (the scenario cannot be rebuilt) the document's description
says why.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.features import altitudes, check_altitude_ref, overlays
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.overlay import plan_prior, png_bytes, warp_prior
from poc_env.agents.mission.plan import Plan, flight, route, search_rings
from poc_env.io import write_bytes_atomic, write_text_atomic

#: altitude reference -> KML altitudeMode
ALTITUDE_MODES = {"home": "relativeToGround", "amsl": "absolute"}


def kml(
    plan: Plan,
    crs: Any,
    altitude_m: float | None = None,
    altitude_ref: str = "home",
    field_elevation_m: float = 0.0,
    ground_overlay: dict[str, Any] | None = None,
) -> str:
    """KML with one Placemark (LineString route) per UAV.

    ``altitude_ref`` ``home`` -> ``relativeToGround``, ``amsl`` -> ``absolute``; z as in
    :func:`geojson` and the QGC mission (see docs/EXPORT.md for the caveat on home vs ground).
    ``ground_overlay`` {``href``, ``box`` (south, west, north, east) degrees, ``note``}: the
    prior as a GroundOverlay (an image evenly spaced in latitude and longitude, see
    :func:`poc_env.agents.mission.overlay.warp_prior`) in its own folder under everything else;
    without one, ``note`` (if any) becomes the document's description.
    """
    alt, ground = altitudes(plan, altitude_m, altitude_ref, field_elevation_m)
    mode = ALTITUDE_MODES[check_altitude_ref(altitude_ref)]
    fl = flight(plan)
    extras = overlays(plan, crs, alt, ground)
    folders = []
    for u in plan["uavs"]:
        pts = to_geographic(route(u), crs)
        zs = [ground, *[alt] * (len(pts) - 2), ground]
        uid = escape(str(u["id"]))
        placemark = (
            f"<Placemark><name>UAV {uid} route</name><styleUrl>#route</styleUrl>"
            f"<description>POS {100 * u['pos']:.2f} %, track {u['track_length_m'] / 1000:.1f} km"
            f", {u['flight_time_s'] / 60:.0f} min, {alt:g} m ({altitude_ref}); out "
            f"{3.6 * fl['transit_speed_mps']:.0f} km/h, search {3.6 * fl['search_speed_mps']:.0f}"
            f" km/h, home {3.6 * fl['cruise_speed_mps']:.0f} km/h</description>"
            f"<LineString><altitudeMode>{mode}</altitudeMode>"
            f"<coordinates>{_kml_coords(pts, zs)}</coordinates></LineString></Placemark>"
        )
        rect = "".join(
            f"<Placemark><name>UAV {uid} {kind.replace('_', ' ')}</name>"
            f"<styleUrl>#rectangle</styleUrl><description>{escape(_kml_props(props))}"
            "</description><Polygon><outerBoundaryIs><LinearRing><coordinates>"
            f"{_kml_coords(to_geographic(ring_m, crs))}</coordinates></LinearRing>"
            "</outerBoundaryIs></Polygon></Placemark>"
            for kind, ring_m, props in search_rings(u)
        )
        mine = [o for o in extras if o["properties"].get("id") == u["id"]]
        extra = "".join(_kml_placemark(o, mode) for o in mine)
        folders.append(f"<Folder><name>UAV {uid}</name>{placemark}{rect}{extra}</Folder>")
    others = "".join(_kml_placemark(o, mode) for o in extras if "id" not in o["properties"])
    name = escape(str(plan["scenario"]))
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2"><Document>'
        f"<name>{name}</name>{_kml_ground_overlay(ground_overlay)}{_KML_STYLES}{''.join(folders)}"
        f"<Folder><name>Area, airfields, no-fly zones</name>{others}</Folder></Document></kml>\n"
    )


#: KML styles (colours aabbggrr): routes orange, approaches white, search rectangles and the
#: operating area outlined, no-fly zones filled red, airfields as the default pin.
_KML_STYLES = (
    '<Style id="route"><LineStyle><color>ff00a5ff</color><width>2</width></LineStyle></Style>'
    '<Style id="landing_approach"><LineStyle><color>ffffffff</color><width>2</width></LineStyle>'
    "</Style>"
    '<Style id="rectangle"><LineStyle><color>ffffff00</color><width>1.5</width></LineStyle>'
    "<PolyStyle><fill>0</fill></PolyStyle></Style>"
    '<Style id="operating_area"><LineStyle><color>ff00ffff</color><width>1.5</width></LineStyle>'
    "<PolyStyle><fill>0</fill></PolyStyle></Style>"
    '<Style id="no_fly_zone"><LineStyle><color>ff0000ff</color><width>1.5</width></LineStyle>'
    "<PolyStyle><color>660000ff</color></PolyStyle></Style>"
    '<Style id="airfield"><IconStyle><scale>1.1</scale></IconStyle></Style>'
)


def _kml_ground_overlay(g: dict[str, Any] | None) -> str:
    """The prior's GroundOverlay folder (or the note why there is none) of :func:`kml`."""
    if g is None:
        return ""
    note = f"<description>{escape(str(g.get('note', '')))}</description>"
    if not g.get("href"):
        return note
    s, w, n, e = (f"{v:.8f}" for v in g["box"])
    return (
        f"{note}<Folder><name>Prior probability of containment</name><GroundOverlay>"
        f"<name>prior POC per cell</name><description>{escape(str(g.get('note', '')))}"
        f"</description><drawOrder>0</drawOrder><Icon><href>{escape(str(g['href']))}</href>"
        f"</Icon><LatLonBox><north>{n}</north><south>{s}</south><east>{e}</east><west>{w}</west>"
        "</LatLonBox></GroundOverlay></Folder>"
    )


def _kml_props(props: dict[str, Any]) -> str:
    """A search area's properties as one line of text (KML descriptions)."""
    return "; ".join(f"{k.replace('_', ' ')}: {v}" for k, v in props.items())


def _kml_coords(latlon, zs=None) -> str:
    if zs is None:
        return " ".join(f"{lon:.8f},{lat:.8f}" for lat, lon in latlon)
    return " ".join(f"{lon:.8f},{lat:.8f},{z:g}" for (lat, lon), z in zip(latlon, zs))


def _kml_placemark(o: dict, mode: str) -> str:
    name = escape(str(o["properties"]["name"]))
    head = f"<Placemark><name>{name}</name><styleUrl>#{o['properties']['kind']}</styleUrl>"
    if o["geometry"] == "Polygon":
        geom = (
            f"<Polygon><outerBoundaryIs><LinearRing><coordinates>{_kml_coords(o['latlon'])}"
            "</coordinates></LinearRing></outerBoundaryIs></Polygon>"
        )
    else:
        tag = o["geometry"]
        geom = (
            f"<{tag}><altitudeMode>{mode}</altitudeMode><coordinates>"
            f"{_kml_coords(o['latlon'], o['z'])}</coordinates></{tag}>"
        )
    return f"{head}{geom}</Placemark>"


def write(job: ExportJob) -> list[Path]:
    """``<stem>.kml`` and, when the prior can be placed, ``<stem>_prior.png`` (written first:
    the KML names it)."""
    overlay, note = plan_prior(job.plan, job.plan_path, job.prior)
    written = []
    g: dict[str, Any] = {"note": note}
    if overlay is not None:
        rgba, box = warp_prior(overlay, job.crs, "latitude")
        png = write_bytes_atomic(job.path("_prior.png"), png_bytes(rgba))
        g.update(href=png.name, box=box)
        written.append(png)
    text = kml(job.plan, job.crs, job.altitude_m, job.altitude_ref, job.ground_m, ground_overlay=g)
    return [write_text_atomic(job.path(".kml"), text), *written]
