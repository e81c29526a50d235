"""Geographic scenarios in: GeoJSON/KML areas, airfields and no-fly zones, GeoTIFF/CSV priors.

``poc-env scenario import area.geojson --prior prior.tif --airfields fields.geojson --out my.yaml``
turns GIS layers (longitude/latitude, WGS84) into a ready scenario: a YAML file, its prior as a
``.npy`` grid beside it and a ``.crs.json`` sidecar holding the coordinate reference system
(the :func:`poc_env.agents.mission.crs.make_crs` record). Every projection goes through
:func:`poc_env.agents.mission.crs.to_local` (pyproj); nothing here projects by hand.
The formats, the resampling rule and the errors are documented in docs/GEO.md.

- CRS: azimuthal equidistant (default; ``utm`` on request) centred on ``origin`` (lat, lon);
  the default origin is the south-west corner of the area's longitude/latitude bounding box
  (min lat, min lon), so the map's local coordinates start near (0, 0) and grow east/north.
- Map: the bounding box of the area polygon in local metres, grown outwards to whole cells
  (``map.origin_km`` is the grid's south-west corner, a multiple of ``cell_km``).
- Prior (mass conserving): every GeoTIFF pixel value is the probability mass of that pixel;
  each pixel is cut into ``s x s`` equal sub-pixels (``s`` chosen so that a sub-pixel spans at
  most a quarter of a cell, 1 <= s <= 16), each carrying ``value / s**2`` at its centre; the
  centre is projected (raster CRS -> WGS84 -> local) and its mass added to the grid cell it falls
  in. A CSV of ``lat,lon,probability`` points adds each point's probability to its cell. Mass
  whose sample point falls outside the area polygon is dropped and reported (a warning above
  1 %); the rest is normalised to 1.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml
from shapely import contains_xy
from shapely.geometry import Point, Polygon
from shapely.geometry.polygon import orient

import poc_env.limits as limits
from poc_env.agents.mission.crs import MAX_DISTANCE_KM, make_crs, parse_origin, to_local
from poc_env.crs import EDGE_TOLERANCE_M, continuous_lon, densify_ring, geojson_crs_to_lonlat
from poc_env.errors import (
    ConfigError,
    GeometryError,
    as_number,
    check_name,
    require_extra,
    say_warning,
)
from poc_env.geometry import check_zones_leave_room, validate_polygon
from poc_env.io import atomic_path

KM = 1000.0
VECTOR_SUFFIXES = (".geojson", ".json", ".kml")
PRIOR_SUFFIXES = (".tif", ".tiff", ".csv")
#: Mass outside the area above this share of the prior's total gives a warning.
OUTSIDE_WARN = 0.01
#: At most this many sub-pixel samples of a GeoTIFF are projected (s is lowered to fit).
MAX_SAMPLES = 4_000_000


# --------------------------------------------------------------------------- reading features
def _check_file(
    path: str | os.PathLike[str], what: str, suffixes: tuple[str, ...], field: str
) -> Path:
    """``path`` checked as the input ``field`` (the option it came from, named in the error
    with the path): its suffix, then readable as a regular file
    (:func:`poc_env.io.check_input_file`: missing, a FIFO, no permission), then not empty."""
    from poc_env.io import check_input_file

    p = Path(path)
    allowed = f"an existing {' / '.join(suffixes)} file ({what})"
    if p.suffix.lower() not in suffixes:
        raise ConfigError(field, str(p), f"{allowed}; it ends in {p.suffix or '(no suffix)'!r}")
    check_input_file(field, p, allowed)
    if p.stat().st_size == 0:
        raise ConfigError(field, str(p), f"{allowed}; it is an empty file")
    return p


def _feature(file: Path, i: int) -> str:
    return f"{file} feature {i}"


def _lonlat(file: Path, i: int, coords: Any) -> np.ndarray:
    """[[lon, lat(, alt)], ...] -> (n, 2) array; swapped or out-of-range values refused."""
    where = _feature(file, i)
    try:
        arr = np.array([[float(c[0]), float(c[1])] for c in coords], dtype=float)
    except (TypeError, ValueError, IndexError, KeyError):
        raise ConfigError(where, coords, "[longitude, latitude] number pairs") from None
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ConfigError(where, coords, "finite [longitude, latitude] pairs")
    bad = np.abs(arr[:, 1]) > 90
    if bad.any():
        k = int(np.argmax(bad))
        hint = " (latitude and longitude swapped? GeoJSON and KML write longitude first)"
        raise ConfigError(
            f"{where} vertex {k}", arr[k].tolist(), f"[longitude, latitude], |latitude| <= 90{hint}"
        )
    if (np.abs(arr[:, 0]) > 180).any():
        k = int(np.argmax(np.abs(arr[:, 0]) > 180))
        raise ConfigError(f"{where} vertex {k}", arr[k].tolist(), "longitude in [-180, 180]")
    return arr


def _geojson_crs(file: Path, doc: Any, outer: Any = None) -> Any:
    """The reprojection to longitude/latitude of ``doc``'s GeoJSON 2008 ``crs`` member
    (:func:`poc_env.crs.geojson_crs_to_lonlat`; a UTM or Web Mercator layer is reprojected, a
    CRS pyproj cannot read refused naming the file); ``outer``: the enclosing collection's,
    which a Feature without its own keeps."""
    if not isinstance(doc, dict) or doc.get("crs") is None:
        return outer
    return geojson_crs_to_lonlat(doc["crs"], f"{file} crs")


def _reprojected(coords: Any, reproject: Any) -> Any:
    """GeoJSON ``coordinates`` (nested lists of positions) with every position reprojected
    to [lon, lat] (altitudes kept); anything that is not numbers is left for the checks."""
    if reproject is None or not isinstance(coords, list) or not coords:
        return coords
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in coords):
        if len(coords) < 2:
            return coords
        lon, lat = reproject(np.array([coords[:2]], dtype=float))[0]
        return [float(lon), float(lat), *coords[2:]]
    return [_reprojected(c, reproject) for c in coords]


def _geojson_features(file: Path) -> list[tuple[str, Any, dict]]:
    """[(geometry type, coordinates, properties)] of a GeoJSON Feature, collection or geometry."""
    from poc_env.io import loads_json

    try:  # the one JSON reader: NaN / Infinity and nesting too deep are refused too
        doc = loads_json(file.read_bytes(), str(file))
    except ConfigError as err:
        why = f"not JSON ({err.allowed})"
        raise ConfigError(str(file), why, "a GeoJSON file (RFC 7946)") from None
    if not isinstance(doc, dict) or "type" not in doc:
        raise ConfigError(str(file), type(doc).__name__, "a GeoJSON object with a type member")
    reproject = _geojson_crs(file, doc)
    if doc["type"] == "FeatureCollection":
        feats = doc.get("features")
        if not isinstance(feats, list):
            raise ConfigError(f"{file} features", feats, "a list of Features")
    elif doc["type"] == "Feature":
        feats = [doc]
    else:
        feats = [{"type": "Feature", "geometry": doc, "properties": {}}]
    out = []
    for i, f in enumerate(feats):
        if not isinstance(f, dict):
            raise ConfigError(_feature(file, i), f, "a GeoJSON Feature")
        own = _geojson_crs(file, f, reproject)
        g = f.get("geometry")
        props = f.get("properties") or {}
        if not isinstance(g, dict) or not isinstance(props, dict):
            raise ConfigError(_feature(file, i), g, "a Feature with a geometry and properties")
        out.append((str(g.get("type")), _reprojected(g.get("coordinates"), own), props))
    return out


def _strip(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _kml_coords(text: str | None) -> list[list[float]]:
    out = []
    for tok in (text or "").split():
        out.append([float(v) for v in tok.split(",")])
    return out


def _kml_features(file: Path) -> list[tuple[str, Any, dict]]:
    """Placemarks of a KML file as GeoJSON-like (type, coordinates, {"name": ...})."""
    raw = file.read_bytes()
    if b"<!DOCTYPE" in raw or b"<!ENTITY" in raw:
        raise ConfigError(str(file), "a DOCTYPE/ENTITY declaration", "plain KML (no DTD)")
    try:
        root = ET.fromstring(raw)
    except ET.ParseError as err:
        raise ConfigError(str(file), f"not XML ({err})", "a KML file") from None
    out: list[tuple[str, Any, dict]] = []
    for i, pm in enumerate(e for e in root.iter() if _strip(e.tag) == "Placemark"):
        name = next((c.text for c in pm if _strip(c.tag) == "name"), None)
        props = {"name": (name or "").strip()} if name is not None else {}
        polys, points = [], []
        try:
            for e in pm.iter():
                t = _strip(e.tag)
                if t == "Point":
                    c = next(x for x in e.iter() if _strip(x.tag) == "coordinates")
                    points.append(_kml_coords(c.text)[0])
                elif t == "Polygon":
                    rings: list[list[list[float]]] = []
                    for b in e:
                        bt = _strip(b.tag)
                        if bt in ("outerBoundaryIs", "innerBoundaryIs"):
                            c = next(x for x in b.iter() if _strip(x.tag) == "coordinates")
                            ring = _kml_coords(c.text)
                            if bt == "outerBoundaryIs":
                                rings.insert(0, ring)
                            else:
                                rings.append(ring)
                    polys.append(rings)
        except (ValueError, IndexError, StopIteration):
            raise ConfigError(
                _feature(file, i), name, "KML coordinates 'lon,lat[,alt] ...'"
            ) from None
        if polys:
            out.append(("Polygon" if len(polys) == 1 else "MultiPolygon", _one(polys), props))
        elif points:
            out.append(("Point", points[0], props))
        else:  # named by its geometry (a LineString, a gx:Track, ...), else "(none)"
            kinds = (_strip(e.tag) for e in pm.iter() if isinstance(e.tag, str))
            other = next((k for k in kinds if k in KML_OTHER_GEOMETRIES), "(none)")
            out.append((other, None, props))
    return out


#: KML geometries that are not a Point or Polygon, named in errors when a Placemark has one.
KML_OTHER_GEOMETRIES = ("LineString", "LinearRing", "Track", "MultiTrack", "Model")


def _one(polys: list) -> Any:
    return polys[0] if len(polys) == 1 else polys


def read_features(
    path: str | os.PathLike[str], what: str, field: str = "file"
) -> tuple[Path, list]:
    """(checked path, [(type, coordinates, properties)]) of a GeoJSON or KML file (``field``:
    the option it came from, named when the file cannot be read)."""
    file = _check_file(path, what, VECTOR_SUFFIXES, field)
    feats = _kml_features(file) if file.suffix.lower() == ".kml" else _geojson_features(file)
    if not feats:
        raise ConfigError(str(file), "no features", f"at least one feature ({what})")
    return file, feats


# --------------------------------------------------------------------------- polygons, points
def _polygons(file: Path, feats: list) -> list[tuple[int, list]]:
    """[(feature index, rings)] of every Polygon / MultiPolygon part; other types refused."""
    out = []
    for i, (gtype, coords, _) in enumerate(feats):
        if gtype == "Polygon":
            out.append((i, coords))
        elif gtype == "MultiPolygon" and isinstance(coords, list):
            out.extend((i, rings) for rings in coords)
        else:
            raise ConfigError(_feature(file, i), gtype, "a Polygon or MultiPolygon (lon/lat)")
    return out


def _antimeridian_area(file: Path, polys: list) -> np.ndarray | None:
    """The (lon, lat) ring of an area crossing the 180th meridian written as RFC 7946 section
    3.1.9 asks (a MultiPolygon cut there: parts of one feature, each with vertices on +-180,
    that join into one polygon), in longitudes continuous around its first vertex (180.5, not
    -179.5; :func:`poc_env.crs.continuous_lon`); None when ``polys`` are not such parts."""
    if len(polys) < 2 or len({i for i, _ in polys}) != 1:
        return None
    parts = []
    for i, rings in polys:
        if not isinstance(rings, list) or len(rings) != 1:
            return None
        ll = _lonlat(file, i, rings[0])
        if not np.any(np.abs(ll[:, 0]) == 180.0):
            return None
        parts.append(ll)
    lon0 = float(parts[0][0, 0])
    shapes = [
        Polygon(np.column_stack([continuous_lon(ll[:, 0], (0.0, lon0)), ll[:, 1]])) for ll in parts
    ]
    if not all(p.is_valid for p in shapes):
        return None
    joined = shapely.union_all(shapes)
    if joined.geom_type != "Polygon" or len(joined.interiors):
        return None
    return np.asarray(joined.exterior.coords)[:-1]


def _local_polygon(
    file: Path, i: int, rings: Any, crs: dict, joined: np.ndarray | None = None
) -> Polygon:
    """One GeoJSON polygon (lon/lat rings) -> a valid local-metre shapely polygon, CCW.

    Either winding is accepted and re-oriented (RFC 7946 asks for a counter-clockwise exterior;
    many tools write clockwise). Holes are refused: give them as no-fly zones, or draw the area
    without them. Self-intersections and zero areas are refused by ``validate_polygon``.
    """
    where = _feature(file, i)
    if not isinstance(rings, list) or not rings:
        raise ConfigError(where, rings, "a Polygon: a list of linear rings [[lon, lat], ...]")
    if len(rings) > 1:
        raise GeometryError(
            f"{where}: a polygon with {len(rings) - 1} hole(s); allowed: polygons without holes "
            "(give a hole that must not be flown as a --no-fly polygon, or draw the area "
            "without it)"
        )
    ll = _lonlat(file, i, rings[0]) if joined is None else joined
    if len(ll) > 1 and np.allclose(ll[0], ll[-1]):
        ll = ll[:-1]
    if np.ptp(ll[:, 0]) > 180:
        raise GeometryError(f"{where}: spans more than 180 deg of longitude; allowed: an area "
                            "spanning less, one that crosses the antimeridian cut there into a "
                            "MultiPolygon (RFC 7946 3.1.9)")  # fmt: skip
    if file.suffix.lower() != ".kml":  # GeoJSON: edges straight in lon/lat (RFC 7946 3.1.1)
        ll = densify_ring(ll, crs, straight_in="lonlat")
    xy = np.array(to_local(ll[:, ::-1], crs))
    poly = validate_polygon(xy, where)
    return orient(poly, 1.0)


def _points(file: Path, feats: list) -> list[tuple[int, str, np.ndarray]]:
    out = []
    for i, (gtype, coords, props) in enumerate(feats):
        if gtype != "Point":
            raise ConfigError(_feature(file, i), gtype, "a Point with a name property (airfield)")
        name = props.get("name")
        if not isinstance(name, str) or not name.strip():
            raise ConfigError(f"{_feature(file, i)} name", name, "a non-empty name property")
        check_name(f"{_feature(file, i)} name", name.strip(), limits.MAX_AIRFIELD_NAME)
        out.append((i, name.strip(), _lonlat(file, i, [coords])[0]))
    return out


def _near(file: Path, i: int, xy: np.ndarray, ll: np.ndarray, area: Polygon, crs: dict) -> None:
    """Refuse a point far from the area; say so when swapping lat/lon would bring it near."""
    d = area.distance(Point(float(xy[0]), float(xy[1])))
    if d <= MAX_DISTANCE_KM * KM:
        return
    hint = ""
    if abs(ll[0]) <= 90:
        sx, sy = to_local([(ll[0], ll[1])], crs)[0]
        if area.distance(Point(sx, sy)) <= MAX_DISTANCE_KM * KM:
            hint = " (latitude and longitude swapped? write [longitude, latitude])"
    raise ConfigError(
        _feature(file, i),
        [float(ll[0]), float(ll[1])],
        f"a point within {MAX_DISTANCE_KM:g} km of the search area (it is {d / KM:.0f} km away)"
        + hint,
    )


# --------------------------------------------------------------------------- grid and prior
class _Grid:
    def __init__(self, area: Polygon, cell_m: float) -> None:
        x0, y0, x1, y1 = area.bounds
        self.cell = cell_m
        self.x0 = math.floor(x0 / cell_m + 1e-9) * cell_m
        self.y0 = math.floor(y0 / cell_m + 1e-9) * cell_m
        self.nx = max(1, math.ceil((x1 - self.x0) / cell_m - 1e-9))
        self.ny = max(1, math.ceil((y1 - self.y0) / cell_m - 1e-9))

    def bin(self, x: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
        ix = np.clip(np.floor((x - self.x0) / self.cell).astype(np.int64), 0, self.nx - 1)
        iy = np.clip(np.floor((y - self.y0) / self.cell).astype(np.int64), 0, self.ny - 1)
        flat = np.bincount(iy * self.nx + ix, weights=w, minlength=self.nx * self.ny)
        return flat.reshape(self.ny, self.nx)  # row 0 at the south edge


def _uniform_prior(grid: _Grid, area: Polygon) -> np.ndarray:
    xs = grid.x0 + (np.arange(grid.nx) + 0.5) * grid.cell
    ys = grid.y0 + (np.arange(grid.ny) + 0.5) * grid.cell
    X, Y = np.meshgrid(xs, ys)
    m = contains_xy(area, X, Y).astype(float)
    if m.sum() == 0:
        m[:] = 1.0
    return m


def _read_csv(file: Path, crs: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, probability) of a lat,lon,probability CSV (header required)."""
    allowed = "a CSV with a header row lat,lon,probability and numbers below it"
    try:
        return _read_csv_rows(file, crs, allowed)
    except (UnicodeDecodeError, csv.Error) as err:
        raise ConfigError(str(file), f"not UTF-8 CSV text ({err})", allowed) from None


