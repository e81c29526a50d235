"""Terrain: a DEM resampled onto the scenario, and mission altitudes that clear it (issue 24).

:func:`load_terrain` builds a :class:`Terrain` from a scenario's ``terrain`` section
(:class:`poc_env.config.TerrainConfig`): a GeoTIFF read through rasterio and resampled by
``rasterio.warp.reproject`` onto a grid aligned with the map that covers eq. 20's operating
area (the scenario's own projected CRS, the local metres of
:mod:`poc_env.agents.mission.crs`), or an elevation grid given in the scenario. Two layers: the
bilinear ground (``ground_m``, drawn by the map report) and the highest ground of each cell
(``ground_max_m``, ``Resampling.max``), which the clearance reads; the airfields' elevations
are sampled bilinearly from the DEM itself. A DEM without a CRS, one that does not cover the
operating area, or nodata/NaN over it is refused naming ``terrain.dem``. Heights are read in
metres (:func:`dem_metres`): the GeoTIFF's scale and offset applied, feet converted.

A plan records the terrain (``terrain`` of :mod:`poc_env.agents.mission.plan`,
:func:`terrain_record`), so an export needs no DEM. :func:`profile` gives a UAV's altitudes
(AMSL) along its mission, take-off field -> ``waypoints_m`` -> landing approach point:

- the wanted altitude is ``search_height_m`` (the UAV's cruise altitude) above the highest
  ground near each point (:meth:`Terrain.ground_at`: the cells within half a cell; at a sample,
  also the ground the points of the sub-legs either side of it read), at most the ceiling
  ``ceiling_m``;
- the required altitude is ``min_clearance_m`` above that ground; a required altitude above the
  ceiling is "clearance impossible within the UAV's ceiling", a ConfigError naming the UAV,
  the point and the ground;
- eq. 19 bounds the pitch by ``beta_max`` (``uav.max_pitch_deg``), so the altitude changes by at
  most ``tan(beta_max)`` per metre flown: the profile is the least such function above the
  wanted one (a forward and a backward pass), raised where a climb must start early; with a
  landing field, lowered where the descent must start early so that it keeps the same bound
  and the final glide from the approach point to the field is no steeper than the flat
  export's 300 m over 4 km (:data:`~poc_env.agents.mission.plan.LANDING_GLIDE`, under PX4's
  FW_LND_ANG) unless the clearance needs it steeper (warned; :func:`_glide_cap`; refused when
  it needs more height than a glide within the pitch bound allows);
- legs are sampled every half cell and where the cells a point reads change
  (:meth:`Terrain.window_changes`), so the straight legs between samples keep the clearance
  too; the profile keeps the route's vertices and, between them, the fewest intermediate
  points whose straight altitude legs stay above the required altitude and within
  :data:`PROFILE_TOLERANCE_M` below the profile.

The take-off item climbs to the profile's first altitude over the field, and the landing
approach point is the profile's last point; the climb from the field's elevation at
``tan(beta_max)`` along the first legs and the glide from the approach point to the field
must stay above the ground (:func:`_check_field_legs`).
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.mission.plan import (
    LANDING_GLIDE,
    MAX_GROUND_M,
    MAX_TERRAIN_CELLS,
    approach_point,
)
from poc_env.errors import ConfigError

#: How far the straight legs between kept profile points may sag below the profile (metres);
#: never below the required clearance.
PROFILE_TOLERANCE_M = 25.0
#: Finest default terrain cell (metres) when ``terrain.cell_km`` is not given.
DEFAULT_TERRAIN_CELL_M = 1000.0
#: The UAV's turn-rate bound (eq. 19) a plan's terrain record without one is read with: the
#: scenario default ``uav.max_turn_rate_deg_s`` = 3 deg/s (:class:`poc_env.config.UavConfig`).
DEFAULT_TURN_RATE_DEG_S = 3.0
#: Arc flown between two drawn points of a climb spiral (metres at most).
SPIRAL_STEP_M = 100.0
#: Arc between two points of a climb spiral's first turn where its ground is read (metres).
ORBIT_SAMPLE_M = 10.0


class GlideError(ConfigError):
    """A final glide to the landing field that cannot keep the ground from this approach
    point: :func:`landing_profile` tries the other sides of the field (then a descent orbit)
    before it refuses the mission."""


@dataclass(frozen=True)
class Terrain:
    """The ground under the operating area on a regular grid (rows from the south).

    Attributes
    ----------
    origin_m : (float, float)
        South-west corner of cell (0, 0), local metres.
    cell_m : float
    ground_m, ground_max_m : ndarray, shape (ny, nx)
        Bilinear ground and the highest ground of each cell, metres AMSL.
    fields : tuple of (name, (x, y), elevation_m)
        The airfields and their elevations (AMSL).
    min_clearance_m, search_height_m, ceiling_m, max_pitch_rad : float
        The clearance, the wanted height above ground, the UAV's ceiling (AMSL) and eq. 19's
        pitch bound.
    source : str
        Where the ground came from (the DEM's file name, or ``scenario``).
    turn_rate_rad_s : float
        Eq. 19's turn-rate bound: a climb spiral's radius is the speed over it.
    usable_endurance_s : float or None
        Eq. 18's 0.85 T, which a climb spiral's time is charged against (None: a plan recorded
        before it, not checked).
    max_climb_mps, max_sink_mps : float or None
        The aircraft's vertical rate limits (``uav.max_climb_rate_mps``,
        ``uav.max_sink_rate_mps``: PX4's FW_T_CLMB_MAX / FW_T_SINK_MAX): with them every
        altitude change is bounded by :func:`vertical_angle`; None: eq. 19's pitch alone.
    """

    origin_m: tuple[float, float]
    cell_m: float
    ground_m: np.ndarray
    ground_max_m: np.ndarray
    fields: tuple[tuple[str, tuple[float, float], float], ...]
    min_clearance_m: float
    search_height_m: float
    ceiling_m: float
    max_pitch_rad: float
    source: str
    turn_rate_rad_s: float = math.radians(DEFAULT_TURN_RATE_DEG_S)
    usable_endurance_s: float | None = None
    max_climb_mps: float | None = None
    max_sink_mps: float | None = None

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) of the grid, local metres."""
        ny, nx = self.ground_m.shape
        x0, y0 = self.origin_m
        return (x0, y0, x0 + nx * self.cell_m, y0 + ny * self.cell_m)

    def near_cells(self, xy: Any) -> tuple[np.ndarray, ...]:
        """Inclusive column and row index ranges ``(i_lo, i_hi, j_lo, j_hi)`` (clipped to the
        grid) of the 2 x 2 cells within half a cell of each point: the cells :meth:`ground_at`
        reads."""
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        ny, nx = self.ground_max_m.shape
        fx = (pts[:, 0] - self.origin_m[0]) / self.cell_m - 0.5
        fy = (pts[:, 1] - self.origin_m[1]) / self.cell_m - 0.5
        i0 = np.clip(np.floor(fx).astype(int), 0, nx - 1)
        j0 = np.clip(np.floor(fy).astype(int), 0, ny - 1)
        return i0, np.clip(i0 + 1, 0, nx - 1), j0, np.clip(j0 + 1, 0, ny - 1)

    def ground_at(self, xy: Any) -> np.ndarray:
        """The highest ground (``ground_max_m``) of the cells within half a cell of each point
        (the 2 x 2 cells around it, :meth:`near_cells`): a bound on the ground anywhere near
        it."""
        i0, i1, j0, j1 = self.near_cells(xy)
        g = self.ground_max_m
        return np.maximum.reduce([g[j0, i0], g[j0, i1], g[j1, i0], g[j1, i1]])

    def window_changes(self, a: Any, b: Any) -> np.ndarray:
        """The fractions ``s`` in (0, 1) of the segment ``a -> b`` where the cells
        :meth:`ground_at` reads change: where it crosses a line through the cells' centres
        (``floor(f - 0.5)`` steps there). Between two of them every point reads the same
        cells."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        out = []
        for k in (0, 1):
            d = b[k] - a[k]
            if d == 0.0:
                continue
            f0, f1 = sorted(
                ((a[k], b[k])[m] - self.origin_m[k]) / self.cell_m - 0.5 for m in (0, 1)
            )
            lines = np.arange(math.ceil(f0), math.floor(f1) + 1)
            out.append((self.origin_m[k] + (lines + 0.5) * self.cell_m - a[k]) / d)
        s = np.concatenate(out) if out else np.zeros(0)
        return s[(s > 0.0) & (s < 1.0)]

    def field_elevation(self, xy: Any) -> float:
        """The elevation of the airfield at ``xy`` (within 1 m), else the bilinear ground."""
        x, y = (float(v) for v in xy)
        for _, (fx, fy), elev in self.fields:
            if math.hypot(fx - x, fy - y) <= 1.0:
                return float(elev)
        return float(bilinear(self.ground_m, self.origin_m, self.cell_m, [[x, y]])[0])


def bilinear(grid: np.ndarray, origin: Any, cell: float, xy: Any) -> np.ndarray:
    """Bilinear interpolation of a cell-centred grid (rows from the south) at local points."""
    pts = np.asarray(xy, dtype=float).reshape(-1, 2)
    ny, nx = grid.shape
    fx = np.clip((pts[:, 0] - origin[0]) / cell - 0.5, 0, nx - 1)
    fy = np.clip((pts[:, 1] - origin[1]) / cell - 0.5, 0, ny - 1)
    i0, j0 = (
        np.minimum(fx.astype(int), nx - 2 if nx > 1 else 0),
        np.minimum(fy.astype(int), ny - 2 if ny > 1 else 0),
    )
    i1, j1 = np.minimum(i0 + 1, nx - 1), np.minimum(j0 + 1, ny - 1)
    tx, ty = fx - i0, fy - j0
    return (
        grid[j0, i0] * (1 - tx) * (1 - ty)
        + grid[j0, i1] * tx * (1 - ty)
        + grid[j1, i0] * (1 - tx) * ty
        + grid[j1, i1] * tx * ty
    )


# --------------------------------------------------------------------------- loading


def load_terrain(sc: Any) -> Terrain | None:
    """The scenario's terrain (module docstring), or None when its ``terrain`` gives none.

    Raises
    ------
    ConfigError
        Naming ``terrain.dem`` / ``terrain.elevation_m``: no CRS, not covering the operating
        area, nodata or NaN over it, unreadable; or a scenario without ``map.origin_deg``.
    """
    t = sc.terrain
    if not t.given:
        return None
    from poc_env.sim.core import operating_area

    area = operating_area(sc)
    if t.elevation_m is not None:
        grid = np.asarray(t.elevation_m, dtype=float)
        cell = t.cell_m or sc.map.cell_m
        origin = t.origin_m or (area[0], area[1])
        ny, nx = grid.shape
        have = (origin[0], origin[1], origin[0] + nx * cell, origin[1] + ny * cell)
        _check_covers("terrain.elevation_m", have, area)
        gmax, gmean, source = grid, grid, "scenario"
        fields = tuple(
            (a.name, a.position_m, float(_cell_value(grid, origin, cell, a.position_m)))
            for a in sc.airfields
        )
    else:
        cell = t.cell_m or min(sc.map.cell_m, DEFAULT_TERRAIN_CELL_M)
        origin, shape = _aligned_grid(sc, area, cell)
        gmean, gmax, elev = _read_dem(sc, Path(str(t.dem)), origin, shape, cell, area)
        source = Path(str(t.dem)).name
        fields = tuple((a.name, a.position_m, e) for a, e in zip(sc.airfields, elev))
    key = "terrain.elevation_m" if t.elevation_m is not None else "terrain.dem"
    heights = np.concatenate([np.ravel(gmax), np.ravel(gmean), [e for _, _, e in fields]])
    worst = float(np.max(np.abs(heights))) if heights.size else 0.0
    if not worst <= MAX_GROUND_M:  # a plan could not record it (NaN is refused too)
        raise ConfigError(
            key, f"{source}: a height of {worst:g} m over the operating area",
            f"ground heights within +-{MAX_GROUND_M:g} m of sea level (metres AMSL; feet or "
            "a nodata value not declared?)",
        )  # fmt: skip
    return Terrain(
        origin_m=(float(origin[0]), float(origin[1])),
        cell_m=float(cell),
        ground_m=gmean,
        ground_max_m=gmax,
        fields=tuple((n, (float(p[0]), float(p[1])), float(e)) for n, p, e in fields),
        min_clearance_m=float(t.min_clearance_m),
        search_height_m=float(sc.uav.cruise_altitude_m),
        ceiling_m=float(sc.uav.max_altitude_m),
        max_pitch_rad=float(sc.uav.max_pitch_rad),
        source=source,
        turn_rate_rad_s=float(sc.uav.max_turn_rate_rad_s),
        usable_endurance_s=float(sc.uav.usable_endurance_s),
        max_climb_mps=sc.uav.max_climb_rate_mps,
        max_sink_mps=sc.uav.max_sink_rate_mps,
    )


def _cell_value(grid: np.ndarray, origin: Any, cell: float, xy: Any) -> float:
    ny, nx = grid.shape
    i = min(max(int((xy[0] - origin[0]) // cell), 0), nx - 1)
    j = min(max(int((xy[1] - origin[1]) // cell), 0), ny - 1)
    return float(grid[j, i])


def _check_covers(field: str, have: tuple, need: tuple, value: Any = None) -> None:
    eps = 1e-6
    if not (
        have[0] <= need[0] + eps
        and have[1] <= need[1] + eps
        and have[2] >= need[2] - eps
        and have[3] >= need[3] - eps
    ):
        km = [round(v / 1e3, 3) for v in need]
        got = [round(v / 1e3, 3) for v in have]
        raise ConfigError(
            field,
            value if value is not None else f"a grid over x, y = {got} km",
            f"ground covering the whole operating area (eq. 20) x0, y0, x1, y1 = {km} km",
        )


def _aligned_grid(sc: Any, area: tuple, cell: float) -> tuple[tuple[float, float], tuple]:
    """South-west corner and (ny, nx) of the grid of ``cell`` aligned with the map's origin
    that covers ``area``."""
    mx, my = sc.map.origin_m
    i0 = math.floor((area[0] - mx) / cell + 1e-9)
    j0 = math.floor((area[1] - my) / cell + 1e-9)
    i1 = math.ceil((area[2] - mx) / cell - 1e-9)
    j1 = math.ceil((area[3] - my) / cell - 1e-9)
    ny, nx = j1 - j0, i1 - i0
    if nx * ny > MAX_TERRAIN_CELLS:
        raise ConfigError(
            "terrain.cell_km", cell / 1e3,
            f"a cell giving at most {MAX_TERRAIN_CELLS} terrain cells over the operating area "
            f"(it gives {nx} x {ny})",
        )  # fmt: skip
    return (mx + i0 * cell, my + j0 * cell), (ny, nx)


def _read_dem(sc: Any, path: Path, origin: tuple, shape: tuple, cell: float, area: tuple) -> tuple:
    """(bilinear ground, cell-max ground, airfield elevations) from the GeoTIFF ``path``.

    The DEM must cover the operating area ``area`` (x0, y0, x1, y1); the grid's outer cells,
    aligned with the map, may reach beyond it and beyond the DEM (reproject fills them from the
    DEM's pixels they overlap; a cell it cannot fill is refused as nodata)."""
    from poc_env.errors import require_extra

    require_extra("geo", "a terrain.dem GeoTIFF", "rasterio")
    import rasterio
    from pyproj import Transformer
    from rasterio.errors import RasterioError, RasterioIOError
    from rasterio.transform import Affine
    from rasterio.warp import Resampling, reproject

    from poc_env.agents.mission.crs import crs_text, make_crs

    field = "terrain.dem"
    m = sc.map
    if m.origin_deg is None:
        raise ConfigError(
            field, str(path), "a DEM in a scenario with map.origin_deg (the map's (0, 0) in "
            "lat, lon places it)",
        )  # fmt: skip
    if not path.is_file():
        raise ConfigError(field, str(path), "an existing GeoTIFF file of ground heights (m AMSL)")
    rec = make_crs(m.projection, m.origin_deg, zone=m.utm_zone)
    dst_crs = crs_text(rec)
    lat0, lon0 = m.origin_deg
    fwd = Transformer.from_crs("EPSG:4326", dst_crs, always_xy=True)
    px0, py0 = fwd.transform(lon0, lat0)
    ny, nx = shape
    dst_transform = Affine(cell, 0.0, origin[0] + px0, 0.0, -cell, origin[1] + ny * cell + py0)
    try:
        src = rasterio.open(path)
    except RasterioIOError as err:
        raise ConfigError(field, f"{path} unreadable ({err})", "a GeoTIFF file") from None
    try:
        with src:
            if src.crs is None:
                raise ConfigError(
                    field, str(path),
                    "a GeoTIFF with a coordinate reference system (georeference it in your GIS)",
                )  # fmt: skip
            _check_vertical_datum(field, path, src.crs)
            from poc_env import limits

            limits.check_memory(field, str(path), 8.0 * src.width * src.height, "DEM band")
            band = dem_metres(src, src.read(1, masked=True).astype(float).filled(np.nan))
            band[~np.isfinite(band)] = np.nan
            _check_dem_covers(field, path, src, dst_crs, px0, py0, area)
            out = {}
            for name, how in (("mean", Resampling.bilinear), ("max", Resampling.max)):
                dst = np.full((ny, nx), np.nan)
                reproject(
                    band, dst, src_transform=src.transform, src_crs=src.crs, src_nodata=np.nan,
                    dst_transform=dst_transform, dst_crs=dst_crs, dst_nodata=np.nan,
                    resampling=how,
                )  # fmt: skip
                out[name] = dst[::-1].copy()  # rows from the south
            # a nodata pixel the resampling would fill from its neighbours (a peak under it
            # would be invisible to the clearance): any under a cell of the area is refused
            holes = np.zeros((ny, nx))
            reproject(
                np.isnan(band).astype(float), holes, src_transform=src.transform,
                src_crs=src.crs, dst_transform=dst_transform, dst_crs=dst_crs,
                resampling=Resampling.max,
            )  # fmt: skip
            out["max"][(holes[::-1] > 0) & _cells_in(origin, shape, cell, area)] = np.nan
            elev = _sample_fields(field, sc, band, src, rec)
    except RasterioError as err:
        raise ConfigError(field, f"{path} unreadable ({err})", "a complete GeoTIFF") from None
    bad = ~(np.isfinite(out["mean"]) & np.isfinite(out["max"]))
    if bad.any():  # a count and a share that a small hole does not round to 0
        raise ConfigError(
            field, f"nodata or NaN at {int(bad.sum())} of the {bad.size} cells of the "
            f"operating area's terrain grid ({100 * bad.mean():.3g} %, {path.name})",
            "a DEM with a height at every point of the operating area (fill the voids)",
        )  # fmt: skip
    gmax = np.maximum(out["max"], out["mean"])
    return out["mean"], gmax, elev


def _check_vertical_datum(field: str, path: Path, crs: Any) -> None:
    """Refuse a DEM whose CRS declares **ellipsoidal** heights (a geographic or projected 3D CRS
    on WGS84's ellipsoid, e.g. EPSG:4979): the missions fly altitudes above mean sea level
    (QGC's MAV_FRAME_GLOBAL, the autopilot's GPS MSL altitude, KML ``absolute``), and an
    ellipsoidal height differs from it by the geoid undulation, -106 m to +85 m over the Earth:
    where it is negative the ground would be read that much too low and the clearance cut by
    it. Converting needs a geoid grid (e.g. PROJ's ``us_nga_egm96_15.tif``), which pyproj does
    not ship: without it PROJ's only transformation is a "ballpark" one that changes nothing.
    A 2D CRS (no vertical axis) or a compound CRS with a gravity-related height (EGM96,
    EGM2008, NAVD88, ...) is read as heights above mean sea level, as before."""
    from pyproj import CRS

    c = CRS.from_wkt(crs.to_wkt())
    axes = [a.name.lower() for a in c.axis_info]
    if "ellipsoidal height" in axes:
        raise ConfigError(
            field, f"{path.name}: ellipsoidal heights ({c.name})",
            "a DEM of heights above mean sea level (a 2D CRS, or a compound CRS with a "
            "gravity-related height such as EGM96 / EGM2008): convert it first, e.g. gdalwarp "
            "-t_srs EPSG:4326+5773 with PROJ's geoid grid us_nga_egm96_15.tif installed",
        )  # fmt: skip


def _cells_in(origin: tuple, shape: tuple, cell: float, area: tuple) -> np.ndarray:
    """Which cells of the terrain grid (``origin`` its south-west corner, rows from the south)
    overlap the operating area ``area`` (x0, y0, x1, y1) by more than a millimetre."""
    ny, nx = shape
    x = origin[0] + np.arange(nx) * cell
    y = origin[1] + np.arange(ny) * cell
    in_x = (np.minimum(x + cell, area[2]) - np.maximum(x, area[0])) > 1e-3
    in_y = (np.minimum(y + cell, area[3]) - np.maximum(y, area[1])) > 1e-3
    return in_y[:, None] & in_x[None, :]


#: The height units a DEM band may declare (GDAL's unit type, lower case): metres per unit.
#: An empty unit is read as metres (the scenario's ``terrain.dem``: metres AMSL).
HEIGHT_UNITS = {
    **dict.fromkeys(("", "m", "metre", "metres", "meter", "meters"), 1.0),
    **dict.fromkeys(("ft", "foot", "feet", "international foot"), 0.3048),
    **dict.fromkeys(("us-ft", "ftus", "us survey foot", "us survey feet"), 1200.0 / 3937.0),
}


def dem_metres(src: Any, raw: np.ndarray, field: str = "terrain.dem") -> np.ndarray:
    """Band 1 of the open GeoTIFF ``src`` (``raw``, as stored) in metres: GDAL's scale and offset
    applied (``raw x scale + offset``, as an int16 of decimetres declares), then the band's
    height unit (:data:`HEIGHT_UNITS`: metres, feet or US survey feet).

    Raises
    ------
    ConfigError
        Naming ``field``: a unit other than those.
    """
    unit = str((src.units or (None,))[0] or "").strip()
    factor = HEIGHT_UNITS.get(unit.lower())
    if factor is None:
        raise ConfigError(
            field, f"{Path(src.name).name}: heights in {unit!r}",
            "a DEM whose band declares its heights in metres or feet (or no unit: metres)",
        )  # fmt: skip
    scale = float((src.scales or (1.0,))[0])
    offset = float((src.offsets or (0.0,))[0])
    return (np.asarray(raw, dtype=float) * scale + offset) * factor


def _check_dem_covers(
    field: str, path: Path, src: Any, dst_crs: str, px0: float, py0: float, need: tuple
) -> None:
    """The operating area's densified boundary, taken into the DEM's pixels, lies on it."""
    from pyproj import Transformer

    x0, y0, x1, y1 = need
    t = np.linspace(0.0, 1.0, 41)
    ring = np.concatenate(
        [
            np.column_stack([x0 + (x1 - x0) * t, np.full_like(t, y0)]),
            np.column_stack([np.full_like(t, x1), y0 + (y1 - y0) * t]),
            np.column_stack([x1 - (x1 - x0) * t, np.full_like(t, y1)]),
            np.column_stack([np.full_like(t, x0), y1 - (y1 - y0) * t]),
        ]
    )
    to_src = Transformer.from_crs(dst_crs, src.crs, always_xy=True)
    sx, sy = to_src.transform(ring[:, 0] + px0, ring[:, 1] + py0)
    cols, rows = ~src.transform @ (np.asarray(sx), np.asarray(sy))
    cols, rows = np.asarray(cols), np.asarray(rows)
    ok = np.isfinite(cols) & (cols >= 0) & (cols <= src.width) & (rows >= 0) & (rows <= src.height)
    if not ok.all():
        raise ConfigError(
            field, f"a DEM covering {ok.mean():.0%} of the operating area's boundary ({path.name})",
            "a DEM covering the whole operating area (eq. 20: the map and the airfields, "
            "grown by episode.boundary_margin_km) x0, y0, x1, y1 = "
            f"{[round(v / 1e3, 3) for v in need]} km",
        )  # fmt: skip


def _sample_fields(field: str, sc: Any, band: np.ndarray, src: Any, rec: dict) -> list[float]:
    """Each airfield's elevation, bilinear from the DEM's own pixels."""
    from pyproj import Transformer

    from poc_env.agents.mission.crs import to_geographic

    ll = to_geographic([a.position_m for a in sc.airfields], rec)
    to_src = Transformer.from_crs("EPSG:4326", src.crs, always_xy=True)
    out = []
    for a, (lat, lon) in zip(sc.airfields, ll):
        sx, sy = to_src.transform(lon, lat)
        c, r = ~src.transform @ (sx, sy)
        value = float(bilinear(band[::-1], (0.0, 0.0), 1.0, [[c, band.shape[0] - r]])[0])
        if not math.isfinite(value):
            raise ConfigError(
                field, f"nodata at airfield {a.name!r}", "a DEM with a height at every airfield"
            )
        out.append(value)
    return out


# --------------------------------------------------------------------------- plan record


def terrain_record(t: Terrain) -> dict[str, Any]:
    """The plan.json ``terrain`` record of ``t`` (heights rounded to 0.1 m)."""
    return {
        "origin_m": [t.origin_m[0], t.origin_m[1]],
        "cell_m": t.cell_m,
        "ground_m": np.round(t.ground_m, 1).tolist(),
        "ground_max_m": np.round(np.ceil(t.ground_max_m * 10) / 10, 1).tolist(),
        "fields": [
            {"name": n, "position_m": [p[0], p[1]], "elevation_m": round(e, 1)}
            for n, p, e in t.fields
        ],
        "min_clearance_m": t.min_clearance_m,
        "search_height_m": t.search_height_m,
        "ceiling_m": t.ceiling_m,
        "max_pitch_deg": math.degrees(t.max_pitch_rad),
        "source": t.source,
        "max_turn_rate_deg_s": math.degrees(t.turn_rate_rad_s),
        **({} if t.usable_endurance_s is None else {"usable_endurance_s": t.usable_endurance_s}),
        **({} if t.max_climb_mps is None else {"max_climb_rate_mps": t.max_climb_mps}),
        **({} if t.max_sink_mps is None else {"max_sink_rate_mps": t.max_sink_mps}),
    }


def from_record(rec: dict[str, Any]) -> Terrain:
    """The :class:`Terrain` a plan records (:func:`terrain_record`)."""
    return Terrain(
        origin_m=(float(rec["origin_m"][0]), float(rec["origin_m"][1])),
        cell_m=float(rec["cell_m"]),
        ground_m=np.asarray(rec["ground_m"], dtype=float),
        ground_max_m=np.asarray(rec["ground_max_m"], dtype=float),
        fields=tuple(
            (
                str(f["name"]),
                (float(f["position_m"][0]), float(f["position_m"][1])),
                float(f["elevation_m"]),
            )
            for f in rec["fields"]
        ),
        min_clearance_m=float(rec["min_clearance_m"]),
        search_height_m=float(rec["search_height_m"]),
        ceiling_m=float(rec["ceiling_m"]),
        max_pitch_rad=math.radians(float(rec["max_pitch_deg"])),
        source=str(rec["source"]),
        turn_rate_rad_s=math.radians(
            float(rec.get("max_turn_rate_deg_s", DEFAULT_TURN_RATE_DEG_S))
        ),
        usable_endurance_s=(
            None if rec.get("usable_endurance_s") is None else float(rec["usable_endurance_s"])
        ),
        max_climb_mps=(
            None if rec.get("max_climb_rate_mps") is None else float(rec["max_climb_rate_mps"])
        ),
        max_sink_mps=(
            None if rec.get("max_sink_rate_mps") is None else float(rec["max_sink_rate_mps"])
        ),
    )


def vertical_angle(t: Terrain, speed_mps: float, climb: bool) -> float:
    """The steepest climb (``climb``) or descent the aircraft flies at ``speed_mps``, as an
    angle (rad): eq. 19's pitch bound ``beta_max``, or less where the aircraft's vertical rate
    limit ``t.max_climb_mps`` / ``t.max_sink_mps`` (PX4's FW_T_CLMB_MAX / FW_T_SINK_MAX) binds
    first, ``atan(rate / v)``. The one bound of every altitude change of a mission over
    terrain: the profile's passes, the take-off climb, the climb spiral, the final glide and
    the descent orbit, and their times. Without a limit, ``beta_max`` itself (eq. 19 alone)."""
    rate = t.max_climb_mps if climb else t.max_sink_mps
    if rate is None or math.tan(t.max_pitch_rad) * speed_mps <= rate:
        return t.max_pitch_rad
    return math.atan(rate / speed_mps)


def _speed(speed_mps: float | None) -> float:
    """``speed_mps``, or the paper's 220 km/h transit speed
    (:data:`~poc_env.agents.mission.plan.DEFAULT_FLIGHT`) when None."""
    from poc_env.agents.mission.plan import DEFAULT_FLIGHT

    return float(DEFAULT_FLIGHT["transit_speed_mps"] if speed_mps is None else speed_mps)


def _bound_text(t: Terrain) -> str:
    """What bounds a mission's climbs and descents, for a refusal: eq. 19's pitch, and the
    aircraft's rates where given."""
    text = f"eq. 19's pitch bound uav.max_pitch_deg = {math.degrees(t.max_pitch_rad):g} deg"
    rates = [
        f"{key} = {v:g} m/s"
        for key, v in (
            ("uav.max_climb_rate_mps", t.max_climb_mps),
            ("uav.max_sink_rate_mps", t.max_sink_mps),
        )
        if v is not None
    ]
    return text + (f" and the rates {', '.join(rates)}" if rates else "")


# --------------------------------------------------------------------------- profiles


@dataclass(frozen=True)
class Spiral:
    """A climb spiral over the take-off field (issue 24, F3 of results/audit/dayaudit).

    The UAV takes off to ``from_m`` (at least the field's elevation plus the clearance; more
    where the ground under the orbit needs it), then orbits the field clockwise at eq. 19's
    turn-rate bound, radius ``speed / turn rate``, climbing at eq. 19's ``tan(beta_max)`` per
    metre flown up to ``to_m``, from where the straight climb along the mission keeps the
    clearance (:func:`climb_spiral`). QGC flies it as MAV_CMD_NAV_LOITER_TO_ALT (31) at the
    field.

    Attributes
    ----------
    center_m : (float, float)
        The take-off field, local metres.
    radius_m, from_m, to_m, speed_mps, pitch_rad : float
        The orbit's radius, its first and last altitude (AMSL), the speed flown on it and the
        pitch it climbs at.
    start_rad : float
        The angle (from east, counter-clockwise) of its first point round the field: the
        heading the take-off climbs out on to ``from_m``.
    depart_m : float
        The take-off climb's length (to ``from_m``) where it departs on a heading of its own,
        away from the first waypoint (i24-missionfix: the straight climb towards it meets the
        ground, :func:`departure_spiral`); 0 where it climbs out towards the first waypoint,
        along the route (as before).
    """

    center_m: tuple[float, float]
    radius_m: float
    from_m: float
    to_m: float
    speed_mps: float
    pitch_rad: float
    start_rad: float
    depart_m: float = 0.0

    @property
    def length_m(self) -> float:
        """The horizontal distance flown on the orbit: the climb (or descent) over
        ``tan(beta_max)``."""
        return abs(self.to_m - self.from_m) / math.tan(self.pitch_rad)

    @property
    def time_s(self) -> float:
        """The orbit's flight time, at ``speed_mps``: what the 2-D time model does not fly.
        With a departure of its own (``depart_m``), also the climb out and the way back to the
        field, charged as twice its length (the 2-D model flies the route from the field)."""
        return (self.length_m + 2.0 * self.depart_m) / self.speed_mps

    @property
    def depart_xy(self) -> tuple[float, float]:
        """Where the take-off climb reaches ``from_m``: ``depart_m`` out on ``start_rad``
        (the field itself without a departure of its own)."""
        c, d = self.center_m, self.depart_m
        return (c[0] + d * math.cos(self.start_rad), c[1] + d * math.sin(self.start_rad))

    def departure(self, field_m: float) -> tuple[np.ndarray, np.ndarray]:
        """``(xy, amsl)`` of the departure drawn before the orbit: the field (at its elevation
        ``field_m``), the point the climb reaches ``from_m``, then the orbit's first point
        (empty arrays without a departure of its own)."""
        if self.depart_m <= 0.0:
            return np.zeros((0, 2)), np.zeros(0)
        a = self.start_rad
        ring = (self.center_m[0] + self.radius_m * math.cos(a),
                self.center_m[1] + self.radius_m * math.sin(a))  # fmt: skip
        xy = np.array([self.center_m, self.depart_xy, ring], dtype=float)
        return xy, np.array([field_m, self.from_m, self.from_m])

    @property
    def turns(self) -> float:
        """Orbits flown."""
        return self.length_m / (2.0 * math.pi * self.radius_m)

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """``(xy, amsl)``: the orbit sampled every :data:`SPIRAL_STEP_M` of arc (at least 8
        points a turn), clockwise from ``start_rad``, climbing (descending) linearly with the
        arc."""
        step = min(SPIRAL_STEP_M, 2.0 * math.pi * self.radius_m / 8.0)
        n = max(1, math.ceil(self.length_m / step))
        s = np.linspace(0.0, self.length_m, n + 1)
        a = self.start_rad - s / self.radius_m
        xy = np.column_stack(
            [
                self.center_m[0] + self.radius_m * np.cos(a),
                self.center_m[1] + self.radius_m * np.sin(a),
            ]
        )
        return xy, self.from_m + (self.to_m - self.from_m) * (s / max(self.length_m, 1e-9))


@dataclass(frozen=True)
class Descent:
    """A descent orbit at the landing approach point (i24-glide): PX4's fixed-wing landing
    pattern, NAV_LOITER_TO_ALT at the approach point, then the final glide from the orbit's
    tangent exit to NAV_LAND (:func:`descent_orbit`).

    Attributes
    ----------
    orbit : Spiral
        Centred on the approach point, from the altitude the route arrives at (``from_m``) to
        the glide's entry altitude (``to_m``), clockwise from the side the UAV comes from.
    exit_m : (float, float)
        The tangent point the UAV leaves the orbit at, heading for the landing field.
    exit_rad : float
        Its angle round the approach point (from east, counter-clockwise).
    glide_m : float
        The final glide's length, from the exit to the landing field (PX4's landing approach
        distance, ``sqrt(d^2 - r^2)`` for the field ``d`` from the approach point).
    """

    orbit: Spiral
    exit_m: tuple[float, float]
    exit_rad: float
    glide_m: float

    @property
    def length_m(self) -> float:
        """Horizontal distance flown on the orbit: the descent's arc, then round at the
        glide's altitude to the exit (less than a turn)."""
        o = self.orbit
        end = o.start_rad - o.length_m / o.radius_m
        return o.length_m + ((end - self.exit_rad) % (2.0 * math.pi)) * o.radius_m

    @property
    def time_s(self) -> float:
        """The orbit's flight time at its speed: what the 2-D time model does not fly."""
        return self.length_m / self.orbit.speed_mps

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """``(xy, amsl)``: the descent's arc (:meth:`Spiral.points`), then the arc round at the
        glide's altitude to the exit."""
        xy, z = self.orbit.points()
        o = self.orbit
        end = o.start_rad - o.length_m / o.radius_m
        rest = (end - self.exit_rad) % (2.0 * math.pi)
        n = max(1, math.ceil(rest * o.radius_m / SPIRAL_STEP_M))
        a = end - np.linspace(0.0, rest, n + 1)[1:]
        arc = np.column_stack(
            [o.center_m[0] + o.radius_m * np.cos(a), o.center_m[1] + o.radius_m * np.sin(a)]
        )
        return np.concatenate([xy, arc]), np.concatenate([z, np.full(len(arc), o.to_m)])


@dataclass(frozen=True)
class Profile:
    """A UAV's mission altitudes (module docstring).

    Attributes
    ----------
    points_m : ndarray, shape (n, 2)
        Take-off field, then the route's points (``waypoints_m`` and the intermediate points
        the profile needs), then the landing approach point.
    amsl_m, ground_m : ndarray, shape (n,)
        Altitude and the highest ground near each point, metres AMSL.
    vertex : ndarray of int, shape (n,)
        The index of the mission vertex (0 field, 1.. ``waypoints_m``, last the approach) a
        point is, or -1 for an intermediate point.
    field_m : float
        The take-off field's elevation (AMSL); ``landing_field_m`` the landing field's.
    climb : Spiral or None
        The climb spiral over the take-off field, where the straight climb meets the ground
        (:func:`climb_spiral`); None where it does not (the mission as before).
    descent : Descent or None
        The descent orbit at the landing approach point, where no straight glide from the
        approach point clears the ground (:func:`landing_profile`); None where one does.
    """

    points_m: np.ndarray
    amsl_m: np.ndarray
    ground_m: np.ndarray
    vertex: np.ndarray
    field_m: float
    landing_field_m: float
    climb: Spiral | None = None
    descent: Descent | None = None


def profile(
    t: Terrain,
    path_xy: Any,
    where: str = "route",
    landing_xy: Any = None,
    layer_m: float = 0.0,
    speed_mps: float | None = None,
    loiter: bool = False,
    route_speed_mps: float | None = None,
    airspace: tuple = ((), None),
) -> Profile:
    """The altitudes along ``path_xy`` (take-off field, waypoints, approach point) over ``t``.

    ``layer_m``: the UAV's altitude layer (:func:`poc_env.agents.mission.features.with_layers`),
    added to the wanted altitude (at least the clearance) before eq. 19's passes and the glide
    cap, so a layered profile keeps the clearance, the pitch bound and the final glide.
    ``speed_mps``: the speed out of the field (the plan's transit speed; default the paper's
    220 km/h, :data:`~poc_env.agents.mission.plan.DEFAULT_FLIGHT`), which sets a climb
    spiral's radius and time (:func:`climb_spiral`). ``loiter``: the UAV descends on an orbit
    at the approach point to the final glide (:func:`descent_orbit`) instead of gliding
    straight from it: the profile ends at the approach point at its wanted altitude (no glide
    cap). ``route_speed_mps``: the fastest speed flown along the legs (default ``speed_mps``):
    with the aircraft's vertical rate limits, the legs' climbs and descents are bounded per
    metre at it (:func:`vertical_angle`: a profile flyable at the fastest speed is flyable at
    the slower ones), as are the straight take-off climb and the final glide. ``airspace``:
    (no-fly zones, operating area polygon or None), where a take-off may depart on a heading
    of its own (:func:`departure_spiral`).

    Raises
    ------
    ConfigError
        ``where`` named: clearance impossible within the UAV's ceiling, or a layer that would
        take the wanted altitude above it, or a take-off climb that meets the ground even
        on a climb spiral (or whose spiral would end above the ceiling).
    """
    path = np.asarray(path_xy, dtype=float).reshape(-1, 2)
    step = t.cell_m / 2.0
    pts, vtx = [path[0]], [0]
    for k in range(1, len(path)):
        a, b = path[k - 1], path[k]
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        s = np.union1d(np.arange(1, n + 1) / n, t.window_changes(a, b))
        pts.extend(a + (b - a) * s[:, None])
        vtx.extend([-1] * (len(s) - 1) + [k])
    p = np.asarray(pts)
    vertex = np.asarray(vtx)
    x0, y0, x1, y1 = t.bounds
    out = (p[:, 0] < x0 - 1) | (p[:, 0] > x1 + 1) | (p[:, 1] < y0 - 1) | (p[:, 1] > y1 + 1)
    if out.any():
        x, y = p[int(np.argmax(out))]
        raise ConfigError(
            where, f"a point at ({x / 1e3:.1f}, {y / 1e3:.1f}) km",
            "a route over the terrain grid (the operating area, x0, y0, x1, y1 = "
            f"{[round(v / 1e3, 3) for v in t.bounds]} km): re-plan inside it",
        )  # fmt: skip
    ground = t.ground_at(p)
    if len(p) > 1:  # and the ground the points of the sub-legs either side of each sample read
        leg = t.ground_at((p[:-1] + p[1:]) / 2.0)  # constant inside: no window change there
        ground = np.maximum(ground, np.maximum(np.append(leg, leg[-1]), np.insert(leg, 0, leg[0])))
    req = ground + t.min_clearance_m
    worst = int(np.argmax(req))
    if req[worst] > t.ceiling_m + 1e-6:
        x, y = p[worst]
        raise ConfigError(
            where, f"ground {ground[worst]:.0f} m AMSL near ({x / 1e3:.1f}, {y / 1e3:.1f}) km",
            f"a route that keeps the clearance terrain.min_clearance_m = {t.min_clearance_m:g} m "
            f"within the UAV's ceiling uav.max_altitude_m = {t.ceiling_m:g} m AMSL (clearance "
            "impossible: re-plan around the high ground, or raise the ceiling if the UAV can)",
        )  # fmt: skip
    base = np.maximum(np.minimum(ground + t.search_height_m, t.ceiling_m), req)
    if layer_m:
        base = base + layer_m
        top = int(np.argmax(base))
        if base[top] > t.ceiling_m + 1e-6:
            x, y = p[top]
            raise ConfigError(
                where, f"altitude {base[top]:.0f} m AMSL near ({x / 1e3:.1f}, {y / 1e3:.1f}) km "
                f"({base[top] - layer_m:.0f} m: {base[top] - layer_m - ground[top]:.0f} m over "
                f"ground {ground[top]:.0f} m, + layer {layer_m:g} m)",
                f"at most the UAV's ceiling uav.max_altitude_m = {t.ceiling_m:g} m AMSL: a "
                "smaller separation_m, layer_by=field, or a higher ceiling if the UAV can",
            )  # fmt: skip
    dist = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    v_route = _speed(route_speed_mps if route_speed_mps is not None else speed_mps)
    up = math.tan(vertical_angle(t, v_route, True))
    down = math.tan(vertical_angle(t, v_route, False))
    z = base.copy()
    for i in range(1, len(z)):  # eq. 19 (and the sink rate): dz >= -down per metre flown
        z[i] = max(z[i], z[i - 1] - down * (dist[i] - dist[i - 1]))
    for i in range(len(z) - 2, -1, -1):  # and the climb: dz <= up per metre flown
        z[i] = max(z[i], z[i + 1] - up * (dist[i + 1] - dist[i]))
    descent = None
    if landing_xy is not None and loiter:
        land_xy = np.asarray(landing_xy, dtype=float)
        descent = descent_orbit(t, p, z, land_xy, where, speed_mps, layer_m)
    elif landing_xy is not None:
        z = _glide_cap(t, p, z, req, dist, np.asarray(landing_xy, dtype=float), where, down)
    glide_to = None if loiter else landing_xy
    climb = _check_field_legs(t, p, z, dist, glide_to, where, speed_mps, layer_m, up, airspace)
    keep = _simplify(dist, z, np.maximum(req, z - PROFILE_TOLERANCE_M), vertex)
    land = path[-1] if landing_xy is None else landing_xy
    return Profile(
        points_m=p[keep],
        amsl_m=z[keep],
        ground_m=ground[keep],
        vertex=vertex[keep],
        field_m=t.field_elevation(path[0]),
        landing_field_m=t.field_elevation(land),
        climb=climb,
        descent=descent,
    )


def _check_field_legs(
    t: Terrain,
    p: np.ndarray,
    z: np.ndarray,
    dist: np.ndarray,
    landing_xy: Any,
    where: str,
    speed_mps: float | None = None,
    layer_m: float = 0.0,
    up: float | None = None,
    airspace: tuple = ((), None),
) -> Spiral | None:
    """The take-off climb and the final glide: above the ground (the bilinear ``ground_m``);
    the climb spiral the take-off needs, if any.

    The climb: from the take-off field's elevation at eq. 19's ``tan(beta_max)`` along the
    mission's path (``p``, ``dist``) until it meets the profile ``z`` (a fixed-wing UAV cannot
    climb to the profile's first altitude over the field; the profile, checked against the
    clearance, is flown from there). Where that straight climb meets the ground, the UAV climbs
    over the field first (:func:`climb_spiral`): it takes off to the spiral's first altitude,
    orbits up to its last and climbs straight on from there. The glide: straight from the
    approach point ``p[-1]`` at ``z[-1]`` down to the landing field ``landing_xy`` (none
    without one). Neither can keep
    ``min_clearance_m`` near its field, where the UAV leaves or meets the ground, and the
    highest ground near a point (:meth:`Terrain.ground_at`, which the clearance reads: up to a
    cell and a half away) is above a UAV on a sloping field by construction: each must stay
    above the ground itself, the DEM's bilinear resampling (the one the fields' elevations
    come from). Points near the field's own terrain cell (the 2 x 2 cells around them include
    it, :meth:`Terrain.near_cells`) are not checked: the UAV stands on the field there. ``up``:
    the straight climbs' gradient (the profile's, :func:`vertical_angle` at the legs' speed;
    default ``tan(beta_max)``).

    Raises
    ------
    ConfigError
        ``where`` named, with the point, its ground, the distance from the field and the
        altitude flown there (a :class:`GlideError` for the final glide).
    """
    grad = math.tan(t.max_pitch_rad) if up is None else up
    field = t.field_elevation(p[0])
    climb = np.minimum(z, field + grad * dist)
    spiral = None
    if _first_cut(t, p[0], p, climb) is not None:  # the straight climb meets the ground
        spiral = climb_spiral(t, p, z, dist, where, speed_mps, layer_m, grad)
        straight = field + grad * dist  # the take-off to the orbit's first altitude, then on
        climb = np.where(
            straight < spiral.from_m, straight, np.minimum(z, spiral.to_m + grad * dist)
        )
        if _first_cut(t, p[0], p, climb) is not None:  # even to the orbit: depart elsewhere
            turned = departure_spiral(t, p, z, dist, where, speed_mps, layer_m, grad, airspace)
            if turned is not None:  # its climb out checked there; the route from the top
                spiral, climb = turned, np.minimum(z, turned.to_m + grad * dist)
    what = "take-off climb from"
    if spiral is not None:
        what = (
            f"take-off climb (to {spiral.from_m:.0f} m, then an orbit of radius "
            f"{spiral.radius_m / 1e3:.2f} km over the field) from"
        )
    legs = [(what, "take-off", p[0], p, climb, dist, field)]
    if landing_xy is not None:
        land = np.asarray(landing_xy, dtype=float)
        final = float(np.hypot(*(land - p[-1])))
        s = np.linspace(0.0, 1.0, max(1, math.ceil(final / (t.cell_m / 2.0))) + 1)[:, None]
        low = t.field_elevation(land)
        glide = (p[-1] + (land - p[-1]) * s, z[-1] + (low - z[-1]) * s[:, 0], final * (1 - s[:, 0]))
        legs.append(("final glide to", "landing", land, *glide, low))
    for what, name, at, xy, alt, off, elev in legs:
        i = _first_cut(t, at, xy, alt)
        if i is not None:
            ground = float(bilinear(t.ground_m, t.origin_m, t.cell_m, xy[i])[0])
            x, y = xy[i]
            raise (GlideError if name == "landing" else ConfigError)(
                where, f"ground {ground:.0f} m AMSL at ({x / 1e3:.1f}, {y / 1e3:.1f}) km, "
                f"{off[i] / 1e3:.1f} km from the {name} field (at {elev:.0f} m), flown at "
                f"{alt[i]:.0f} m",
                f"a {what} the field within {_bound_text(t)} that stays above the ground "
                f"(re-plan the first or last leg away from the rising ground, or another {name} "
                "field)",
            )  # fmt: skip
    return spiral


def _first_cut(t: Terrain, at: Any, xy: np.ndarray, alt: np.ndarray) -> int | None:
    """The first of the points ``xy`` flown at ``alt`` at or below the bilinear ground, outside
    the cells around the field ``at`` (:func:`_check_field_legs`); None if none is."""
    ground = bilinear(t.ground_m, t.origin_m, t.cell_m, xy)
    cut = ~_own_cells(t, at, xy) & (alt <= ground)
    return int(np.argmax(cut)) if cut.any() else None


def _own_cells(t: Terrain, at: Any, xy: np.ndarray) -> np.ndarray:
    """Which of the points ``xy`` read the terrain cell of the field ``at`` (the 2 x 2 cells
    around them include it): where the UAV stands on the field, not checked."""
    i0, i1, j0, j1 = t.near_cells(xy)
    fi, _, fj, _ = (int(v[0]) for v in t.near_cells(np.asarray(at) + t.cell_m / 2.0))
    return ((i0 == fi) | (i1 == fi)) & ((j0 == fj) | (j1 == fj))


def climb_spiral(
    t: Terrain,
    p: np.ndarray,
    z: np.ndarray,
    dist: np.ndarray,
    where: str,
    speed_mps: float | None = None,
    layer_m: float = 0.0,
    up: float | None = None,
    start_rad: float | None = None,
) -> Spiral:
    """The climb spiral over the take-off field ``p[0]`` for a mission whose straight climb
    meets the ground (:class:`Spiral`); ``start_rad``: the heading the take-off climbs out on
    (default towards the first waypoint, :func:`departure_spiral` tries others).

    Eq. 19 in the horizontal plane bounds the turn rate, so the tightest orbit at the speed
    ``v`` (``speed_mps``, default the paper's 220 km/h) has the radius ``v / turn rate``, and a
    UAV given an altitude layer ``layer_m`` (:func:`~poc_env.agents.mission.features.
    with_layers`) orbits that much wider, so field-mates' orbits are at least the layers'
    separation apart (:func:`orbit_radius`); its
    pitch bound ``tan(beta_max)`` bounds the climb per metre flown, or the aircraft's climb
    rate where it binds first (:func:`vertical_angle` at ``v``: more turns, a longer orbit);
    ``up`` is the straight climb's gradient after it (the profile's; default the orbit's).
    The orbit (clockwise, from
    the point towards the first waypoint) starts at the least altitude from which it keeps
    ``min_clearance_m`` over the ground under it (the bilinear ``ground_m``, read every
    :data:`ORBIT_SAMPLE_M` of its first turn; the later turns are higher over the same
    ground), at least the field's elevation plus the clearance: the take-off item's altitude,
    which the UAV climbs to straight, checked as the straight climb is
    (:func:`_check_field_legs`). It ends at the least altitude ``H`` (at least its start) from
    which the straight climb on along the mission, ``min(z, H + tan(beta_max) x distance)``,
    keeps ``min_clearance_m`` above the ground (the bilinear ``ground_m``, as the straight
    climb's check) at every sample. Unless the ground under the orbit holds it higher, ``H``
    is at most the profile's altitude over the field (``z`` keeps the clearance and climbs at
    most ``tan(beta_max)`` a metre), so the profile is flown on from there unchanged. The UAV
    leaves the orbit heading for the next waypoint (QGC: heading required), at the field's
    distance along the route and up to a radius beside its line: the clearance after the
    orbit is read along the line.

    Raises
    ------
    ConfigError
        ``where`` named: ``H`` above the UAV's ceiling.
    """
    v = _speed(speed_mps)
    pitch = vertical_angle(t, v, True)
    grad = math.tan(pitch)
    on = grad if up is None else up
    field = t.field_elevation(p[0])
    r = orbit_radius(t, v, layer_m)
    ground = bilinear(t.ground_m, t.origin_m, t.cell_m, p)
    start = _route_heading(p, dist) if start_rad is None else start_rad
    arc = np.arange(0.0, 2.0 * math.pi * r, ORBIT_SAMPLE_M)  # one turn: the later ones are higher
    ring = np.column_stack(
        [p[0][0] + r * np.cos(start - arc / r), p[0][1] + r * np.sin(start - arc / r)]
    )
    under = bilinear(t.ground_m, t.origin_m, t.cell_m, ring)
    low = max(field, float(np.max(under - grad * arc))) + t.min_clearance_m
    top = max(low, float(np.max(ground + t.min_clearance_m - on * dist)))
    if top > t.ceiling_m + 1e-6:
        raise ConfigError(
            where, f"a climb spiral over the take-off field (at {field:.0f} m) to {top:.0f} m AMSL",
            f"a climb within the UAV's ceiling uav.max_altitude_m = {t.ceiling_m:g} m AMSL from "
            "which the straight climb keeps terrain.min_clearance_m (another take-off field)",
        )  # fmt: skip
    sp = Spiral(
        center_m=(float(p[0][0]), float(p[0][1])),
        radius_m=r,
        from_m=low,
        to_m=top,
        speed_mps=v,
        pitch_rad=pitch,
        start_rad=start,
    )
    return sp


def _route_heading(p: np.ndarray, dist: np.ndarray) -> float:
    """The heading (rad from east, counter-clockwise) from the field ``p[0]`` towards the
    mission's first point away from it (east for a mission that goes nowhere)."""
    ahead = p[np.argmax(dist > 0.0)] - p[0] if dist[-1] > 0.0 else np.array([1.0, 0.0])
    return math.atan2(float(ahead[1]), float(ahead[0]))


#: The take-off headings :func:`departure_spiral` tries: every 15 degrees (the landing's
#: :func:`~poc_env.agents.mission.plan.approach_sides` step), nearest the route's first.
DEPARTURE_STEP_RAD = math.pi / 12.0


def departure_spiral(
    t: Terrain,
    p: np.ndarray,
    z: np.ndarray,
    dist: np.ndarray,
    where: str,
    speed_mps: float | None,
    layer_m: float,
    up: float,
    airspace: tuple = ((), None),
) -> Spiral | None:
    """A climb spiral whose take-off climbs out on a heading of its own, for a mission whose
    take-off climb towards its first waypoint meets the ground before the spiral's first
    altitude (i24-missionfix: at PX4's 5 m/s climb the day audit's probes 13 and 14 were
    refused so).

    A pilot departs away from rising ground: the headings every
    :data:`DEPARTURE_STEP_RAD` round the field are tried, nearest the route's first (+ before
    -), each with its own :func:`climb_spiral` (the orbit starts where the departure line
    crosses it, so its first altitude reads the ground from there). A heading flies if its
    straight climb at ``up`` per metre from the field's elevation to the orbit's first
    altitude stays above the ground (the bilinear ``ground_m``, outside the field's own cells,
    as every take-off climb, :func:`_check_field_legs`), inside the terrain grid, outside the
    no-fly zones and inside the operating area (``airspace`` = (zones, operating area polygon
    or None); the QGC fences). Of those, the one over the least rising ground (the highest
    ground under it, the field's cells included, above the field, to the metre) is taken, the
    nearest the route's among equals: away from the terrain, not skimming it. Its length is
    the spiral's ``depart_m`` (charged twice, :attr:`Spiral.time_s`). None if no heading
    flies.
    """
    from shapely.geometry import LineString, Polygon

    zones, area = airspace
    polys = [Polygon(zn) for zn in zones or ()]
    fence = Polygon(area).buffer(1.0) if area else None
    x0, y0, x1, y1 = t.bounds
    field = t.field_elevation(p[0])
    route = _route_heading(p, dist)
    n = round(2.0 * math.pi / DEPARTURE_STEP_RAD)
    steps = [s * k for k in range(1, n // 2 + 1) for s in ((1, -1) if k < n // 2 else (1,))]
    best: tuple[float, Spiral] | None = None
    for k in steps:
        h = route + k * DEPARTURE_STEP_RAD
        try:  # (its top above the ceiling: not this heading)
            sp = climb_spiral(t, p, z, dist, where, speed_mps, layer_m, up, start_rad=h)
        except ConfigError:
            continue
        run = max(0.0, (sp.from_m - field) / up)
        s = np.linspace(0.0, run, max(1, math.ceil(run / (t.cell_m / 2.0))) + 1)
        xy = p[0] + s[:, None] * np.array([math.cos(h), math.sin(h)])
        end = xy[-1]
        if not (x0 <= end[0] <= x1 and y0 <= end[1] <= y1):
            continue
        line = LineString([tuple(p[0]), tuple(end)])
        if any(line.intersects(zn) for zn in polys) or (fence and not fence.covers(line)):
            continue
        if _first_cut(t, p[0], xy, field + up * s) is not None:
            continue
        top = float(np.max(bilinear(t.ground_m, t.origin_m, t.cell_m, xy)))  # the ground under it
        rise = max(0.0, round(top - field))
        if best is None or rise < best[0]:
            best = (rise, dataclasses.replace(sp, depart_m=float(run)))
        if rise == 0.0:  # level ground: the nearest such heading to the route's
            break
    return None if best is None else best[1]


def departure_heading_deg(sp: Spiral) -> float:
    """The compass heading (degrees clockwise from grid north, the map's +y) of a climb
    spiral's take-off climb (:attr:`Spiral.start_rad`)."""
    return (90.0 - math.degrees(sp.start_rad)) % 360.0


def orbit_radius(t: Terrain, speed_mps: float, layer_m: float = 0.0) -> float:
    """An orbit's radius: eq. 19's turn-rate bound at ``speed_mps`` (the tightest circle,
    ``v / turn rate``), widened by the UAV's altitude layer ``layer_m``
    (:func:`~poc_env.agents.mission.features.with_layers`). Field-mates' layers differ by at
    least ``separation_m``, so their concentric orbits over one field (or one approach point)
    are that far apart horizontally at every altitude, whenever each is flown: their altitudes
    come from the ground, not from the layer, and two helices on one circle are not kept apart
    by an altitude offset unless they start together (the export schedules no launch times)."""
    return speed_mps / t.turn_rate_rad_s + float(layer_m)


def _disc(centre: Any, r: float) -> np.ndarray:
    """Points covering the disc of radius ``r`` round ``centre``: rings at 0, r/4, .., r, each
    sampled every :data:`ORBIT_SAMPLE_M` of arc (where the UAV flies out to its orbit and
    round it)."""
    pts = [np.asarray(centre, dtype=float).reshape(1, 2)]
    for k in range(1, 5):
        rk = r * k / 4.0
        a = np.arange(0.0, 2.0 * math.pi * rk, ORBIT_SAMPLE_M) / rk
        pts.append(np.column_stack([centre[0] + rk * np.cos(a), centre[1] + rk * np.sin(a)]))
    return np.concatenate(pts)


def descent_orbit(
    t: Terrain,
    p: np.ndarray,
    z: np.ndarray,
    land: np.ndarray,
    where: str,
    speed_mps: float | None = None,
    layer_m: float = 0.0,
) -> Descent:
    """The descent orbit at the approach point ``p[-1]`` (reached at ``z[-1]``) to the final
    glide to the landing field ``land`` (:class:`Descent`): PX4's fixed-wing landing pattern.

    The orbit (clockwise, radius :func:`orbit_radius`) descends at eq. 19's ``tan(beta_max)``
    per metre flown (or the aircraft's sink rate where it binds first, :func:`vertical_angle`:
    a longer orbit, its time charged) to the glide's entry altitude ``H``, and the UAV leaves
    it at the tangent point heading for the field: PX4 (navigator ``FeasibilityChecker::
    checkFixedWindLandApproach``) reads the glide from NAV_LOITER_TO_ALT to NAV_LAND as ``(H -
    field) / sqrt(d^2 - r^2)``, ``d`` the field's distance from the orbit's centre, which must
    exceed ``r``. ``H`` is the flat export's glide, :data:`~poc_env.agents.mission.plan.
    LANDING_GLIDE` over that distance, or higher where the orbit needs it: the disc the UAV
    flies out to and round its orbit keeps ``min_clearance_m`` over the ground under it (the
    bilinear ``ground_m``, as the climb spiral's) at the lower of ``z[-1]`` and ``H``. A glide
    steeper than LANDING_GLIDE is warned (:class:`SteepGlideWarning`); the glide from the exit
    must stay above the ground as a straight glide must (:func:`_check_field_legs`).

    Raises
    ------
    GlideError
        ``where`` named: the field within the orbit, the orbit's clearance above the ceiling or
        needing a glide steeper than ``tan(beta_max)``, or the glide meeting the ground.
    """
    v = _speed(speed_mps)
    pitch = vertical_angle(t, v, False)  # the orbit's descent; the glide keeps beta_max
    c = np.asarray(p[-1], dtype=float)
    r = orbit_radius(t, v, layer_m)
    field = t.field_elevation(land)
    d = float(np.hypot(*(land - c)))
    if d <= r:
        raise GlideError(
            where, f"a descent orbit of radius {r / 1e3:.2f} km {d / 1e3:.2f} km from the field",
            "a landing field outside the orbit (PX4's landing pattern)",
        )  # fmt: skip
    glide_m = math.sqrt(d * d - r * r)
    need = float(np.max(bilinear(t.ground_m, t.origin_m, t.cell_m, _disc(c, r))))
    need += t.min_clearance_m
    top = max(field + LANDING_GLIDE * glide_m, need)
    steep = (top - field) / glide_m > math.tan(t.max_pitch_rad) + 1e-12  # the glide: FW_LND_ANG
    if top > t.ceiling_m + 1e-6 or steep or z[-1] < need - 1e-6:
        raise GlideError(
            where, f"a descent orbit at ({c[0] / 1e3:.1f}, {c[1] / 1e3:.1f}) km over ground up "
            f"to {need - t.min_clearance_m:.0f} m AMSL, {glide_m / 1e3:.2f} km of glide from a "
            f"landing field at {field:.0f} m",
            f"an orbit keeping terrain.min_clearance_m = {t.min_clearance_m:g} m within the "
            f"ceiling and a glide within {_bound_text(t)}",
        )  # fmt: skip
    exit_xy, ex = tangent_exit(c, r, land)
    s = np.linspace(0.0, 1.0, max(1, math.ceil(glide_m / (t.cell_m / 2.0))) + 1)
    line = exit_xy + (land - exit_xy) * s[:, None]
    i = _first_cut(t, land, line, top + (field - top) * s)
    if i is not None:
        x, y = line[i]
        ground = float(bilinear(t.ground_m, t.origin_m, t.cell_m, line[i])[0])
        raise GlideError(
            where, f"ground {ground:.0f} m AMSL at ({x / 1e3:.1f}, {y / 1e3:.1f}) km under the "
            f"glide from a descent orbit at {top:.0f} m",
            "a final glide that stays above the ground",
        )  # fmt: skip
    _warn_steep(where, "descent orbit's exit", top - field, field, glide_m)
    back = p[-2] - c if len(p) > 1 else np.array([1.0, 0.0])
    orbit = Spiral(
        center_m=(float(c[0]), float(c[1])),
        radius_m=r,
        from_m=float(z[-1]),
        to_m=float(top),
        speed_mps=v,
        pitch_rad=pitch,
        start_rad=math.atan2(float(back[1]), float(back[0])),
    )
    return Descent(
        orbit=orbit,
        exit_m=(float(exit_xy[0]), float(exit_xy[1])),
        exit_rad=ex,
        glide_m=glide_m,
    )


def tangent_exit(centre: Any, r: float, target: Any) -> tuple[np.ndarray, float]:
    """Where a clockwise orbit of radius ``r`` round ``centre`` is left heading straight for
    ``target`` (outside it): the tangent point (PX4's NAV_LOITER_TO_ALT with heading required)
    and its angle round the centre (from east, counter-clockwise)."""
    c = np.asarray(centre, dtype=float)
    to = np.asarray(target, dtype=float)
    d = float(np.hypot(*(to - c)))
    u = (to - c) / d
    alpha = math.acos(r / d)  # clockwise: the exit is u turned alpha counter-clockwise
    ex = math.atan2(u[1], u[0]) + alpha
    return c + r * np.array([math.cos(ex), math.sin(ex)]), ex


def separate_orbits(plan: Any, t: Terrain, profs: list[Profile]) -> list[Profile]:
    """Field-mates' concentric orbits kept apart where one's exit crosses another (i24-rates).

    With altitude layers (``plan["altitude_layers"]``, separation ``S``), field-mates' climb
    spirals (and descent orbits at one approach point) are concentric, ``S`` apart
    (:func:`orbit_radius`), and the UAV leaving an inner orbit (at its tangent exit,
    :func:`tangent_exit`) crosses every outer one ``sqrt(R^2 - r^2)`` further on, where the
    outer UAV passes once a turn at the altitudes of its helix (and at its last altitude on
    the way round to its own exit). Measured on probe 13 of results/audit/dayaudit at ``S`` =
    30 m: the inner UAV crossed within the outer one's altitudes there, 0 m apart
    (results/mission/i24-rates/README.md). So:

    - a climb spiral inside others tops out at least ``S`` above their highest altitude (their
      tops, themselves raised first, outermost first) plus what it may descend, at most
      :func:`vertical_angle`'s sink gradient, over the run to the crossing: it crosses above
      every altitude they fly there, whatever the timing (more turns: charged);
    - a descent orbit outside others ends at least ``S`` above the altitude at which each inner
      UAV's glide (from its exit to the field) crosses it: it flies above that crossing
      throughout (a steeper glide from its exit, warned above the flat export's
      :data:`~poc_env.agents.mission.plan.LANDING_GLIDE`).

    Without layers, or with no concentric orbits, ``profs`` is returned as it is.

    Raises
    ------
    ConfigError
        Naming ``plan.uavs[k]``: a raised spiral above the ceiling, or a raised descent orbit
        whose glide would be steeper than eq. 19's pitch bound.
    """
    layers = plan.get("altitude_layers")
    if not layers or not profs:
        return profs
    sep = float(layers["separation_m"])
    from poc_env.agents.mission.plan import flight

    down = math.tan(vertical_angle(t, route_speed_mps(flight(plan)), False))
    out = list(profs)
    uavs = plan["uavs"]
    where = [f"plan.uavs[{k}] (UAV {u['id']})" for k, u in enumerate(uavs)]
    climbs: dict[tuple, list[int]] = {}
    falls: dict[tuple, list[int]] = {}
    for k, p in enumerate(out):
        if not uavs[k]["waypoints_m"]:
            continue
        if p.climb is not None:
            climbs.setdefault(p.climb.center_m, []).append(k)
        if p.descent is not None:
            falls.setdefault(p.descent.orbit.center_m, []).append(k)
    for ks in climbs.values():  # outermost first: an inner spiral reads the raised tops
        ks.sort(key=lambda k: -out[k].climb.radius_m)  # type: ignore[union-attr]
        for i, k in enumerate(ks):
            sp = out[k].climb
            assert sp is not None
            top = sp.to_m
            for j in ks[:i]:
                o = out[j].climb
                assert o is not None
                if o.radius_m > sp.radius_m + 1e-6:
                    run = math.sqrt(o.radius_m**2 - sp.radius_m**2)
                    top = max(top, o.to_m + sep + down * run)
            if top > sp.to_m:
                if top > t.ceiling_m + 1e-6:
                    raise ConfigError(
                        where[k], f"a climb spiral over the take-off field to {top:.0f} m AMSL "
                        f"(separation {sep:g} m above the field-mates' orbits round it)",
                        f"a climb within the UAV's ceiling uav.max_altitude_m = {t.ceiling_m:g}"
                        " m AMSL: a smaller separation_m, or launch them apart in time",
                    )  # fmt: skip
                out[k] = dataclasses.replace(out[k], climb=dataclasses.replace(sp, to_m=top))
    for ks in falls.values():  # innermost first: an outer orbit reads the inner glides
        ks.sort(key=lambda k: out[k].descent.orbit.radius_m)  # type: ignore[union-attr]
        for i, k in enumerate(ks):
            d = out[k].descent
            assert d is not None
            floor = d.orbit.to_m
            for j in ks[:i]:
                di = out[j].descent
                assert di is not None
                oi = di.orbit
                if d.orbit.radius_m > oi.radius_m + 1e-6:
                    run = math.sqrt(d.orbit.radius_m**2 - oi.radius_m**2)
                    slope = (oi.to_m - out[j].landing_field_m) / di.glide_m
                    floor = max(floor, oi.to_m - slope * run + sep)
            if floor > d.orbit.to_m:
                field = out[k].landing_field_m
                if (floor - field) / d.glide_m > math.tan(t.max_pitch_rad) + 1e-12:
                    raise ConfigError(
                        where[k], f"a descent orbit raised to {floor:.0f} m AMSL, {sep:g} m above "
                        "where a field-mate's glide crosses it",
                        f"a glide within {_bound_text(t)}: a smaller separation_m, or land "
                        "them apart in time",
                    )  # fmt: skip
                _warn_steep(where[k], "descent orbit's exit", floor - field, field, d.glide_m)
                orbit = dataclasses.replace(d.orbit, to_m=floor)
                out[k] = dataclasses.replace(out[k], descent=dataclasses.replace(d, orbit=orbit))
    return out


def landing_profile(
    t: Terrain,
    u: Any,
    zones: Any,
    where: str,
    speed_mps: float,
    area: Any = None,
    route_speed_mps: float | None = None,
) -> Profile:
    """A UAV's :func:`profile` with the final glide it can fly (i24-glide; probe 13 of
    results/audit/dayaudit).

    First, as before, straight from the approach point of
    :func:`~poc_env.agents.mission.plan.approach_point`. Only where that glide cannot keep the
    ground (:class:`GlideError`), the sides of the landing field are searched, nearest first
    (:func:`~poc_env.agents.mission.plan.approach_sides`, 15 degree steps, clear of the no-fly
    ``zones``, the approach and its orbit on the terrain grid and inside the operating area
    ``area``, the QGC inclusion fence): on each, a straight glide from it, then a descent
    orbit at it (:func:`descent_orbit`); the first that flies with a glide no steeper than
    :data:`~poc_env.agents.mission.plan.LANDING_GLIDE` (PX4's default FW_LND_ANG accepts it)
    is taken, else the first that flies (its :class:`SteepGlideWarning` said). Only the
    attempt taken says its warnings.

    Raises
    ------
    ConfigError
        ``where`` named: no side of the field gives a glide that clears the ground (the first
        side's refusal, with the sides tried); or the profile's other refusals.
    """
    import warnings

    from poc_env.agents.mission.plan import approach_sides

    path = mission_path(u, zones)
    layer = u.get("layer_m", 0.0)
    land = u["landing_m"]

    def attempt(app: Any, loiter: bool, steep: bool) -> Profile:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")  # the caller's filters decide when said below
            prof = profile(
                t, [*path[:-1], app], where, land, layer, speed_mps, loiter, route_speed_mps,
                (zones, area),
            )  # fmt: skip
        if not steep and any(issubclass(w.category, SteepGlideWarning) for w in said):
            raise GlideError(where, "a glide steeper than the flat export's", "a gentler one")
        for w in said:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return prof

    try:
        return attempt(path[-1], False, True)
    except GlideError as err:
        first = err
    from shapely.geometry import Point, Polygon

    x0, y0, x1, y1 = t.bounds
    r = orbit_radius(t, speed_mps, layer)
    fence = Polygon(area).buffer(1.0) if area else None
    sides: list[list[float]] = []
    for side in approach_sides(u, zones):  # +-180 deg: one side
        if all(math.dist(side, other) > 1.0 for other in sides):
            sides.append(side)
    tries = [
        (app, loiter)
        for app in sides
        if x0 + r <= app[0] <= x1 - r and y0 + r <= app[1] <= y1 - r
        for loiter in ((True,) if app == path[-1] else (False, True))
        if fence is None or fence.covers(Point(app).buffer(r if loiter else 0.0))
    ]
    other: ConfigError | None = None  # a side refused for something else than its landing
    for steep in (False, True):
        for app, loiter in tries:
            try:
                return attempt(app, loiter, steep)
            except GlideError:  # this side does not fly (its glide, its orbit)
                continue
            except ConfigError as err:  # nor this one (its last leg, or the take-off)
                other = other or err
                continue
    also = "" if other is None else f"; where the landing clears: {other.value}, {other.allowed}"
    raise ConfigError(
        where, first.value,
        f"{first.allowed}; no side of the landing field clears it either ({len(sides)} "
        "approach sides 15 deg apart tried, each with a straight glide and with a descent "
        f"orbit at the approach point){also}",
    )  # fmt: skip


#: PX4's and ArduPlane's default vertical rate limits (m/s): FW_T_CLMB_MAX and FW_T_SINK_MAX
#: (fw_pos_control's TECS parameters), TECS_CLMB_MAX and TECS_SINK_MAX. An export of a plan
#: whose scenario gives no ``uav.max_climb_rate_mps`` / ``max_sink_rate_mps`` says which of
#: its missions need more (:func:`rate_warnings`).
AUTOPILOT_DEFAULT_RATE_MPS = 5.0


def vertical_rates(
    t: Terrain, p: Profile, speed_mps: float, route_speed_mps: float
) -> list[tuple[str, str, float, str]]:
    """The vertical rates (m/s) the phases of the mission ``p`` need, as flown at its speeds
    (``speed_mps`` on the orbits, ``route_speed_mps`` on the legs, as :func:`profile` bounds
    them): (phase, ``climb`` or ``sink``, rate, a note), the fastest of each phase that has
    one. The route's legs: the steepest climb and descent between the profile's points (the
    exported waypoints' altitudes); the straight take-off climb: the least gradient that keeps
    it above the ground (:func:`_check_field_legs`), or the climb spiral's (its minutes at
    :data:`AUTOPILOT_DEFAULT_RATE_MPS` in the note); the descent orbit's sink (and its
    minutes). Not the final glide: flown at the landing airspeed, bounded by PX4's
    FW_LND_ANG (:class:`SteepGlideWarning`)."""
    out: list[tuple[str, str, float, str]] = []
    dz = np.diff(p.amsl_m)
    ds = np.maximum(np.hypot(*np.diff(p.points_m, axis=0).T), 1e-9)
    if len(dz):
        out.append(("route legs", "climb", float(max(0.0, np.max(dz / ds))) * route_speed_mps, ""))
        out.append(("route legs", "sink", float(max(0.0, np.max(-dz / ds))) * route_speed_mps, ""))
    slow = AUTOPILOT_DEFAULT_RATE_MPS
    for name, kind, o in (
        ("take-off climb spiral", "climb", p.climb),
        ("descent orbit", "sink", None if p.descent is None else p.descent.orbit),
    ):
        if o is not None:
            rate = math.tan(o.pitch_rad) * o.speed_mps
            height = abs(o.to_m - o.from_m)
            note = (
                f"{height:.0f} m in {o.time_s / 60:.1f} min charged, "
                f"{height / min(rate, slow) / 60:.1f} min at {slow:g} m/s"
            )
            out.append((name, kind, rate, note))
    if p.climb is None and len(p.points_m) > 1:  # the legs sampled every tenth of a cell
        xy = _densify(p.points_m, t.cell_m / 10.0)
        dist = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        ground = bilinear(t.ground_m, t.origin_m, t.cell_m, xy)
        far = ~_own_cells(t, p.points_m[0], xy) & (dist > 0.0)
        need = (ground[far] - p.field_m) / dist[far]
        up = float(max(0.0, need.max())) if need.size else 0.0
        out.append(("straight take-off climb", "climb", up * route_speed_mps, ""))
    return out


class SteepGlideWarning(UserWarning):
    """A UAV's final glide to its landing field steeper than the flat export's (the
    clearance holds the approach point high): PX4 refuses the mission unless FW_LND_ANG allows
    it. Said by ``poc-env plan`` (the officer may re-plan the landing) and by ``export
    --format qgc`` (the mission that flies; the vehicle's parameter to set); the viewing
    formats draw the glide and say nothing (:func:`poc_env.agents.mission.export.export_plan`).
    """


def _glide_cap(
    t: Terrain,
    p: np.ndarray,
    z: np.ndarray,
    req: np.ndarray,
    dist: np.ndarray,
    land: Any,
    where: str,
    down: float | None = None,
) -> np.ndarray:
    """``z`` lowered so that the descent to the landing field ``land`` (on the ground) keeps
    eq. 19's ``tan(beta_max)`` and the final glide, straight from the approach point ``p[-1]``
    to the field, is no steeper than it must be: at most ``field + g x final + tan(beta_max) x
    (distance flown to the approach point)`` at every point (a descent started early enough;
    the lower of two such limited profiles is one), with ``g`` the least gradient from
    :data:`~poc_env.agents.mission.plan.LANDING_GLIDE` (the flat export's 300 m over 4 km,
    which PX4's FW_LND_ANG accepts) up to ``tan(beta_max)`` that keeps the clearance. A ``g``
    above LANDING_GLIDE is warned (UserWarning, ``where`` named, the angle PX4's FW_LND_ANG
    must allow). ``down``: the descent's gradient to the approach point in place of
    ``tan(beta_max)`` (the profile's, :func:`vertical_angle` with the aircraft's sink rate);
    the final glide itself keeps ``tan(beta_max)``: it is flown at the landing airspeed, not
    the route's, and PX4 bounds it by FW_LND_ANG (the flat export's 4.29 deg is under it).

    Raises
    ------
    ConfigError
        ``where`` named: the clearance needs more height than a glide at ``tan(beta_max)``
        allows.
    """
    pitch = math.tan(t.max_pitch_rad)  # the final glide's own bound (PX4 checks FW_LND_ANG)
    grad = pitch if down is None else down
    field = t.field_elevation(land)
    final = max(float(np.hypot(*(land - p[-1]))), 1e-9)
    to_go = dist[-1] - dist + final
    need = (req - field - grad * (dist[-1] - dist)) / final  # the least g each point allows
    g = max(min(pitch, LANDING_GLIDE), float(need.max()))
    if g > pitch + 1e-12:
        i = int(np.argmax(need > pitch + 1e-12))
        x, y = p[i]
        raise GlideError(
            where, f"ground {req[i] - t.min_clearance_m:.0f} m AMSL near ({x / 1e3:.1f}, "
            f"{y / 1e3:.1f}) km, {to_go[i] / 1e3:.1f} km before a landing field at {field:.0f} m",
            f"a glide to the landing field within {_bound_text(t)} that keeps "
            "terrain.min_clearance_m = "
            f"{t.min_clearance_m:g} m (re-plan the last search leg or the landing field away "
            "from the high ground, or a UAV that can glide steeper)",
        )  # fmt: skip
    out = np.minimum(z, field + g * final + grad * (dist[-1] - dist))
    _warn_steep(where, "landing approach point", float(out[-1]) - field, field, final)
    return out


def _warn_steep(where: str, what: str, height_m: float, field: float, final: float) -> None:
    """:class:`SteepGlideWarning` when a final glide of ``height_m`` over ``final`` metres to
    a landing field at ``field`` is steeper than :data:`LANDING_GLIDE`."""
    glide = height_m / final
    if glide > LANDING_GLIDE * (1 + 1e-9):
        import warnings

        warnings.warn(
            f"{where}: the clearance holds the {what} {height_m:.0f} m "
            f"above the landing field at {field:.0f} m, {final / 1e3:g} km from it: a final "
            f"glide of {math.degrees(math.atan(glide)):.1f} deg, steeper than the "
            f"{math.degrees(math.atan(LANDING_GLIDE)):.2f} deg of the flat export; PX4 refuses "
            "the mission unless its FW_LND_ANG (default 5 deg) allows it",
            SteepGlideWarning,
            stacklevel=5,
        )


def _simplify(dist: np.ndarray, z: np.ndarray, floor: np.ndarray, vertex: np.ndarray) -> list:
    """Indices kept: every vertex, and between vertices the fewest points whose straight
    altitude legs stay at or above ``floor`` at every sample (greedy, farthest first).

    From a kept point ``i`` the leg to a candidate ``c`` passes when ``z[i] + (z[c] - z[i]) x
    frac_s >= floor[s] - 1e-6`` at every sample ``s`` between them. For the samples strictly
    inside, that is ``slope(i, c) >= need_s = (floor[s] - 1e-6 - z[i]) / (dist[s] - dist[i])``,
    so a running maximum of ``need_s`` decides each candidate in O(1) (linear in the samples
    of a leg; it made O(m^2) ``np.all`` calls before, 175 s of a 24-UAV export, results/
    audit/scale). A candidate within a rounding margin of the maximum is decided by the
    sample-by-sample test itself, so the points kept are exactly those of that test
    (tests/mission/test_export_profiles_once.py compares the two on random profiles).
    """
    d, zz, fl, vx = (np.asarray(a, dtype=float).tolist() for a in (dist, z, floor, vertex))
    keep = [0]
    i = 0
    n = len(zz)
    while i < n - 1:
        j = i + 1
        worst = -math.inf  # the largest need_s over the samples inside (i, j]
        near = d[i + 1] - d[i]
        exact = not near > 0  # samples on top of each other: the sample test throughout
        margin = 1e-9 / near if near > 0 else math.inf  # 1e-9 m at the nearest sample
        while j + 1 < n and vx[j] < 0:  # try to reach farther, never past a vertex
            cand = j + 1
            gap = d[j] - d[i]
            if gap > 0:
                worst = max(worst, (fl[j] - 1e-6 - zz[i]) / gap)
            else:
                exact = True
            span = max(d[cand] - d[i], 1e-9)
            slope = (zz[cand] - zz[i]) / span
            ends = zz[i] >= fl[i] - 1e-6 and (  # the end samples, as the sample test has them
                zz[i] + (zz[cand] - zz[i]) * ((d[cand] - d[i]) / span) >= fl[cand] - 1e-6
            )
            if not ends or (not exact and slope < worst - margin):
                break
            if exact or slope <= worst + margin:  # within the rounding margin: samples decide
                seg = slice(i, cand + 1)
                line = z[i] + (z[cand] - z[i]) * ((dist[seg] - dist[i]) / span)
                if not np.all(line >= floor[seg] - 1e-6):
                    break
            j = cand
        keep.append(j)
        i = j
    return keep


def _densify(points: np.ndarray, step_m: float) -> np.ndarray:
    """The polyline ``points`` sampled at most ``step_m`` apart (its vertices kept)."""
    out = [points[:1]]
    for a, b in itertools.pairwise(points):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step_m))
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(out)


def clearance_violations(t: Terrain, prof: Profile, step_m: float | None = None) -> int:
    """Points, sampled every ``step_m`` (default a tenth of a cell) along the straight legs
    between a profile's points, that fly less than the clearance above the ground near them."""
    step = step_m or t.cell_m / 10.0
    bad = 0
    for k in range(1, len(prof.points_m)):
        a, b = prof.points_m[k - 1], prof.points_m[k]
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / step))
        s = np.linspace(0.0, 1.0, n + 1)
        xy = a[None, :] + (b - a)[None, :] * s[:, None]
        zz = prof.amsl_m[k - 1] + (prof.amsl_m[k] - prof.amsl_m[k - 1]) * s
        bad += int(np.sum(zz - t.ground_at(xy) < t.min_clearance_m - 1e-6))
    return bad


