"""KML (Google Earth): per UAV a folder with its route, search areas and landing approach.

Beside the KML, ``<stem>_prior.png`` (:mod:`poc_env.agents.mission.overlay`) is the plan's
prior as a GroundOverlay: an image evenly spaced in latitude and longitude, drawn under
everything else. Without a prior (the scenario cannot be rebuilt) the document's description
says why.

The document is built with lxml (every text escaped by the serialiser) in the element order of
the OGC KML 2.2 schema (``ogckml22.xsd``: a Feature's ``name``, ``description``, ``styleUrl``,
then a Document's ``Style`` selectors, then its Features); :func:`validate_kml` checks a file
against that schema, vendored in ``agents/mission/assets/kml22`` so it works offline.
"""

from __future__ import annotations

import contextlib
import functools
from pathlib import Path
from typing import Any
from urllib.parse import quote

from lxml import etree

from poc_env.agents.mission.crs import continuous_lon, to_geographic
from poc_env.agents.mission.features import (
    APPROACH_KIND,
    altitudes,
    check_altitude_ref,
    layer_of,
    layer_text,
    layers_note,
    overlays,
    routes_3d,
)
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.overlay import plan_prior, png_bytes, warp_prior
from poc_env.agents.mission.plan import CLIMB_KIND, DESCENT_KIND, Plan, flight, search_rings
from poc_env.io import write_bytes_atomic, write_text_atomic

#: altitude reference -> KML altitudeMode
ALTITUDE_MODES = {"home": "relativeToGround", "amsl": "absolute"}
KML_NS = "http://www.opengis.net/kml/2.2"
SCHEMA = Path(__file__).resolve().parents[1] / "assets" / "kml22" / "ogckml22.xsd"

#: KML styles (colours aabbggrr): routes orange, approaches white, search rectangles and the
#: operating area outlined, no-fly zones filled red, airfields as the default pin. Each is
#: (id, [(sub-style, [(element, text)])]) in the schema's order.
_STYLES: tuple[tuple[str, tuple[tuple[str, tuple[tuple[str, str], ...]], ...]], ...] = (
    ("route", (("LineStyle", (("color", "ff00a5ff"), ("width", "2"))),)),
    (APPROACH_KIND, (("LineStyle", (("color", "ffffffff"), ("width", "2"))),)),
    (
        "rectangle",
        (
            ("LineStyle", (("color", "ffffff00"), ("width", "1.5"))),
            ("PolyStyle", (("fill", "0"),)),
        ),
    ),
    (
        "operating_area",
        (
            ("LineStyle", (("color", "ff00ffff"), ("width", "1.5"))),
            ("PolyStyle", (("fill", "0"),)),
        ),
    ),
    (
        "no_fly_zone",
        (
            ("LineStyle", (("color", "ff0000ff"), ("width", "1.5"))),
            ("PolyStyle", (("color", "660000ff"),)),
        ),
    ),
    ("airfield", (("IconStyle", (("scale", "1.1"),)),)),
)