def _read_csv_rows(
    file: Path, crs: dict, allowed: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_read_csv` on a file that decodes (decoding and CSV errors raised as they come)."""
    with open(file, newline="", encoding="utf-8-sig") as fh:  # a spreadsheet's BOM dropped
        reader = csv.reader(fh)
        try:
            header = [h.strip().lower() for h in next(reader)]
        except StopIteration:
            raise ConfigError(str(file), "an empty file", allowed) from None
        need = ("lat", "lon", "probability")
        missing = [c for c in need if c not in header]
        if missing:
            raise ConfigError(f"{file} header", header, f"{allowed} (missing: {missing})")
        cols = [header.index(c) for c in need]
        rows = []
        for n, row in enumerate(reader, start=2):
            if not row or not any(v.strip() for v in row):
                continue
            vals = []
            for c, name in zip(cols, need):
                v = row[c].strip() if c < len(row) else ""
                try:
                    f = float(v)
                except ValueError:
                    f = math.nan
                if not math.isfinite(f):
                    raise ConfigError(f"{file} line {n} {name}", v, "a finite number")
                vals.append(f)
            if vals[2] < 0:
                raise ConfigError(f"{file} line {n} probability", vals[2], "a number >= 0")
            if abs(vals[0]) > 90:
                raise ConfigError(
                    f"{file} line {n} lat", vals[0],
                    "a latitude in [-90, 90] (lat and lon swapped?)",
                )  # fmt: skip
            if abs(vals[1]) > 180:
                raise ConfigError(f"{file} line {n} lon", vals[1], "a longitude in [-180, 180]")
            rows.append(vals)
    if not rows:
        raise ConfigError(str(file), "a header and no data rows", allowed)
    arr = np.array(rows)
    xy = np.array(to_local(arr[:, :2], crs))
    return xy[:, 0], xy[:, 1], arr[:, 2]


def _read_geotiff(file: Path, crs: dict, grid: _Grid, area: Polygon) -> tuple[np.ndarray, ...]:
    """(x, y, mass) of the sub-pixel samples of a GeoTIFF (module docstring)."""
    require_extra("geo", "poc-env scenario import of a GeoTIFF", "rasterio")
    import rasterio
    from rasterio.errors import RasterioError, RasterioIOError

    try:
        src = rasterio.open(file)
    except RasterioIOError as err:
        raise ConfigError(str(file), f"unreadable ({err})", "a GeoTIFF file") from None
    try:
        return _geotiff_samples(file, src, grid, area, crs)
    except RasterioError as err:  # a truncated or corrupt raster fails when read
        raise ConfigError(str(file), f"unreadable ({err})", "a complete GeoTIFF file") from None


def _geotiff_samples(file: Path, src: Any, grid: _Grid, area: Polygon, crs: dict) -> tuple:
    """:func:`_read_geotiff` on an opened raster ``src`` (closed on return)."""
    from pyproj import Transformer

    with src:
        if src.crs is None:
            raise ConfigError(
                f"{file} crs", None,
                "a GeoTIFF with a coordinate reference system (georeference it in your GIS)",
            )  # fmt: skip
        band = src.read(1, masked=True).astype(float).filled(0.0)
        transform = src.transform
        to_wgs = Transformer.from_crs(src.crs, "EPSG:4326", always_xy=True)
        from_wgs = Transformer.from_crs("EPSG:4326", src.crs, always_xy=True)
        h, w = band.shape
    band = np.where(np.isfinite(band), band, 0.0)
    if (band < 0).any():
        raise ConfigError(f"{file} band 1", float(band.min()), "probabilities >= 0")
    if band.sum() <= 0:
        raise ConfigError(f"{file} band 1", "all zero", "a raster with positive probability mass")

    def local(cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
        a, b, c, d, e, f = (float(v) for v in tuple(transform)[:6])
        xs, ys = a * cols + b * rows + c, d * cols + e * rows + f
        lon, lat = to_wgs.transform(np.asarray(xs), np.asarray(ys))
        return np.array(to_local(np.column_stack([lat, lon]), crs)).reshape(-1, 2)

    # coverage: the area's densified boundary and a 40 x 40 lattice of its interior points,
    # taken into the raster's pixel space, must all lie on the raster
    ring = np.asarray(shapely.segmentize(area.exterior, grid.cell / 2).coords)
    bx0, by0, bx1, by1 = area.bounds
    gx, gy = np.meshgrid(np.linspace(bx0, bx1, 40), np.linspace(by0, by1, 40))
    interior = np.column_stack([gx.ravel(), gy.ravel()])
    interior = interior[contains_xy(area, interior[:, 0], interior[:, 1])]
    ring_cr = _pixels(ring, crs, from_wgs, ~transform)
    on = [_on(*ring_cr, w, h), _on(*_pixels(interior, crs, from_wgs, ~transform), w, h)]
    if not (on[0].all() and on[1].all()):
        share = float(on[1].mean()) if len(on[1]) else 0.0
        raise ConfigError(
            str(file),
            f"a raster covering about {share:.0%} of the search area",
            "a GeoTIFF covering the whole search area",
        )
    # only pixels in the area's pixel-space bounding box (+1 pixel) can put mass in it; the
    # mass of every other pixel is outside the area as a whole (no need to project it)
    c0, c1 = max(0, int(ring_cr[0].min()) - 1), min(w, int(ring_cr[0].max()) + 2)
    r0, r1 = max(0, int(ring_cr[1].min()) - 1), min(h, int(ring_cr[1].max()) + 2)
    window = np.zeros_like(band, dtype=bool)
    window[r0:r1, c0:c1] = True
    rows_nz, cols_nz = np.nonzero(window & (band != 0))
    far = float(band[~window].sum())
    # sub-pixel size: a pixel's extent in metres from its projected neighbours
    rc, cc = max(0, min((r0 + r1) // 2, h - 1)), max(0, min((c0 + c1) // 2, w - 1))
    p = local(np.array([cc, cc + 1, cc]), np.array([rc, rc, rc + 1]))
    pix_m = max(np.hypot(*(p[1] - p[0])), np.hypot(*(p[2] - p[0])))
    s = int(min(16, max(1, math.ceil(pix_m / (grid.cell / 4)))))
    while s > 1 and len(rows_nz) * s * s > MAX_SAMPLES:
        s -= 1
    off = (np.arange(s) + 0.5) / s
    fc, fr = np.meshgrid(off, off)
    cols = (cols_nz[:, None] + fc.ravel()[None, :]).ravel()
    rows = (rows_nz[:, None] + fr.ravel()[None, :]).ravel()
    mass = np.repeat(band[rows_nz, cols_nz] / (s * s), s * s)
    xy = local(cols, rows)
    if far > 0:  # one sample far outside the area carrying the mass of every far pixel
        xy = np.vstack([xy, [[math.inf, math.inf]]])
        mass = np.append(mass, far)
    return xy[:, 0], xy[:, 1], mass


def _pixels(xy: np.ndarray, crs: dict, from_wgs: Any, inv: Any) -> tuple[np.ndarray, np.ndarray]:
    """(col, row) pixel coordinates of local points (via WGS84 and the inverse geotransform)."""
    from poc_env.agents.mission.crs import to_geographic

    ll = np.array(to_geographic(xy, crs)).reshape(-1, 2)
    if ll.size == 0:
        return np.zeros(0), np.zeros(0)
    x, y = from_wgs.transform(ll[:, 1], ll[:, 0])
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a, b, c, d, e, f = (float(v) for v in tuple(inv)[:6])
    return a * x + b * y + c, d * x + e * y + f


def _on(col: np.ndarray, row: np.ndarray, w: int, h: int) -> np.ndarray:
    eps = 1e-6
    ok = np.isfinite(col) & np.isfinite(row)
    return ok & (col >= -eps) & (col <= w + eps) & (row >= -eps) & (row <= h + eps)


def _prior(
    path: Any,
    crs: dict,
    grid: _Grid,
    area: Polygon,
    particles: Any = None,
    particles_time: str | None = None,
) -> tuple[np.ndarray, dict]:
    """The normalised prior grid and a report {total, outside, outside_share, samples}: from
    the ``path`` (GeoTIFF, CSV), or the ``particles`` of a trajectory NetCDF at
    ``particles_time`` (:mod:`poc_env.agents.mission.particles`, one equal mass each), or
    uniform over the area."""
    extra: dict[str, Any] = {}
    if particles is not None:
        from poc_env.agents.mission.particles import read_particles

        file = Path(particles)
        parts = read_particles(file, particles_time)
        xy = np.array(to_local(np.column_stack([parts.lat, parts.lon]), crs))
        x, y, w = xy[:, 0], xy[:, 1], np.ones(len(xy))
        extra = {"time": parts.time, "particles": parts.total, "inactive": parts.inactive}
    elif path is None:
        m = _uniform_prior(grid, area)
        return m / m.sum(), {"source": "uniform over the area", "outside_share": 0.0}
    else:
        file = _check_file(path, "prior", PRIOR_SUFFIXES, "prior")
        if file.suffix.lower() == ".csv":
            x, y, w = _read_csv(file, crs)
        else:
            x, y, w = _read_geotiff(file, crs, grid, area)
    # scaled by the largest sample first (as probability_map.validate_map does): finite
    # samples whose sum overflows (two of 1e308) keep their proportions
    peak = float(np.max(w)) if len(w) else 0.0
    if not peak > 0 or not math.isfinite(peak):
        raise ConfigError(str(file), "zero total probability", "positive probability mass")
    w = w / peak
    total = float(w.sum())
    # on the edge as drawn counts as inside: within the edges' tolerance (densify_ring), either side
    inside = contains_xy(area.buffer(EDGE_TOLERANCE_M), x, y)
    if file.suffix.lower() == ".csv" and inside.mean() < 0.5:
        swapped = np.array(to_local(np.column_stack(_swap_back(x, y, crs)), crs))
        if contains_xy(area, swapped[:, 0], swapped[:, 1]).mean() > inside.mean():
            raise ConfigError(
                str(file), f"{1 - inside.mean():.0%} of the points outside the area",
                "points in the search area (are the lat and lon columns swapped?)",
            )  # fmt: skip
    m = grid.bin(x[inside], y[inside], w[inside])
    kept = float(m.sum())
    if kept <= 0:
        raise ConfigError(str(file), "no probability mass inside the area", "a prior over it")
    outside = max(total - kept, 0.0)  # (rounding printed "-0.000%")
    report = {  # in the file's units (may overflow to inf; the share does not)
        "source": str(file),
        "total": total * peak,
        "inside": kept * peak,
        "outside": outside * peak,
        "outside_share": outside / total,
        "samples": len(w),
        **extra,
    }
    if outside / total > OUTSIDE_WARN:
        warnings.warn(
            f"{file}: {outside / total:.1%} of the prior's mass lies outside the search area "
            "and is dropped (the rest is normalised to 1)",
            stacklevel=3,
        )
    return m / kept, report


def _swap_back(x: np.ndarray, y: np.ndarray, crs: dict) -> tuple[np.ndarray, np.ndarray]:
    """(lat, lon) of local points read with lat and lon exchanged: (lon, lat) as (lat, lon)."""
    from poc_env.agents.mission.crs import to_geographic

    ll = np.array(to_geographic(np.column_stack([x, y]), crs))
    lat, lon = ll[:, 1], ll[:, 0]
    ok = np.abs(lat) <= 90
    return np.where(ok, lat, 0.0), np.where(ok, lon, 0.0)


# --------------------------------------------------------------------------- the import
def _base_mapping(base: str) -> dict[str, Any]:
    from poc_env.config import CONFIG_DIR, builtin_scenarios, read_yaml

    path = CONFIG_DIR / f"{base}.yaml" if base in builtin_scenarios() else Path(base)
    if not path.is_file():
        raise ConfigError(
            "base", base, "a built-in scenario (" + ", ".join(builtin_scenarios()) + ") or YAML"
        )
    return read_yaml(path)


def _km(v: float) -> float:
    return float(round(float(v) / KM, 6))


def import_scenario(
    area: str | os.PathLike[str],
    *,
    prior: str | os.PathLike[str] | None = None,
    airfields: str | os.PathLike[str] | None = None,
    no_fly: str | os.PathLike[str] | None = None,
    origin: Any = None,
    cell_km: float = 5.0,
    name: str = "imported",
    base: str = "paper_6_2",
    projection: str = "aeqd",
    dem: str | os.PathLike[str] | None = None,
    particles: str | os.PathLike[str] | None = None,
    particles_time: str | None = None,
    particle_motion: bool = False,
) -> dict[str, Any]:
    """Build a scenario from GIS layers; nothing is written (see :func:`write_imported`).

    The prior is ``prior`` (GeoTIFF, CSV), or the ``particles`` of an OpenDrift trajectory
    file at ``particles_time`` (default its last time), or uniform over the area.

    ``particle_motion``: the particles' trajectories also move the target
    (``target.model: particles``, :mod:`poc_env.theory.particles`): the episode starts at
    ``particles_time`` (default the file's *first* time), the prior is the particles there,
    and their tracks from then on (``result["tracks"]``, written as ``<stem>.particles.npz``)
    must cover the episode (the base scenario's horizon).

    ``dem``: a GeoTIFF of ground heights (m AMSL) recorded as ``terrain.dem`` (its absolute
    path) after :func:`poc_env.agents.mission.terrain.load_terrain` has read it over the
    scenario's operating area: a DEM without a CRS, not covering the area or with nodata over
    it is refused here, naming ``terrain.dem``.

    Returns {``scenario``: the YAML mapping (``prior: {kind: file, file: <name>.npy}``),
    ``prior``: the (ny, nx) grid summing to 1, ``crs``: the :func:`make_crs` record,
    ``report``: {``prior``: mass report, ``area_km2``, ``cells``}}. The base scenario gives the UAV,
    sensor, comms, episode and planner sections and the fleet size, spread round-robin over the
    imported airfields.
    """
    from poc_env.config import load_scenario

    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]{1,64}", name):
        raise ConfigError("name", name, "1-64 characters A-Z a-z 0-9 _ . -")
    cell_km = as_number("cell_km", cell_km, limits.MIN_CELL_KM, limits.MAX_EXTENT_KM)
    if prior is not None and particles is not None:
        raise ConfigError("particles", str(particles), "either --prior or --particles, not both")
    if particles_time is not None and particles is None:
        raise ConfigError("particles_time", particles_time, "only with --particles")
    if particle_motion and particles is None:
        raise ConfigError("particle_motion", True, "only with --particles FILE.nc")
    tracks = None
    if particle_motion:
        from poc_env.agents.mission.particles import read_tracks

        assert particles is not None
        tracks = read_tracks(Path(particles), particles_time)
        particles_time = tracks.start  # the prior: the same particles at the same time
    if airfields is None:
        raise ConfigError(
            "airfields", None,
            "a GeoJSON/KML file of named airfield points (the base scenario's are in its own km)",
        )  # fmt: skip
    file, feats = read_features(area, "the search area: one Polygon", "area")
    polys = _polygons(file, feats)
    joined = _antimeridian_area(file, polys)  # one area cut at the 180th meridian, or None
    if len(polys) != 1 and joined is None:
        raise ConfigError(
            str(file), f"{len(polys)} polygons",
            "exactly one Polygon (the area), or one cut at the antimeridian into a "
            "MultiPolygon (RFC 7946 3.1.9)",
        )  # fmt: skip
    i_area, rings = polys[0]
    if origin is None:
        ll = joined if joined is not None else _lonlat(
            file, i_area, rings[0] if isinstance(rings, list) and rings else []
        )  # fmt: skip
        west = float(ll[:, 0].min())  # continuous across 180: wrapped only past it (the
        if not -180.0 <= west < 180.0:  # modulo would round 126.2 to 126.19999999999999)
            west = (west + 180.0) % 360.0 - 180.0
        origin = (float(ll[:, 1].min()), west)  # south-west corner
    elif isinstance(origin, str):
        origin = parse_origin(origin)
    crs = make_crs(projection, origin)
    poly = _local_polygon(file, i_area, rings, crs, joined)
    far = poly.distance(Point(0.0, 0.0))  # the origin is local (0, 0) in every projection
    if far > MAX_DISTANCE_KM * KM:  # the projection's scale error grows with the distance
        raise ConfigError(
            "origin", [float(v) for v in crs["origin_deg"]],
            f"a point within {MAX_DISTANCE_KM:g} km of the search area (it is {far / KM:.0f} km "
            "away; the map's scale error grows as (distance / R)^2 / 6: leave --origin out for "
            "the area's south-west corner)",
        )  # fmt: skip
    grid = _Grid(poly, cell_km * KM)

    ffile, ffeats = read_features(airfields, "airfields: named Points", "airfields")
    fields = []
    for i, fname, ll in _points(ffile, ffeats):
        xy = np.array(to_local([(ll[1], ll[0])], crs)[0])
        _near(ffile, i, xy, ll, poly, crs)
        fields.append({"name": fname, "position_km": [_km(xy[0]), _km(xy[1])]})
    names = [f["name"] for f in fields]
    if len(set(names)) != len(names):
        raise ConfigError(f"{ffile} names", names, "distinct airfield names")

    zones = []
    zone_names: list[str] = []
    if no_fly is not None:
        zfile, zfeats = read_features(no_fly, "no-fly zones: Polygons", "no_fly")
        for i, zr in _polygons(zfile, zfeats):
            z = _local_polygon(zfile, i, zr, crs)
            for v in np.asarray(z.exterior.coords)[:-1]:
                if poly.distance(Point(*v)) > MAX_DISTANCE_KM * KM:
                    _near(zfile, i, v, np.array(to_geographic_one(v, crs)), poly, crs)
            ring = np.asarray(z.exterior.coords)[:-1]
            zones.append([[_km(x), _km(y)] for x, y in ring])
            zname = str((zfeats[i][2] or {}).get("name") or "")
            zone_names.append(
                check_name(f"{_feature(zfile, i)} name", zname, limits.MAX_ZONE_NAME, empty=True)
            )

    if zones:  # the map's rectangle is checked by the loader; the area drawn is checked here
        check_zones_leave_room(
            [[(x * KM, y * KM) for x, y in z] for z in zones], zone_names, poly,
            f"the search area ({file.name} feature {i_area})",
        )  # fmt: skip
    grid_prior, prior_report = _prior(prior, crs, grid, poly, particles, particles_time)

    data = _base_mapping(base)
    n_uavs = sum(int(g.get("count", 1)) for g in data.get("fleet", [])) or len(fields)
    counts = [0] * len(fields)
    for k in range(n_uavs):
        counts[k % len(fields)] += 1
    old_map = data.get("map", {})
    data["name"] = name
    data["description"] = (
        f"imported from {one_line(Path(file).name)} (origin {origin[0]:.6f}, {origin[1]:.6f}; "
        f"{crs['kind']}), base {base}"
    )
    new_map: dict[str, Any] = {
        "width_km": _km(grid.nx * grid.cell),
        "height_km": _km(grid.ny * grid.cell),
        "cell_km": cell_km,
        "origin_km": [_km(grid.x0), _km(grid.y0)],
        "prior": {"kind": "file", "file": f"{name}.npy"},
        # the geography: plan reads it, so plan.json gets its CRS without --origin
        "origin_deg": [float(v) for v in crs["origin_deg"]],
        "projection": crs["kind"],
    }
    if crs["kind"] == "utm":
        new_map["utm_zone"] = int(crs["epsg"]) % 100
    if zones:
        new_map["no_fly_zones_km"] = zones
        if any(zone_names):  # kept end to end: YAML -> plan.json -> every export
            new_map["no_fly_names"] = zone_names
    if "threat_threshold" in old_map:
        new_map["threat_threshold"] = old_map["threat_threshold"]
    data["map"] = new_map
    data["airfields"] = fields
    data["fleet"] = [{"takeoff": f["name"], "count": c} for f, c in zip(fields, counts) if c]
    if dem is not None:
        data["terrain"] = {**(data.get("terrain") or {}), "dem": str(Path(dem).resolve())}
    if tracks is not None:
        data["target"] = {"model": "particles", "particles_file": f"{name}.particles.npz"}
    sc = load_scenario(data)  # every section checked as the loader will check it
    if tracks is not None:
        from poc_env.theory.particles import tracks_from_lonlat

        # the checks the environment will make (enough particles, the episode covered)
        tracks_from_lonlat(
            tracks.lon, tracks.lat, tracks.t_s, sc.map, sc.horizon_steps * sc.episode.dt_s,
            str(particles),
        )  # fmt: skip
        prior_report["stranded"] = tracks.stranded
    if dem is not None:
        from poc_env.agents.mission.terrain import load_terrain

        load_terrain(sc)  # the DEM read over the operating area: refused before any write
    return {
        "scenario": data,
        "prior": grid_prior,
        "crs": crs,
        "tracks": tracks,
        "report": {
            "prior": prior_report,
            "area_km2": poly.area / KM**2,
            "cells": (grid.ny, grid.nx),
        },
    }


def to_geographic_one(xy: Any, crs: dict) -> tuple[float, float]:
    """(lon, lat) of one local point (for error messages)."""
    from poc_env.agents.mission.crs import to_geographic

    lat, lon = to_geographic([xy], crs)[0]
    return lon, lat


def scenario_yaml(result: dict[str, Any]) -> str:
    """The YAML text of an imported scenario: a comment header with its CRS, then the mapping."""
    crs = result["crs"]
    lat, lon = crs["origin_deg"]
    name = result["scenario"]["name"]
    head = [
        f"# Imported by `poc-env scenario import` ({one_line(result['scenario']['description'])}).",
        f"# Geographic origin (local 0, 0): lat {lat!r}, lon {lon!r}; CRS {crs['kind']}:",
        f"#   {crs.get('proj', 'EPSG:' + str(crs.get('epsg')))}",
        f"# map.origin_deg/projection carry it (plan records the CRS: poc-env plan --scenario "
        f"{name}.yaml); the full record is in {name}.crs.json.",
        f"# The prior {name}.npy is read relative to this file's folder.",
    ]
    return "\n".join(head) + "\n" + yaml.safe_dump(result["scenario"], sort_keys=False)


def one_line(text: str) -> str:
    """``text`` with every character that is not printable on one line (line breaks, YAML's
    NEL/LS/PS, controls, lone surrogates) written as a backslash escape: safe in a comment."""
    out = []
    for c in text:
        if c.isprintable() and c not in "\x85\u2028\u2029\ufeff":
            out.append(c)
        else:
            n = ord(c)
            out.append(f"\\x{n:02x}" if n < 256 else f"\\u{n:04x}" if n < 65536 else f"\\U{n:08x}")
    return "".join(out)


def write_imported(result: dict[str, Any], out: str | os.PathLike[str]) -> list[Path]:
    """Write ``out`` (YAML), ``<stem>.npy`` and ``<stem>.crs.json`` (and, with particle
    motion, ``<stem>.particles.npz``) as a set.

    Every file is staged as a temporary file beside its destination and published only after
    all are complete (the .npz and .npy first, the YAML last, so a YAML never points at a
    missing file); an error while staging leaves no file behind and any old files untouched.
    """
    import contextlib

    p = Path(out)
    if p.suffix.lower() not in (".yaml", ".yml"):
        raise ConfigError("out", str(p), "a .yaml or .yml path")
    stem = p.stem
    tracks = result.get("tracks")
    if result["scenario"]["map"]["prior"]["file"] != f"{stem}.npy" or (
        tracks is not None
        and result["scenario"]["target"]["particles_file"] != f"{stem}.particles.npz"
    ):
        result = dict(result, scenario=dict(result["scenario"]))
        result["scenario"]["map"] = dict(result["scenario"]["map"])
        result["scenario"]["map"]["prior"] = {"kind": "file", "file": f"{stem}.npy"}
        if tracks is not None:
            result["scenario"]["target"] = {
                "model": "particles",
                "particles_file": f"{stem}.particles.npz",
            }
    npy, crs_json = p.with_name(f"{stem}.npy"), p.with_name(f"{stem}.crs.json")
    npz = p.with_name(f"{stem}.particles.npz")
    text = scenario_yaml(result)
    crs_text = json.dumps(result["crs"], indent=2) + "\n"
    with contextlib.ExitStack() as stack:
        ty = stack.enter_context(atomic_path(p))
        tc = stack.enter_context(atomic_path(crs_json))
        tn = stack.enter_context(atomic_path(npy))
        if tracks is not None:  # published first (the innermost)
            tz = stack.enter_context(atomic_path(npz))
            with open(tz, "wb") as fh:
                np.savez_compressed(
                    fh, lon=tracks.lon, lat=tracks.lat, t_s=tracks.t_s, start=np.str_(tracks.start)
                )
        with open(tn, "wb") as fh:
            np.save(fh, np.asarray(result["prior"], dtype=np.float64), allow_pickle=False)
        tc.write_text(crs_text, encoding="utf-8")
        ty.write_text(text, encoding="utf-8")
    return [p, npy, crs_json] + ([npz] if tracks is not None else [])


# --------------------------------------------------------------------------- command line
def add_scenario_import_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``poc-env scenario import``."""
    p.add_argument("area", help="search area: GeoJSON or KML with one Polygon (lon/lat, WGS84)")
    p.add_argument(
        "--prior", default=None, help="GeoTIFF (needs the geo extra) or CSV lat,lon,probability"
    )
    p.add_argument(
        "--particles",
        default=None,
        help="OpenDrift output (CF trajectory NetCDF, lon/lat): its particles as the prior "
        "(needs the ocean extra)",
    )
    p.add_argument(
        "--particles-time",
        default=None,
        help="ISO 8601 time of the particles to use (default the file's last time; with "
        "--particle-motion the episode's start, default the file's first time)",
    )
    p.add_argument(
        "--particle-motion",
        action="store_true",
        help="the particles' trajectories also move the target and the belief (target.model "
        "particles; their tracks written beside the scenario as <stem>.particles.npz)",
    )
    p.add_argument("--airfields", required=True, help="GeoJSON/KML Points with a name")
    p.add_argument("--no-fly", default=None, help="GeoJSON/KML Polygons: no-fly zones")
    p.add_argument(
        "--dem",
        default=None,
        help="GeoTIFF of ground heights (m AMSL, any CRS; needs the geo extra) covering the "
        "operating area: recorded as terrain.dem, missions then clear it",
    )
    p.add_argument("--out", required=True, help="scenario YAML (the .npy and .crs.json go beside)")
    p.add_argument(
        "--origin",
        default=None,
        help="LAT,LON of local (0, 0) (default: the area's south-west lon/lat corner)",
    )
    p.add_argument("--cell-km", type=float, default=5.0, help="cell side, km")
    p.add_argument("--projection", default="aeqd", help="aeqd or utm")
    p.add_argument("--base", default="paper_6_2", help="scenario giving UAV, sensor, fleet size")
    p.add_argument("--name", default=None, help="scenario name (default: the --out file's stem)")


def cmd_scenario_import(args: argparse.Namespace) -> int:
    """Run ``poc-env scenario import``; print what was written and the prior's mass report."""
    if args.projection not in ("aeqd", "utm"):
        raise ConfigError("projection", args.projection, "aeqd or utm")
    out = Path(args.out)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = import_scenario(
            args.area,
            prior=args.prior,
            airfields=args.airfields,
            no_fly=args.no_fly,
            origin=args.origin,
            cell_km=args.cell_km,
            name=args.name or out.stem,
            base=args.base,
            projection=args.projection,
            dem=args.dem,
            particles=args.particles,
            particles_time=args.particles_time,
            particle_motion=args.particle_motion,
        )
    for w in caught:
        say_warning(w.message)
    rep = result["report"]
    ny, nx = rep["cells"]
    sc = result["scenario"]
    lat, lon = result["crs"]["origin_deg"]
    print(
        f"area {rep['area_km2']:.0f} km^2; grid {nx} x {ny} cells of {sc['map']['cell_km']:g} km "
        f"from ({sc['map']['origin_km'][0]:g}, {sc['map']['origin_km'][1]:g}) km; "
        f"origin {lat:.6f}, {lon:.6f} ({result['crs']['kind']})"
    )
    pr = rep["prior"]
    if "total" in pr:
        print(
            f"prior {pr['source']}: {pr['samples']} samples, mass outside the area "
            f"{pr['outside_share']:.3%} (dropped; the rest normalised to 1)"
        )
        if "particles" in pr:
            print(
                f"particles at {pr['time']}: {pr['particles'] - pr['inactive']} active of "
                f"{pr['particles']} ({pr['inactive']} inactive, not counted)"
            )
        if "stranded" in pr:
            print(
                f"particle motion: {pr['stranded']} of them deactivated later (hold their "
                "last position)"
            )
    else:
        print(f"prior: {pr['source']}")
    for path in write_imported(result, out):
        print(f"wrote {path}")
    return 0