def mission_path(u: Any, zones: Any = ()) -> list[list[float]]:
    """Take-off field, ``waypoints_m``, landing approach point (clear of the plan's no-fly
    ``zones``): the path a profile covers."""
    return [list(u["takeoff_m"]), *[list(w) for w in u["waypoints_m"]], approach_point(u, zones)]


#: Within :func:`profiles_once`: (id of the terrain record, of the UAV, of the zones) ->
#: (those three objects, kept alive so that their ids stay theirs, and the profile); and
#: ("terrain", id of the record) -> (the record, its :class:`Terrain`).
_PROFILES: contextvars.ContextVar[dict | None] = contextvars.ContextVar("_profiles", default=None)


@contextlib.contextmanager
def profiles_once() -> Iterator[None]:
    """Within it, :func:`plan_profiles` computes each UAV's profile once: one export's
    checks, routes, overlays and table read the same profiles (each was computed 2-3 times
    an export, 243 s of 251 for a 24-UAV plan, results/audit/scale). The plan must not change
    within it (an export's does not: :func:`poc_env.agents.mission.export.export_plan`)."""
    token = _PROFILES.set({})
    try:
        yield
    finally:
        _PROFILES.reset(token)


def orbit_time_s(p: Profile) -> float:
    """The time (s) ``p``'s orbits add to the 2-D flight: the take-off climb spiral's and the
    descent orbit's (0 without either), charged against eq. 18's 0.85 T by
    :func:`plan_profiles`."""
    return (0.0 if p.climb is None else p.climb.time_s) + (
        0.0 if p.descent is None else p.descent.time_s
    )


