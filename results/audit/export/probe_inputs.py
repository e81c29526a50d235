"""Probe inputs: imported areas with hostile names (S/W hemisphere; near 60 N) and DEMs."""

import importlib.util
import json
from pathlib import Path

HOST_Z = ['R&D <range> "Alpha"', "Zona d'exclusión ñandú", "منطقة محظورة 7", "אזור סגור"]
HOST_F = ['Base <A> & "B"', "Aeródromo O'Higgins", "مطار"]


def fc(feats):
    return {"type": "FeatureCollection", "features": feats}


def poly(name, ring):
    return {
        "type": "Feature",
        "properties": {"name": name},
        "geometry": {"type": "Polygon", "coordinates": [ring]},
    }


def pt(name, lon, lat):
    return {
        "type": "Feature",
        "properties": {"name": name},
        "geometry": {"type": "Point", "coordinates": [lon, lat]},
    }


def box(w, s, e, n):
    return [[w, s], [e, s], [e, n], [w, n], [w, s]]


def write(tag, area, zones, fields, prior):
    d = Path(tag)
    d.mkdir(exist_ok=True)
    (d / "area.geojson").write_text(
        json.dumps(fc([poly("area " + tag + ' <&"> ', area)])), encoding="utf-8"
    )
    (d / "zones.geojson").write_text(
        json.dumps(fc([poly(n, r) for n, r in zones]), ensure_ascii=False), encoding="utf-8"
    )
    (d / "fields.geojson").write_text(
        json.dumps(fc([pt(n, lo, la) for n, lo, la in fields]), ensure_ascii=False),
        encoding="utf-8",
    )
    (d / "prior.csv").write_text(
        "lat,lon,probability\n" + "".join(f"{a},{b},{p}\n" for a, b, p in prior)
    )


# southern / western hemisphere: near Santiago de Chile, 40 x 30 km
write(
    "chile",
    box(-71.0, -33.7, -70.55, -33.43),
    [
        (HOST_Z[0], box(-70.95, -33.60, -70.90, -33.55)),
        (HOST_Z[2], box(-70.70, -33.50, -70.65, -33.46)),
    ],
    [(HOST_F[0], -71.05, -33.75), (HOST_F[1], -70.50, -33.72), (HOST_F[2], -70.80, -33.78)],
    [(-33.55, -70.80, 0.4), (-33.50, -70.75, 0.3), (-33.62, -70.62, 0.3)],
)
# near 60 N (Norway), 60 x 40 km
write(
    "n60",
    box(10.0, 60.0, 11.08, 60.36),
    [(HOST_Z[1], box(10.3, 60.1, 10.4, 60.15)), (HOST_Z[3], box(10.7, 60.25, 10.8, 60.3))],
    [("Gardermoen", 11.10, 60.19), ("Hamar <N>", 10.05, 59.95)],
    [(60.2, 10.5, 0.5), (60.1, 10.9, 0.3), (60.3, 10.2, 0.2)],
)
# the antimeridian: an area just east of it, the airfield west of it (Fiji)
write(
    "fiji",
    box(-179.9, -16.6, -179.5, -16.3),
    [],
    [("Savusavu", 179.34, -16.80)],
    [(-16.45, -179.7, 0.6), (-16.5, -179.6, 0.4)],
)
# terrain DEM (the test's synthetic Alps), and a second field up the ridge flank
spec = importlib.util.spec_from_file_location(
    "tt", "/work/wt/export-audit/tests/mission/test_terrain.py"
)
tt = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tt)
tt._dem(Path("dem.tif"))