def _el(parent: Any, tag: str, text: str | None = None, **attrib: str) -> Any:
    """A KML element under ``parent`` (text escaped by lxml)."""
    e = etree.SubElement(parent, f"{{{KML_NS}}}{tag}", attrib)
    if text is not None:
        e.text = text
    return e


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
    root = etree.Element(f"{{{KML_NS}}}kml", nsmap={None: KML_NS})
    doc = _el(root, "Document")
    _el(doc, "name", str(plan["scenario"]))
    g = ground_overlay
    if g is not None or plan.get("altitude_layers"):  # the note, the export's layers
        text = " ".join(v for v in (str((g or {}).get("note", "")), layers_note(plan)) if v)
        _el(doc, "description", text)
    for sid, subs in _STYLES:
        style = _el(doc, "Style", id=sid)
        for sub, fields in subs:
            s = _el(style, sub)
            for tag, text in fields:
                _el(s, tag, text)
    if g is not None and g.get("href"):
        folder = _el(doc, "Folder")
        _el(folder, "name", "Prior probability of containment")
        ov = _el(folder, "GroundOverlay")
        _el(ov, "name", "prior POC per cell")
        _el(ov, "description", str(g.get("note", "")))
        _el(ov, "drawOrder", "0")
        _el(_el(ov, "Icon"), "href", str(g["href"]))
        s, w, n, e = (f"{v:.8f}" for v in g["box"])
        box = _el(ov, "LatLonBox")
        for tag, text in (("north", n), ("south", s), ("east", e), ("west", w)):
            _el(box, tag, text)
    for u, (xy, zs) in zip(plan["uavs"], routes_3d(plan, alt, ground)):
        pts = to_geographic(xy, crs)
        uid = str(u["id"])
        folder = _el(doc, "Folder")
        _el(folder, "name", f"UAV {uid}")
        pm = _placemark(
            folder,
            f"UAV {uid} route",
            "route",
            f"POS {100 * u['pos']:.2f} %, track {u['track_length_m'] / 1000:.1f} km"
            f", {u['flight_time_s'] / 60:.0f} min, {_alt_text(plan, alt, altitude_ref, u)}; out "
            f"{3.6 * fl['transit_speed_mps']:.0f} km/h, search "
            f"{3.6 * fl['search_speed_mps']:.0f} km/h, home "
            f"{3.6 * fl['cruise_speed_mps']:.0f} km/h",
        )
        _line(pm, "LineString", mode, _kml_coords(pts, crs, zs))
        for kind, ring_m, props in search_rings(u):
            pm = _placemark(
                folder, f"UAV {uid} {kind.replace('_', ' ')}", "rectangle", _kml_props(props)
            )
            _polygon(pm, _kml_coords(to_geographic(ring_m, crs), crs))
        for o in extras:
            if o["properties"].get("id") == u["id"]:
                _kml_placemark(folder, o, mode, crs)
    folder = _el(doc, "Folder")
    _el(folder, "name", "Area, airfields, no-fly zones")
    for o in extras:
        if "id" not in o["properties"]:
            _kml_placemark(folder, o, mode, crs)
    body = etree.tostring(root, encoding="unicode")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + body + "\n"


def _alt_text(plan: Plan, alt: float, altitude_ref: str, u: Any) -> str:
    """The route's altitude rule in words: flat, or following the plan's terrain; and the UAV's
    altitude layer (:func:`~poc_env.agents.mission.features.with_layers`), if any."""
    t = plan.get("terrain")
    if t is None:
        return f"{alt + layer_of(u):g} m ({altitude_ref}{layer_text(u)})"
    return (
        f"{t['search_height_m']:g} m above ground where the climb allows{layer_text(u)}, at "
        f"least {t['min_clearance_m']:g} m, altitudes AMSL from {t['source']}"
    )


def _placemark(parent: Any, name: str, style: str, description: str | None = None) -> Any:
    """A Placemark with its name, description and style in the schema's order."""
    pm = _el(parent, "Placemark")
    _el(pm, "name", name)
    if description is not None:
        _el(pm, "description", description)
    _el(pm, "styleUrl", f"#{style}")
    return pm


def _line(parent: Any, tag: str, mode: str, coords: str) -> None:
    geom = _el(parent, tag)
    _el(geom, "altitudeMode", mode)
    _el(geom, "coordinates", coords)


def _polygon(parent: Any, coords: str) -> None:
    ring = _el(_el(_el(parent, "Polygon"), "outerBoundaryIs"), "LinearRing")
    _el(ring, "coordinates", coords)


def _kml_props(props: dict[str, Any]) -> str:
    """A search area's properties as one line of text (KML descriptions)."""
    return "; ".join(f"{k.replace('_', ' ')}: {v}" for k, v in props.items())