def plan_profiles(plan: Any, charge: bool = True) -> list[Profile] | None:
    """Every UAV's :func:`~poc_env.agents.mission.terrain.profile` over the plan's recorded
    terrain; None without terrain. Within :func:`profiles_once`, a UAV's profile computed
    before (the same record, UAV and zone objects) is reused.

    A UAV whose straight take-off climb meets the ground climbs on a spiral over its field
    first (:func:`climb_spiral`, at the plan's transit speed): its time is charged against eq.
    18's 0.85 T (the terrain record's ``usable_endurance_s``) on top of the plan's
    ``flight_time_s``, which the 2-D time model flies without it (so is a descent orbit's). A
    UAV whose flight alone is beyond 0.85 T is not charged: the plan marks it infeasible and
    the export's over-endurance check refuses it (``--allow-infeasible`` writes it). With
    ``charge`` False no orbit time is checked (the planners'
    :func:`poc_env.agents.planning.geography.fit_orbits` reads the orbits first).

    Raises
    ------
    ConfigError
        Naming ``plan.uavs[k]``: clearance impossible within the ceiling; a take-off climb
        that meets the ground even on a climb spiral, or a spiral whose time takes the flight
        beyond 0.85 T (the minutes missing named).
    """
    rec = plan.get("terrain")
    if rec is None:
        return None
    from poc_env.agents.mission.plan import flight

    memo = _PROFILES.get()
    zones = plan.get("no_fly_zones_m") or ()
    fl = flight(plan)
    speed = fl["transit_speed_mps"]
    route_speed = route_speed_mps(fl)
    layered = bool(plan.get("altitude_layers"))
    t: Terrain | None = None
    out = []
    for k, u in enumerate(plan["uavs"]):
        key = (id(rec), id(u), id(zones), charge)
        if memo is not None and key in memo:
            out.append(memo[key][-1])
            continue
        t = t or _record_terrain(rec, memo)
        where = f"plan.uavs[{k}] (UAV {u['id']})"
        area = plan.get("operating_area_m")
        p = landing_profile(t, u, zones, where, speed, area, route_speed)
        if charge and not layered:  # with layers: once the orbits are kept apart, below
            _charge_orbits(t, u, p, where)
        if memo is not None:
            memo[key] = (rec, u, zones, p)
        out.append(p)
    if layered:  # field-mates' concentric orbits kept apart, then charged
        t = t or _record_terrain(rec, memo)
        out = separate_orbits(plan, t, out)
        for k, (u, p) in enumerate(zip(plan["uavs"], out)):
            if charge:
                _charge_orbits(t, u, p, f"plan.uavs[{k}] (UAV {u['id']})")
    return out


