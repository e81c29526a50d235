"""The prior overlay: the plan's prior probability of containment as a PNG on a lat/lon box.

The KML's GroundOverlay (``<stem>_prior.png``) and the HTML map report's image overlay are
this image, warped for each.

The prior
---------
plan.json records the scenario's name and ``map_source`` (``builtin`` or the map file given to
``poc-env plan --map``), not the grid, so :func:`plan_prior` rebuilds it: the scenario is loaded by
name (:func:`~poc_env.agents.mission.plan.scenario_source`: a built-in scenario, the YAML
file the plan records as
``scenario_file`` (``poc-env plan --scenario FILE.yaml``; else that file's name beside the plan),
or ``NAME.yaml`` beside the plan or in the current folder) and its prior built with
:func:`poc_env.theory.probability_map.build_prior`, from the recorded map file when there is one
(resolved as given, else beside the plan). Scenario overrides are not recorded in plan.json, so the
rebuilt scenario is checked against what the plan does record (its airfields, no-fly zones and
operating area); when they differ, or the scenario or map file cannot be found, the page says why
and draws no overlay rather than a wrong one. A caller with the prior at hand passes it
(``export_plan(..., prior=...)``: an array of the scenario's grid shape, or a ``.npy``/``.csv``
file) and it is used as given.

Warping: the grid lives in the plan's projected CRS; a web map stretches an image linearly in
Web Mercator (Leaflet ``imageOverlay``), Google Earth linearly in latitude and longitude (KML
``GroundOverlay``). :func:`warp_prior` therefore computes, for each output pixel centre, its
latitude and longitude (Mercator-spaced or evenly spaced rows), projects it into local metres
with :func:`~poc_env.agents.mission.crs.to_local` (pyproj) and takes the value of the grid cell
holding it (nearest cell, no interpolation: each pixel shows one cell's POC). Pixels outside the
grid are transparent. The colour is a fixed colormap (:data:`COLORMAP`, YlOrRd's five anchors,
linear between them) of the cell value over the grid's largest cell value; the alpha rises from
:data:`ALPHA_RANGE` ``[0]`` at zero to ``[1]`` at the maximum so the basemap shows through low
values. The PNG is written with Pillow (:func:`png_bytes`, a core dependency); the ramp's numbers
come from matplotlib's YlOrRd data, kept as a small table so matplotlib stays optional.
"""

from __future__ import annotations

import io
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.mission.crs import continuous_lon, to_geographic, to_local
from poc_env.agents.mission.plan import (
    Plan,
    map_file_candidates,
    scenario_not_found,
    scenario_source,
)
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import Grid

#: YlOrRd anchors, low to high: the overlay's colormap, linear between anchors. Taken once from
#: matplotlib's colormap data (``matplotlib.colormaps["YlOrRd"]``, ColorBrewer's nine classes;
#: every other one, times 255): tests/mission/test_report.py checks the equality when
#: matplotlib is installed, so the core install needs no matplotlib.
COLORMAP = np.array(
    [[255, 255, 204], [254, 217, 118], [253, 141, 60], [227, 26, 28], [128, 0, 38]], dtype=float
)
#: Overlay alpha (0-255) at zero and at the grid's largest cell value.
ALPHA_RANGE = (40, 230)
#: Longest side of the overlay image, pixels (at least 3 pixels per cell up to this size).
MAX_OVERLAY_PX = 1600
MIN_OVERLAY_PX = 512


@dataclass(frozen=True)
class PriorOverlay:
    """A prior grid (``values`` of shape ``grid.shape``) and where it came from."""

    grid: Grid
    values: np.ndarray
    source: str


