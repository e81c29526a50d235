"""The HTML map report of a plan: one self-contained page a planning officer opens offline.

``poc-env export plan.json --format html`` (:func:`poc_env.agents.mission.export.export_plan`)
writes ``<stem>.html``: Leaflet 1.9.4 (vendored in ``agents/mission/assets/leaflet``,
BSD-2-Clause, inlined with its CSS and images) draws

- an OpenStreetMap tile basemap (online only; offline the tiles fail quietly and everything
  else is drawn),
- the plan's prior probability of containment as a coloured image overlay
  (:func:`poc_env.agents.mission.overlay.warp_prior`),
- per UAV its route in one colour, labelled ``UAV <id>`` where its search starts (transit legs
  dashed, the search pattern solid, the landing
  approach dotted), its search strips, rectangles or areas
  (:func:`~poc_env.agents.mission.plan.search_rings`),
- the airfields (named markers), the no-fly zones (red polygons) and the operating area,

with a layer control, a legend and a per-UAV table (flight time, distances, POD, POC, POS,
altitude). The table is static HTML: it reads without JavaScript. When the page has drawn every
layer, its script sets ``document.body.dataset.drawn`` to the number of overlay layers added.
"""

from __future__ import annotations

import base64
import functools
import html
import json
from pathlib import Path
from typing import Any

import jinja2
import numpy as np
from markupsafe import Markup

from poc_env.agents.mission.crs import continuous_lon, crs_text, to_geographic
from poc_env.agents.mission.features import layer_of, layer_text, layers_note, overlays, r6
from poc_env.agents.mission.job import ExportJob
from poc_env.agents.mission.overlay import (
    ALPHA_RANGE,
    COLORMAP,
    PriorOverlay,
    plan_prior,
    png_bytes,
    warp_prior,
)
from poc_env.agents.mission.plan import Plan, flight, route, search_rings, sortie_figures
from poc_env.io import write_text_atomic

ASSETS = Path(__file__).resolve().parents[1] / "assets" / "leaflet"
#: Route colours per UAV (cycled): blues, greens and purples, apart from the overlay's
#: yellow-red ramp and the red no-fly zones.
ROUTE_COLOURS = (
    "#1f5fd1", "#1a9e3f", "#7b3fbf", "#0aa5b8", "#d63fa8", "#4b4b4b", "#6b8e23", "#00008b",
)  # fmt: skip
TILE_URL = "https://tile.openstreetmap.org/{z}/{x}/{y}.png"
TILE_ATTRIBUTION = '&copy; <a href="https://www.openstreetmap.org/copyright">OpenStreetMap</a>'


def _latlon(points: Any, crs: Any) -> list[list[float]]:
    return _continuous(to_geographic(points, crs), crs)


def _continuous(latlon: Any, crs: Any) -> list[list[float]]:
    """``[lat, lon]`` rounded to 1e-6, longitudes continuous around the map's origin
    (:func:`poc_env.crs.continuous_lon`): Leaflet joins points straight in longitude, so a
    route from 179.9 to -179.9 would cross the whole map; at 180.1 it goes on past 180."""
    lons = continuous_lon([p[1] for p in latlon], crs)
    return [[r6(p[0]), r6(lon)] for p, lon in zip(latlon, lons)]


def _field_name(plan: Plan, xy: Any) -> str:
    for a in plan.get("airfields") or []:
        if np.hypot(*(np.asarray(a["position_m"], float) - np.asarray(xy, float))) < 1.0:
            return str(a["name"])
    return f"({xy[0] / 1e3:.1f}, {xy[1] / 1e3:.1f}) km"