def _record_terrain(rec: dict[str, Any], memo: dict | None) -> Terrain:
    """The plan's terrain record as a :class:`Terrain`: read once within
    :func:`profiles_once` (the orbit fit's trials call :func:`plan_profiles` once per dropped
    waypoint, and each read the whole grid from the record again, i24-missionfix), else read
    now."""
    if memo is None:
        return from_record(rec)
    key = ("terrain", id(rec))
    if key not in memo:
        memo[key] = (rec, from_record(rec))  # rec kept alive, so that its id stays its own
    t: Terrain = memo[key][-1]
    return t


def _charge_orbits(t: Terrain, u: Any, p: Profile, where: str) -> None:
    """Eq. 18 with UAV ``u``'s orbits (:func:`_check_orbit_time`, :func:`_check_spiral_time`),
    unless its flight alone is beyond 0.85 T (the over-endurance check's)."""
    f = u.get("flight_time_s")  # (the greedy baseline's routes record none)
    over = t.usable_endurance_s is not None and f is not None and f > t.usable_endurance_s + 1e-6
    if over:  # the flight itself is over: the over-endurance check's
        return
    if p.descent is not None:
        _check_orbit_time(t, p, float(u["flight_time_s"]), where)
    elif p.climb is not None:
        _check_spiral_time(t, p.climb, float(u["flight_time_s"]), where)