def png_bytes(rgba: np.ndarray) -> bytes:
    """An RGBA image (H, W, 4) uint8 as PNG bytes (Pillow, zlib level 9)."""
    from PIL import Image

    img = np.ascontiguousarray(rgba, dtype=np.uint8)
    if img.ndim != 3 or img.shape[2] != 4 or img.shape[0] < 1 or img.shape[1] < 1:
        raise ConfigError("image", getattr(img, "shape", None), "an (H, W, 4) RGBA array")
    buf = io.BytesIO()
    Image.fromarray(img, "RGBA").save(buf, format="PNG", compress_level=9)
    return buf.getvalue()


def colorize(t: np.ndarray) -> np.ndarray:
    """Values in [0, 1] -> RGBA uint8 by :data:`COLORMAP` and :data:`ALPHA_RANGE`."""
    t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0)
    pos = t * (len(COLORMAP) - 1)
    k = np.minimum(pos.astype(int), len(COLORMAP) - 2)
    f = (pos - k)[..., None]
    rgb = COLORMAP[k] * (1 - f) + COLORMAP[k + 1] * f
    a = ALPHA_RANGE[0] + (ALPHA_RANGE[1] - ALPHA_RANGE[0]) * t
    return np.round(np.concatenate([rgb, a[..., None]], axis=-1)).astype(np.uint8)


def _mercator(lat_deg: np.ndarray) -> np.ndarray:
    return np.log(np.tan(np.pi / 4 + np.radians(lat_deg) / 2))


def _inverse_mercator(y: np.ndarray) -> np.ndarray:
    return np.degrees(2 * np.arctan(np.exp(y)) - np.pi / 2)


def overlay_bounds(grid: Any, crs: Any) -> tuple[float, float, float, float]:
    """(south, west, north, east) degrees enclosing the grid (its outline sampled densely;
    ``grid``: anything with ``bounds`` (x0, y0, x1, y1) in local metres). A grid across the
    180th meridian has ``east`` beyond 180 (OGC 07-147r2 section 9.14.3.4: "for overlays that
    overlap the meridian of 180 degrees longitude, values can extend beyond that range";
    Leaflet draws it so too), not a box around the globe."""
    x0, y0, x1, y1 = grid.bounds
    s = np.linspace(0.0, 1.0, 65)
    edge = np.concatenate(
        [
            np.stack([x0 + s * (x1 - x0), np.full_like(s, y0)], 1),
            np.stack([np.full_like(s, x1), y0 + s * (y1 - y0)], 1),
            np.stack([x0 + s * (x1 - x0), np.full_like(s, y1)], 1),
            np.stack([np.full_like(s, x0), y0 + s * (y1 - y0)], 1),
        ]
    )
    ll = np.array(to_geographic(edge, crs))
    lon = continuous_lon(ll[:, 1], crs)  # across the 180th meridian: east beyond 180
    return (float(ll[:, 0].min()), float(lon.min()), float(ll[:, 0].max()), float(lon.max()))


def warp_prior(
    ov: PriorOverlay, crs: Any, rows: str = "mercator"
) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """The prior as an RGBA image on a lat/lon box: ``(rgba, (south, west, north, east))``.

    ``rows``: ``mercator`` (rows evenly spaced in Web Mercator y: Leaflet's imageOverlay) or
    ``latitude`` (evenly spaced in latitude: KML GroundOverlay). Each pixel takes the colour of
    the grid cell under its centre (module docstring); outside the grid it is transparent.
    """
    if rows not in ("mercator", "latitude"):
        raise ConfigError("rows", rows, "mercator or latitude")
    south, west, north, east = overlay_bounds(ov.grid, crs)
    if rows == "mercator":
        top, bottom = float(_mercator(np.array(north))), float(_mercator(np.array(south)))
        height_units = top - bottom
    else:
        top, bottom = north, south
        height_units = math.radians(north - south) / max(
            math.cos(math.radians(0.5 * (north + south))), 1e-6
        )
    width_units = math.radians(east - west)
    cells = max(ov.grid.nx, ov.grid.ny)
    longest = int(min(MAX_OVERLAY_PX, max(MIN_OVERLAY_PX, 3 * cells)))
    scale = longest / max(width_units, height_units, 1e-12)
    w = max(2, round(width_units * scale))
    h = max(2, round(height_units * scale))
    v = top + (np.arange(h) + 0.5) / h * (bottom - top)
    lat = _inverse_mercator(v) if rows == "mercator" else v
    lon = west + (np.arange(w) + 0.5) / w * (east - west)
    glat, glon = np.meshgrid(lat, lon, indexing="ij")
    xy = np.array(to_local(np.stack([glat.ravel(), glon.ravel()], 1), crs)).reshape(h, w, 2)
    j, i = ov.grid.cell_of(xy)
    peak = float(np.max(ov.values))
    t = ov.values[j, i] / peak if peak > 0 else np.zeros((h, w))
    rgba = colorize(t)
    rgba[~ov.grid.contains(xy)] = 0
    return rgba, (south, west, north, east)