def report_data(
    plan: Plan,
    crs: Any,
    overlay: PriorOverlay | None,
    alt: float,
    altitude_ref: str,
    ground: float,
) -> dict[str, Any]:
    """Everything the page's script draws, in lat/lon degrees (rounded to 1e-6)."""
    extra = overlays(plan, crs, alt, ground)
    uavs = []
    for k, u in enumerate(plan["uavs"]):
        wps = [list(w) for w in u["waypoints_m"]]
        start, end = list(u["takeoff_m"]), list(u["landing_m"])
        if wps:
            transit = [_latlon([start, wps[0]], crs), _latlon([wps[-1], end], crs)]
            search = _latlon(wps, crs) if len(wps) > 1 else []
        else:
            transit, search = [_latlon([start, end], crs)], []
        approach = [
            _continuous(o["latlon"], crs) for o in extra if o["properties"].get("id") == u["id"]
        ]
        rings = [{"kind": kind, "latlon": _latlon(ring, crs)} for kind, ring, _ in search_rings(u)]
        uavs.append(
            {
                "id": str(u["id"]),
                "colour": ROUTE_COLOURS[k % len(ROUTE_COLOURS)],
                "transit": transit,
                "search": search,
                "approach": approach,
                "rings": rings,
            }
        )
    overlay_doc = None
    if overlay is not None:
        rgba, (s, w, n, e) = warp_prior(overlay, crs, "mercator")
        url = "data:image/png;base64," + base64.b64encode(png_bytes(rgba)).decode("ascii")
        overlay_doc = {
            "url": url,
            "bounds": [[s, w], [n, e]],
            "peak": float(np.max(overlay.values)),
            "source": overlay.source,
        }
    terrain_doc = None
    rec = plan.get("terrain")
    if rec is not None:  # shaded relief and contours of the plan's DEM
        from poc_env.agents.mission.overlay import warp_terrain
        from poc_env.agents.mission.terrain import from_record

        t = from_record(rec)
        rgba, (s, w, n, e), interval = warp_terrain(t, crs)
        terrain_doc = {
            "url": "data:image/png;base64," + base64.b64encode(png_bytes(rgba)).decode("ascii"),
            "bounds": [[s, w], [n, e]],
            "name": f"Terrain ({t.source}; contours every {interval:g} m, "
            f"{float(t.ground_m.min()):.0f}-{float(t.ground_m.max()):.0f} m AMSL)",
        }
    polys = {"no_fly_zone": [], "operating_area": []}  # type: dict[str, list[Any]]
    for o in extra:
        kind = o["properties"]["kind"]
        if kind in polys:
            polys[kind].append(
                {
                    "name": o["properties"]["name"],
                    "latlon": _continuous(o["latlon"], crs),
                }
            )
    fields = [
        {"name": str(a["name"]), "latlon": _latlon([a["position_m"]], crs)[0]}
        for a in plan.get("airfields") or []
    ]
    if not fields:  # a plan without airfields: mark the take-off and landing points
        seen: list[list[float]] = []
        for u in plan["uavs"]:
            for p in (u["takeoff_m"], u["landing_m"]):
                if list(p) not in seen:
                    seen.append(list(p))
        fields = [{"name": _field_name(plan, p), "latlon": _latlon([p], crs)[0]} for p in seen]
    return {
        "scenario": str(plan["scenario"]),
        "uavs": uavs,
        "airfields": fields,
        "no_fly_zones": polys["no_fly_zone"],
        "operating_area": polys["operating_area"],
        "overlay": overlay_doc,
        "terrain": terrain_doc,
        "colormap": [[int(c) for c in row] for row in COLORMAP],
        "alpha": list(ALPHA_RANGE),
        "tiles": {"url": TILE_URL, "attribution": TILE_ATTRIBUTION},
    }


def expected_layers(plan: Plan, overlay: bool) -> int:
    """How many overlay layers the page adds (the ``data-drawn`` marker): the prior (if
    drawn), the terrain (if the plan has one), one per UAV route, the search areas, the
    airfields, the no-fly zones and the operating area (each when the plan has them; airfields
    always: take-off points stand in)."""
    rings = any(search_rings(u) for u in plan["uavs"])
    return (
        int(overlay)
        + int(plan.get("terrain") is not None)
        + len(plan["uavs"])
        + int(rings)
        + 1
        + int(bool(plan.get("no_fly_zones_m")))
        + int(bool(plan.get("operating_area_m")))
    )


def _inline_css() -> str:
    """leaflet.css with its images as data URIs (the page loads nothing but tiles)."""
    css = (ASSETS / "leaflet.css").read_text(encoding="utf-8")
    for img in sorted((ASSETS / "images").glob("*.png")):
        uri = "data:image/png;base64," + base64.b64encode(img.read_bytes()).decode("ascii")
        css = css.replace(f"url(images/{img.name})", f"url({uri})")
    return css