def route_speed_mps(fl: dict[str, float]) -> float:
    """The fastest of a plan's ``flight`` speeds (transit out, search, cruise home): the speed
    a profile's legs are bounded at (:func:`vertical_angle`)."""
    return max(fl["transit_speed_mps"], fl["search_speed_mps"], fl["cruise_speed_mps"])


def _check_spiral_time(t: Terrain, sp: Spiral, flight_s: float, where: str) -> None:
    """Eq. 18 with the climb spiral: ``flight_s + sp.time_s <= 0.85 T`` (``t``'s usable
    endurance; not checked when the plan records none).

    Raises
    ------
    ConfigError
        ``where`` named, with the flight time, the spiral's and the minutes missing.
    """
    if t.usable_endurance_s is None:
        return
    total = flight_s + sp.time_s
    if total > t.usable_endurance_s + 1e-6:
        raise ConfigError(
            where, f"flight {flight_s / 60:.1f} min + take-off climb spiral {sp.time_s / 60:.1f} "
            f"min = {total / 60:.1f} min",
            f"at most eq. 18's 0.85 T = {t.usable_endurance_s / 60:.1f} min: "
            f"{(total - t.usable_endurance_s) / 60:.1f} min missing for the climb spiral over "
            f"the take-off field ({sp.turns:.1f} turns of radius {sp.radius_m / 1e3:.2f} km up "
            f"to {sp.to_m:.0f} m AMSL; re-plan this UAV with a shorter route, or from another "
            "take-off field)",
        )  # fmt: skip