def _kml_coords(latlon: Any, crs: Any, zs: Any = None) -> str:
    """``lon,lat[,z]`` tuples, longitudes continuous around the map's origin
    (:func:`poc_env.crs.continuous_lon`): Google Earth joins two points the short way only when
    their longitudes are (a polygon from 179.9 to -179.9 is drawn around the globe); the OGC
    KML 2.2 schema's ``coordinates`` is a string that sets no range on them."""
    lats = [p[0] for p in latlon]
    lons = continuous_lon([p[1] for p in latlon], crs).tolist()
    if zs is None:
        return " ".join(f"{lon:.8f},{lat:.8f}" for lat, lon in zip(lats, lons))
    return " ".join(f"{lon:.8f},{lat:.8f},{z:g}" for lat, lon, z in zip(lats, lons, zs))


def _kml_placemark(parent: Any, o: dict, mode: str, crs: Any) -> None:
    kind = str(o["properties"]["kind"])
    flown = (CLIMB_KIND, DESCENT_KIND)  # the orbits are flown: a route's style
    style = "route" if kind in flown else kind
    pm = _placemark(parent, str(o["properties"]["name"]), style)
    if o["geometry"] == "Polygon":
        _polygon(pm, _kml_coords(o["latlon"], crs))
    else:
        _line(pm, o["geometry"], mode, _kml_coords(o["latlon"], crs, o["z"]))


@functools.lru_cache(maxsize=1)
def _schema() -> Any:
    return etree.XMLSchema(etree.parse(str(SCHEMA)))


def validate_kml(data: bytes | str | Path) -> list[str]:
    """The OGC KML 2.2 schema's complaints about a KML document (``[]``: valid).

    ``data``: the document's bytes or text, or a path to it. A document that is not well-formed
    XML is one complaint (lxml's parse error); no network access (the schema is vendored).

    One deviation from the XSD, which the KML reference itself makes: a ``LatLonBox`` across
    the antimeridian has its ``east`` beyond 180 ("for overlays that overlap the meridian of
    180 degrees longitude, values can extend beyond that range"), which the schema's
    ``maxInclusive`` of 180 refuses; such a box (``west <= 180 < east < west + 360``) is checked
    with ``east - 360`` in its place, and any other ``east`` above 180 is still a complaint.
    """
    if isinstance(data, Path):
        data = data.read_bytes()
    raw = data.encode("utf-8") if isinstance(data, str) else data
    try:
        doc = etree.fromstring(raw, etree.XMLParser(resolve_entities=False, no_network=True))
    except etree.XMLSyntaxError as err:
        return [f"not well-formed XML: {err}"]
    for box in doc.iter(f"{{{KML_NS}}}LatLonBox"):
        w, e = box.find(f"{{{KML_NS}}}west"), box.find(f"{{{KML_NS}}}east")
        with contextlib.suppress(TypeError, ValueError, AttributeError):
            west, east = float(w.text), float(e.text)  # type: ignore[union-attr, arg-type]
            if -180.0 <= west <= 180.0 < east < west + 360.0:
                e.text = repr(east - 360.0)  # type: ignore[union-attr]
    schema = _schema()
    if schema.validate(doc):
        return []
    return [f"line {e.line}: {e.message}" for e in schema.error_log]


def write(job: ExportJob) -> list[Path]:
    """``<stem>.kml`` and, when the prior can be placed, ``<stem>_prior.png`` (written first:
    the KML names it)."""
    overlay, note = plan_prior(job.plan, job.plan_path, job.prior)
    if overlay is None:  # said on the command line too, not only inside the file
        print(f"note: {note}")
    written = []
    g: dict[str, Any] = {"note": note}
    if overlay is not None:
        rgba, box = warp_prior(overlay, job.crs, "latitude")
        png = write_bytes_atomic(job.path("_prior.png"), png_bytes(rgba))
        g.update(href=quote(png.name), box=box)  # a URI reference: '#', '%', ' ' escaped
        written.append(png)
    text = kml(job.plan, job.crs, job.altitude_m, job.altitude_ref, job.ground_m, ground_overlay=g)
    return [write_text_atomic(job.path(".kml"), text), *written]