def _table(plan: Plan, alt: float, altitude_ref: str) -> str:
    from poc_env.agents.mission.terrain import departure_heading_deg, plan_profiles

    fl = flight(plan)
    profs = plan_profiles(plan)
    rows = []
    for k, u in enumerate(plan["uavs"]):
        alt_text = f"{alt + layer_of(u):g} ({altitude_ref}{layer_text(u)})"
        if profs is not None:  # the terrain profile: AMSL range and the least height
            p = profs[k]
            alt_text = (
                f"{float(p.amsl_m.min()):.0f}-{float(p.amsl_m.max()):.0f} (amsl{layer_text(u)}),"
                f" at least {float((p.amsl_m - p.ground_m).min()):.0f} above ground"
            )
            if p.climb is not None:  # the straight climb met the ground: an orbit first
                sp = p.climb
                alt_text += (
                    f"; climb spiral over the take-off field {sp.from_m:.0f}-{sp.to_m:.0f}, "
                    f"{sp.turns:.1f} turns of {sp.radius_m / 1e3:.2f} km, {sp.time_s / 60:.1f} "
                    "min not in the flight time"
                )
                if sp.depart_m > 0.0:  # its take-off climbs out on a heading of its own
                    alt_text += (
                        f" (take-off on heading {departure_heading_deg(sp):.0f} deg, "
                        f"{sp.depart_m / 1e3:.1f} km out, away from the rising ground)"
                    )
            if p.descent is not None:  # no straight glide cleared: an orbit to the glide
                o = p.descent.orbit
                alt_text += (
                    f"; descent orbit at the landing approach point {o.from_m:.0f}-{o.to_m:.0f},"
                    f" radius {o.radius_m / 1e3:.2f} km, {p.descent.time_s / 60:.1f} min not in "
                    "the flight time"
                )
        pts = np.asarray(route(u), dtype=float)
        route_km = float(np.sum(np.hypot(*np.diff(pts, axis=0).T))) / 1e3
        t = u["flight_time_s"]
        cells = [
            f'<span class="swatch" style="background:{ROUTE_COLOURS[k % len(ROUTE_COLOURS)]}">'
            f"</span>{html.escape(str(u['id']))}",
            html.escape(_field_name(plan, u["takeoff_m"])),
            html.escape(_field_name(plan, u["landing_m"])),
            f"{int(t // 3600)}:{int(t % 3600 // 60):02d}",
            f"{u['track_length_m'] / 1e3:.1f}",
            f"{route_km:.1f}",
            f"{u['spacing_m'] / 1e3:.2f}",
            f"{100 * u['pod']:.1f}",
            f"{100 * u['poc']:.1f}",
            f"{100 * u['pos']:.2f}",
            html.escape(alt_text),
            "yes" if u["feasible"] else "NO",
        ]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    head = (
        "UAV", "take-off", "landing", "flight time (h:min)", "search track (km)",
        "route (km, incl. transit)", "spacing (km)", "POD (%)", "POC (%)", "POS (%)",
        "altitude (m)", "within endurance",
    )  # fmt: skip
    speeds = (
        f"transit {3.6 * fl['cruise_speed_mps']:.0f} km/h, search "
        f"{3.6 * fl['search_speed_mps']:.0f} km/h"
    )
    return (
        '<table id="uav-table"><thead><tr>'
        + "".join(f"<th>{h}</th>" for h in head)
        + "</tr></thead><tbody>"
        + "".join(rows)
        + f'</tbody></table><p class="small">Speeds: {speeds}. Route: take-off field, '
        "search pattern, landing field (the landing approach is not counted)."
        + (" " + html.escape(layers_note(plan)) if plan.get("altitude_layers") else "")
        + "</p>"
    )


def html_report(
    plan: Plan,
    crs: Any,
    overlay: PriorOverlay | None,
    note: str,
    alt: float,
    altitude_ref: str,
    ground: float,
) -> str:
    """The self-contained page (module docstring)."""
    data = report_data(plan, crs, overlay, alt, altitude_ref, ground)
    payload = json.dumps(data, allow_nan=False).replace("<", "\\u003c")
    b: Any = plan.get("bounds") or {}
    bounds = (
        f"; bounds for the environment: honest {100 * b['honest']:.1f} %, reach-aware "
        f"{100 * b['reach']:.1f} %"
        if b
        else ""
    )
    title = f"poc-env plan: {plan['scenario']}"
    pos = f"POS_C {100 * plan['posc']:.2f} %"
    if sortie := sortie_figures(plan):  # a replanned sortie: what it finds, the search's POS
        pos = (
            f"sortie {sortie['sortie']:.0f}: POS_C {100 * sortie['sortie_posc']:.2f} % on the "
            f"belief the flights left (the planner's model {100 * plan['posc']:.2f} %), "
            f"cumulative {100 * sortie['cumulative_posc']:.2f} %"
        )
    summary = (
        f"scenario {plan['scenario']}, {len(plan['uavs'])} UAVs, {pos}{bounds}; "
        f"optimiser {plan['optimizer'].get('name')}, "
        f"seed {plan['seed']}; CRS {crs_text(crs) if isinstance(crs, dict) else crs}"
    )
    return _template().render(
        title=title,
        css=Markup(_inline_css()),
        js=Markup((ASSETS / "leaflet.js").read_text(encoding="utf-8")),
        summary=summary,
        note=note,
        table=Markup(_table(plan, alt, altitude_ref)),
        payload=Markup(payload),
        script=Markup(_SCRIPT),
    )