def _check_orbit_time(t: Terrain, p: Profile, flight_s: float, where: str) -> None:
    """Eq. 18 with the descent orbit (and the climb spiral, if any): ``flight_s`` + both
    orbits' time ``<= 0.85 T`` (not checked when the plan records no endurance).

    Raises
    ------
    ConfigError
        ``where`` named, with the flight time, the orbits' and the minutes missing.
    """
    if t.usable_endurance_s is None or p.descent is None:
        return
    climb_s = 0.0 if p.climb is None else p.climb.time_s
    total = flight_s + climb_s + p.descent.time_s
    if total > t.usable_endurance_s + 1e-6:
        o = p.descent.orbit
        raise ConfigError(
            where, f"flight {flight_s / 60:.1f} min + take-off climb spiral {climb_s / 60:.1f} "
            f"min + descent orbit {p.descent.time_s / 60:.1f} min = {total / 60:.1f} min",
            f"at most eq. 18's 0.85 T = {t.usable_endurance_s / 60:.1f} min: "
            f"{(total - t.usable_endurance_s) / 60:.1f} min missing for the orbits (the descent "
            f"at the landing approach point: radius {o.radius_m / 1e3:.2f} km from {o.from_m:.0f}"
            f" to {o.to_m:.0f} m AMSL; re-plan this UAV with a shorter route, or to another "
            "landing field)",
        )  # fmt: skip