def contour_interval(lo: float, hi: float) -> float:
    """A round contour interval (1, 2 or 5 times a power of ten metres) giving about ten
    contours between heights ``lo`` and ``hi``."""
    span = max(hi - lo, 1.0) / 10.0
    mag = 10.0 ** math.floor(math.log10(span))
    return next(m * mag for m in (1.0, 2.0, 5.0, 10.0) if m * mag >= span)


def warp_terrain(t: Any, crs: Any) -> tuple[np.ndarray, tuple[float, float, float, float], float]:
    """A plan's terrain (:class:`poc_env.agents.mission.terrain.Terrain`) as a shaded-relief
    RGBA image with contour lines on a Web Mercator lat/lon box (Leaflet's imageOverlay):
    ``(rgba, (south, west, north, east), contour interval in metres)``.

    Hill shading: the bilinear ground's slope lit from the north-west at 45 degrees, in
    grey (dark on shadowed slopes, transparent on lit flat ground); contours: the pixels where
    the ground crosses a multiple of :func:`contour_interval`, in brown.
    """
    south, west, north, east = overlay_bounds(t, crs)
    top, bottom = float(_mercator(np.array(north))), float(_mercator(np.array(south)))
    width_units, height_units = math.radians(east - west), top - bottom
    ny, nx = t.ground_m.shape
    longest = int(min(MAX_OVERLAY_PX, max(MIN_OVERLAY_PX, 3 * max(nx, ny))))
    scale = longest / max(width_units, height_units, 1e-12)
    w, h = max(2, round(width_units * scale)), max(2, round(height_units * scale))
    lat = _inverse_mercator(top + (np.arange(h) + 0.5) / h * (bottom - top))
    lon = west + (np.arange(w) + 0.5) / w * (east - west)
    glat, glon = np.meshgrid(lat, lon, indexing="ij")
    xy = np.array(to_local(np.stack([glat.ravel(), glon.ravel()], 1), crs)).reshape(-1, 2)
    from poc_env.agents.mission.terrain import bilinear

    g = t.ground_m
    gy, gx = np.gradient(g, t.cell_m)  # rows from the south: gy is d/d(north)
    az, alt = math.radians(315.0), math.radians(45.0)
    slope = np.arctan(np.hypot(gx, gy))
    aspect = np.arctan2(-gx, -gy)  # direction the slope faces, clockwise from north
    lit = np.sin(alt) * np.cos(slope) + np.cos(alt) * np.sin(slope) * np.cos(az - aspect)
    shade = bilinear(lit, t.origin_m, t.cell_m, xy).reshape(h, w)
    z = bilinear(g, t.origin_m, t.cell_m, xy).reshape(h, w)
    interval = contour_interval(float(g.min()), float(g.max()))
    band = np.floor(z / interval)
    edge = np.zeros_like(band, dtype=bool)
    edge[:-1, :] |= band[:-1, :] != band[1:, :]
    edge[:, :-1] |= band[:, :-1] != band[:, 1:]
    rgba = np.zeros((h, w, 4), dtype=np.uint8)
    dark = np.clip((np.sin(alt) - shade) / np.sin(alt), 0.0, 1.0)  # 0 lit flat .. 1 shadow
    rgba[..., :3] = 40
    rgba[..., 3] = np.round(170 * dark).astype(np.uint8)
    rgba[edge] = (120, 70, 20, 200)
    x0, y0, x1, y1 = t.bounds
    inside = (xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1)
    rgba[~inside.reshape(h, w)] = 0
    return rgba, (south, west, north, east), interval