@functools.lru_cache(maxsize=1)
def _template() -> jinja2.Template:
    """:data:`_PAGE` compiled once, with autoescaping on."""
    env = jinja2.Environment(autoescape=True, keep_trailing_newline=True)
    return env.from_string(_PAGE)


#: The page (Jinja2, autoescaping on): ``title``, ``summary`` and ``note`` are plain text (escaped
#: by the template); ``css``, ``js``, ``script``, ``table`` and ``payload`` are trusted markup
#: (``Markup``: the vendored Leaflet, this module's script, the table whose cells are escaped
#: one by one, the plan data with ``<`` written as ``\\u003c``).
_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ title }}</title>
<style>{{ css }}</style>
<style>
body { margin: 0; font: 13px/1.35 system-ui, sans-serif; color: #222; }
header, section { padding: 6px 10px; }
h1 { font-size: 16px; margin: 0 0 2px 0; }
#map { height: 480px; }
table { border-collapse: collapse; }
th, td { border: 1px solid #bbb; padding: 2px 6px; text-align: right; }
th { background: #eee; }
.swatch { display: inline-block; width: 14px; height: 4px; margin: 0 4px 2px 0; }
.small { color: #555; font-size: 12px; }
.legend { background: rgba(255,255,255,0.9); padding: 6px 8px; border-radius: 4px;
  line-height: 1.5; }
.legend .ramp { width: 140px; height: 10px; }
.legend svg { vertical-align: middle; }
</style></head>
<body>
<header><h1>{{ title }}</h1><div class="small">{{ summary }}</div>
<div class="small" id="prior-note">{{ note }}</div></header>
<div id="map"></div>
<section>{{ table }}</section>
<script type="application/json" id="plan-data">{{ payload }}</script>
<script>{{ js }}</script>
<script>{{ script }}</script>
</body></html>
"""

_SCRIPT = r"""
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("plan-data").textContent);
  var map = L.map("map", {preferCanvas: false});
  var base = L.tileLayer(data.tiles.url, {maxZoom: 18, attribution: data.tiles.attribution});
  base.addTo(map);
  var overlays = {};
  var added = 0;
  var extent = L.latLngBounds([]);
  function add(name, layer) {
    layer.addTo(map);
    overlays[name] = layer;
    added += 1;
    if (layer.getBounds) { extent.extend(layer.getBounds()); }
  }
  function label(text) {
    var span = document.createElement("span");
    span.textContent = text;
    return span;
  }
  if (data.terrain) {
    add(data.terrain.name, L.imageOverlay(data.terrain.url, data.terrain.bounds, {opacity: 1.0}));
  }
  var image = null;
  if (data.overlay) {
    image = L.imageOverlay(data.overlay.url, data.overlay.bounds, {opacity: 1.0});
    add("Prior probability of containment", image);
  }
  // drawn as a map is read: the ground (above), the areas, the routes, the airfields on top
  if (data.operating_area.length) {
    var area = L.featureGroup();
    data.operating_area.forEach(function (z) {
      L.polygon(z.latlon, {color: "#555", weight: 1.5, dashArray: "4 4", fill: false})
        .bindTooltip(label(z.name)).addTo(area);
    });
    add("Operating area", area);
  }
  if (data.no_fly_zones.length) {
    var nfz = L.featureGroup();
    data.no_fly_zones.forEach(function (z) {
      L.polygon(z.latlon, {color: "#d00000", weight: 2, fillColor: "#ff0000", fillOpacity: 0.35})
        .bindTooltip(label(z.name)).addTo(nfz);
    });
    add("No-fly zones", nfz);
  }
  var areas = L.featureGroup();
  var nAreas = 0;
  data.uavs.forEach(function (u) {
    u.rings.forEach(function (r) {
      L.polygon(r.latlon, {color: u.colour, weight: 1.5, opacity: 0.6, fillOpacity: 0.06})
        .bindTooltip(label("UAV " + u.id + " " + r.kind.replace("_", " "))).addTo(areas);
      nAreas += 1;
    });
  });
  if (nAreas) { add("Search areas", areas); }
  data.uavs.forEach(function (u) {
    var g = L.featureGroup();
    u.transit.forEach(function (leg) {
      L.polyline(leg, {color: u.colour, weight: 3, dashArray: "8 6"}).addTo(g);
    });
    if (u.search.length > 1) {
      L.polyline(u.search, {color: u.colour, weight: 3}).addTo(g);
      // named on the map where its search starts: colours repeat beyond 8 UAVs
      L.circleMarker(u.search[0], {radius: 3, color: u.colour, weight: 2, fillOpacity: 1})
        .bindTooltip(label("UAV " + u.id), {permanent: true, direction: "top",
                                            className: "uav-label"}).addTo(g);
    }
    u.approach.forEach(function (leg) {
      L.polyline(leg, {color: u.colour, weight: 2, opacity: 0.7, dashArray: "2 4"}).addTo(g);
    });
    g.bindTooltip(label("UAV " + u.id));
    add("UAV " + u.id + " route", g);
  });
  var fields = L.featureGroup();
  data.airfields.forEach(function (a) {
    L.circleMarker(a.latlon, {radius: 6, color: "#000", weight: 2, fillColor: "#fff",
                              fillOpacity: 1}).bindTooltip(label(a.name), {permanent: true,
                              direction: "right"}).addTo(fields);
  });
  add("Airfields", fields);
  var view = extent.isValid() ? extent : L.latLngBounds([[-1, -1], [1, 1]]);
  map.fitBounds(view, {padding: [10, 10]});
  L.control.layers({"OpenStreetMap": base}, overlays, {collapsed: false}).addTo(map);
  L.control.scale({imperial: false}).addTo(map);
  var legend = L.control({position: "bottomright"});
  legend.onAdd = function () {
    var div = L.DomUtil.create("div", "legend");
    function row(svg, text) {
      var r = document.createElement("div");
      r.innerHTML = svg;
      r.appendChild(document.createTextNode(" " + text));
      div.appendChild(r);
    }
    if (data.overlay) {
      var stops = data.colormap.map(function (c, i) {
        var f = i / (data.colormap.length - 1);
        var a = (data.alpha[0] + (data.alpha[1] - data.alpha[0]) * f) / 255;
        return "rgba(" + c[0] + "," + c[1] + "," + c[2] + "," + a.toFixed(3) + ")";
      });
      var ramp = document.createElement("div");
      ramp.className = "ramp";
      ramp.style.background = "linear-gradient(to right, " + stops.join(", ") + ")";
      div.appendChild(document.createTextNode("Prior POC per cell"));
      div.appendChild(ramp);
      var peak = (100 * data.overlay.peak).toPrecision(3);
      div.appendChild(document.createTextNode("0 \u2013 " + peak + " % (cell maximum)"));
    }
    var line = function (dash) {
      return '<svg width="30" height="8"><line x1="0" y1="4" x2="30" y2="4" stroke="#333" ' +
        'stroke-width="3"' + (dash ? ' stroke-dasharray="' + dash + '"' : "") + "/></svg>";
    };
    row(line("6 4"), "transit");
    row(line(""), "search");
    row(line("2 3"), "landing approach");
    if (data.no_fly_zones.length) {
      row('<svg width="30" height="12"><rect x="1" y="1" width="28" height="10" fill="#ff0000" ' +
          'fill-opacity="0.35" stroke="#d00000"/></svg>', "no-fly zone");
    }
    row('<svg width="30" height="12"><circle cx="15" cy="6" r="5" fill="#fff" stroke="#000" ' +
        'stroke-width="2"/></svg>', "airfield");
    return div;
  };
  legend.addTo(map);
  function done() { document.body.dataset.drawn = String(added); }
  if (image) {
    if (image.getElement() && image.getElement().complete) { done(); }
    else { image.once("load", done); }
  } else {
    done();
  }
})();
"""


def write(job: ExportJob) -> list[Path]:
    """``<stem>.html``: the map report, its prior overlay from :func:`plan_prior`."""
    overlay, note = plan_prior(job.plan, job.plan_path, job.prior)
    if overlay is None:  # said on the command line too, not only inside the file
        print(f"note: {note}")
    if job.warning is not None:  # on the page too: a route QGC would not fly
        note = f"Warning: {job.warning}. {note}"
    page = html_report(
        job.plan, job.crs, overlay, note, job.altitude_m, job.altitude_ref, job.ground_m
    )
    return [write_text_atomic(job.path(".html"), page)]