def approaches(plan: Any) -> list[list[float]]:
    """Each UAV's landing approach point as its mission flies it: the terrain profile's (which
    may have turned it round the field, :func:`landing_profile`) when the plan has terrain and
    its profiles are found, else :func:`~poc_env.agents.mission.plan.approach_point`'s."""
    zones = plan.get("no_fly_zones_m")
    profs = None
    if plan.get("terrain") is not None:
        with contextlib.suppress(ConfigError):  # refused elsewhere, naming the UAV
            profs = plan_profiles(plan)
    if profs is None:
        return [approach_point(u, zones) for u in plan["uavs"]]
    return [pr.points_m[-1].tolist() for pr in profs]


# --------------------------------------------------------------------------- checking exports


def dem_heights_at(dem: str | Path, latlon: Any) -> np.ndarray:
    """Heights of the GeoTIFF ``dem`` itself at ``(lat, lon)`` points (WGS84): the highest of
    the 2 x 2 pixels around each point (an independent check of exported altitudes, read from
    the DEM's own pixels rather than the resampled :class:`Terrain`)."""
    import rasterio
    from pyproj import Transformer

    pts = np.asarray(latlon, dtype=float).reshape(-1, 2)
    with rasterio.open(dem) as src:
        band = dem_metres(src, src.read(1))
        to_src = Transformer.from_crs("EPSG:4326", src.crs, always_xy=True)
        sx, sy = to_src.transform(pts[:, 1], pts[:, 0])
        cols, rows = ~src.transform @ (np.asarray(sx), np.asarray(sy))
    c0 = np.clip(np.floor(np.asarray(cols) - 0.5).astype(int), 0, band.shape[1] - 2)
    r0 = np.clip(np.floor(np.asarray(rows) - 0.5).astype(int), 0, band.shape[0] - 2)
    return np.maximum.reduce(
        [band[r0, c0], band[r0 + 1, c0], band[r0, c0 + 1], band[r0 + 1, c0 + 1]]
    )