def plan_prior(
    plan: Plan, plan_path: str | os.PathLike[str], prior: Any = None
) -> tuple[PriorOverlay | None, str]:
    """The plan's prior grid and a note, or ``(None, why not)`` (see the module docstring).

    ``prior``: None (rebuild it from the plan's scenario and map source), an array of the
    scenario grid's shape, or a map file path (``.npy``/``.csv``, as ``poc-env plan --map``);
    a given prior that does not fit the scenario grid is a ConfigError.
    """
    from poc_env.config import load_scenario
    from poc_env.errors import MapFileError
    from poc_env.theory.probability_map import build_prior, load_map

    name = str(plan.get("scenario"))
    where = scenario_source(name, plan_path, plan.get("scenario_file"))
    if where is None:
        why = scenario_not_found(name, plan_path, plan)
        if prior is None:
            return None, f"no prior overlay: {why}"
        raise ConfigError("scenario", name, f"a scenario to place the prior on ({why})")
    sc = load_scenario(where)
    grid = Grid.from_config(sc.map)
    if prior is not None:
        if isinstance(prior, (str, Path)):
            values, source = load_map(prior, grid), str(prior)
        else:
            values, source = np.asarray(prior, dtype=float), "given"
            if values.shape != grid.shape or not np.all(np.isfinite(values)):
                raise ConfigError("prior", values.shape, f"finite values of shape {grid.shape}")
        return PriorOverlay(grid, values, source), f"prior: {source}"
    mismatch = _scenario_mismatch(plan, sc)
    if mismatch:
        return (
            None,
            f"no prior overlay: scenario {name!r} as built differs from the plan {mismatch}",
        )
    src = str(plan.get("map_source") or "builtin")
    if src == "builtin":
        return PriorOverlay(grid, build_prior(sc.map), f"{name} (built in)"), f"prior: {name}"
    for cand in map_file_candidates(src, plan_path):
        if cand.is_file():
            try:
                return PriorOverlay(grid, build_prior(sc.map, cand), str(cand)), f"prior: {cand}"
            except MapFileError as err:
                return None, f"no prior overlay: {err}"
    return None, f"no prior overlay: map file {src!r} not found"


def _scenario_mismatch(plan: Plan, sc: Any) -> str:
    """What the rebuilt scenario contradicts in the plan (airfields, zones, area), or ''."""
    fields = plan.get("airfields")
    if fields is not None:
        mine = [(a.name, [float(v) for v in a.position_m]) for a in sc.airfields]
        theirs = [(a["name"], [float(v) for v in a["position_m"]]) for a in fields]
        if mine != theirs:
            return "(airfields)"
    zones = plan.get("no_fly_zones_m")
    if zones is not None:
        mine_z = [[[float(v) for v in p] for p in z] for z in sc.map.no_fly_zones_m]
        if mine_z != [[[float(v) for v in p] for p in z] for z in zones]:
            return "(no-fly zones)"
    area = plan.get("operating_area_m")
    if area is not None:
        from poc_env.sim.core import make_params

        b = np.asarray(make_params(sc).bounds, dtype=float)
        a = np.asarray(area, dtype=float)
        if not np.allclose([a[:, 0].min(), a[:, 1].min(), a[:, 0].max(), a[:, 1].max()], b):
            return "(operating area)"
    return ""