def qgc_clearance(doc: dict[str, Any], dem: str | Path, step_m: float = 100.0) -> tuple[float, int]:
    """(least height above the DEM, legs checked) along a QGC ``.plan`` mission ``doc`` from
    its take-off item to its last waypoint (commands 22, 31 and 16, altitudes AMSL, linear
    between items; a climb spiral, command 31 over the field, as a climb there), legs sampled
    about every ``step_m`` metres (:func:`dem_heights_at`)."""
    from pyproj import Geod

    nav = [it for it in doc["mission"]["items"] if it.get("command") in (16, 22, 31)]
    pts = np.array([[it["params"][4], it["params"][5], it["params"][6]] for it in nav], float)
    geod = Geod(ellps="WGS84")
    legs = []
    for a, b in itertools.pairwise(pts):
        dist = geod.inv(a[1], a[0], b[1], b[0])[2]
        n = max(2, math.ceil(dist / step_m) + 1)
        s = np.linspace(0.0, 1.0, n)[:, None]
        legs.append(a[None, :] + (b - a)[None, :] * s)
    if not legs:
        return math.inf, 0
    p = np.concatenate(legs)  # every leg's samples read from the DEM at once
    return float(np.min(p[:, 2] - dem_heights_at(dem, p[:, :2]))), len(legs)
