"""The audit's input layers (results/audit/sar/README.md): ``python layers.py DIR`` writes every
GeoJSON/KML/CSV file the probes in ``probes.sh`` read into DIR."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np


def box(lon0: float, lat0: float, lon1: float, lat1: float) -> list[list[float]]:
    """A closed lon/lat rectangle ring."""
    return [[lon0, lat0], [lon1, lat0], [lon1, lat1], [lon0, lat1], [lon0, lat0]]


def fc(features: list) -> dict:
    return {"type": "FeatureCollection", "features": features}


def feat(geometry: dict | None, name: str | None = None) -> dict:
    props = {"name": name} if name is not None else {}
    return {"type": "Feature", "properties": props, "geometry": geometry}


def poly(ring: list) -> dict:
    return {"type": "Polygon", "coordinates": [ring]}


def point(lon: float, lat: float) -> dict:
    return {"type": "Point", "coordinates": [lon, lat]}


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)

    def w(name: str, obj: dict) -> None:
        (out / name).write_text(json.dumps(obj), encoding="utf-8")

    # CSV priors over a small Swiss area
    w("ch_area.geojson", fc([feat(poly(box(7.9, 46.5, 8.3, 46.8)), "a")]))
    w("ch_field.geojson", fc([feat(point(7.85, 46.6), "f")]))
    rows = "lat,lon,probability\n46.6,8.0,0.5\n46.7,8.2,0.5\n"
    (out / "bom.csv").write_text(rows, encoding="utf-8-sig")
    (out / "semi.csv").write_text("lat;lon;probability\n46,6;8,0;0,5\n")
    (out / "zero.csv").write_text("lat,lon,probability\n46.6,8.0,0\n46.7,8.2,0\n")
    (out / "crlf.csv").write_text(rows.replace("\n", "\r\n"), newline="")
    (out / "quoted.csv").write_text('"lat","lon","probability"\n"46.6","8.0","0.5"\n')
    (out / "upper.csv").write_text("Latitude,Longitude,Probability\n46.6,8.0,0.5\n")
    # other hemispheres, the antimeridian, a pole, GeoJSON shapes
    nz = box(170.0, -44.0, 170.6, -43.6)
    w("nz_area.geojson", fc([feat(poly(nz), "nz")]))
    w("nz_field.geojson", fc([feat(point(169.9, -43.8), "Wanaka")]))
    w("fj_area.geojson", fc([feat(poly(box(179.4, -17.0, 179.95, -16.6)), "fj")]))
    w("fj_field.geojson", fc([feat(point(179.3, -16.8), "west")]))
    w("fj_field_w.geojson", fc([feat(point(-179.9, -16.8), "east")]))
    am = [[179.6, -17.0], [-179.7, -17.0], [-179.7, -16.6], [179.6, -16.6], [179.6, -17.0]]
    w("am_area.geojson", fc([feat(poly(am), "am")]))
    w("po_area.geojson", fc([feat(poly(box(10.0, 85.0, 30.0, 85.5)), "po")]))
    w("po_field.geojson", fc([feat(point(20.0, 84.9), "ice")]))
    w("bare_area.geojson", poly(nz))
    w("mp_area.geojson", fc([feat({"type": "MultiPolygon", "coordinates": [[nz]]}, "mp")]))
    w("feat_area.geojson", feat(poly(nz), "f"))
    w("bare_field.geojson", point(169.9, -43.8))
    # no-fly zones over the NZ area
    w("z_touch.geojson", fc([feat(poly(box(170.5, -43.9, 170.7, -43.7)), "touch E")]))
    w("z_overlap.geojson", fc([feat(poly(box(170.2, -43.9, 170.35, -43.7)), "A"),
                               feat(poly(box(170.3, -43.85, 170.45, -43.65)), "B")]))  # fmt: skip
    w("z_between.geojson", fc([feat(poly(box(169.93, -43.95, 169.97, -43.65)), "wall")]))
    rng = np.random.default_rng(1)
    many = []
    for i in range(40):
        lo, la = rng.uniform(170.02, 170.55), rng.uniform(-43.98, -43.63)
        many.append(feat(poly(box(lo, la, lo + 0.01, la + 0.008)), f"z{i}"))
    w("z_many.geojson", fc(many))
    w("z_field.geojson", fc([feat(poly(box(169.88, -43.82, 169.92, -43.78)), "on field")]))
    w("z_whole.geojson", fc([feat(poly(box(169.99, -44.01, 170.61, -43.59)), "whole")]))
    hole = {
        "type": "Polygon",
        "coordinates": [box(170.2, -43.9, 170.4, -43.7), box(170.25, -43.85, 170.3, -43.8)],
    }
    w("z_hole.geojson", fc([feat(hole, "hole")]))  # fmt: skip
    bow = [[170.2, -43.9], [170.4, -43.7], [170.4, -43.9], [170.2, -43.7], [170.2, -43.9]]
    w("z_bowtie.geojson", fc([feat(poly(bow), "bow")]))
    w("z_empty.geojson", fc([feat({"type": "Polygon", "coordinates": []}, "empty")]))
    w("z_emptyfc.geojson", fc([]))
    w("z_nullgeom.geojson", fc([feat(None, "n")]))
    same = poly(box(170.2, -43.9, 170.3, -43.8))
    w("z_dup.geojson", fc([feat(same, "same"), feat(same, "same")]))
    w("z_far.geojson", fc([feat(poly(box(175.2, -43.9, 175.3, -43.8)), "far")]))
    w("z_long_name.geojson", fc([feat(same, 'Zone <b>"R&D"</b> ü 🚁 ' + "x" * 300)]))
    w("z_ctl.geojson", fc([feat(same, "bell\x07zone")]))
    w("f_long.geojson", fc([feat(point(169.9, -43.8), "Wanaka " + "a" * 70)]))
    w("f_ctl.geojson", fc([feat(point(169.9, -43.8), "Wan\x07aka")]))
    w(
        "z_uni.geojson",
        fc([feat(same, 'Zone <b>"R&D"</b> </script><script>alert(1)</script> ü 🚁 \' end')]),
    )
    w("f_uni.geojson", fc([feat(point(169.9, -43.8), 'W<i>an</i>&aka "x" 🛩')]))
    # a circular zone digitised with 64, 360 and 2,000 vertices
    for n in (64, 360, 2000):
        t = np.linspace(0, 2 * np.pi, n, endpoint=False)
        lon = 170.3 + 0.08 * np.cos(t) / np.cos(np.radians(43.8))
        lat = -43.8 + 0.08 * np.sin(t)
        ring = [[float(a), float(b)] for a, b in zip(lon, lat)]
        w(f"circle{n}.geojson", fc([feat(poly([*ring, ring[0]]), f"CTR {n}")]))
    # tiny, thin, far
    w("tiny_area.geojson", fc([feat(poly(box(170.0, -44.0, 170.02, -43.99)), "tiny")]))
    w("tiny_field.geojson", fc([feat(point(169.99, -43.995), "near")]))
    w("far_field.geojson", fc([feat(point(167.0, -44.0), "far")]))
    w("thin_area.geojson", fc([feat(poly(box(170.0, -44.0, 170.6, -43.999)), "thin")]))
    # KML: a Folder and a MultiGeometry; a LineString placemark among airfields
    ring = " ".join(f"{lon},{lat},0" for lon, lat in nz)
    kml = ('<?xml version="1.0" encoding="UTF-8"?><kml xmlns="http://www.opengis.net/kml/2.2">'
           "<Document><Folder>{}</Folder></Document></kml>")  # fmt: skip
    (out / "area.kml").write_text(kml.format(
        "<Placemark><name>area</name><MultiGeometry><Polygon><outerBoundaryIs><LinearRing>"
        f"<coordinates>{ring}</coordinates></LinearRing></outerBoundaryIs></Polygon>"
        "</MultiGeometry></Placemark>"))  # fmt: skip
    field = ("<Placemark><name>Wanaka</name><Point><coordinates>169.9,-43.8,0</coordinates>"
             "</Point></Placemark>")  # fmt: skip
    line = ("<Placemark><name>Track</name><LineString><coordinates>169.9,-43.8 170.1,-43.7"
            "</coordinates></LineString></Placemark>")  # fmt: skip
    (out / "fields.kml").write_text(kml.format(field))
    (out / "fields_line.kml").write_text(kml.format(field + line))
    # the largest area: ~500 x 500 km near 45 N, 3 airfields, 4 zones, sightings by the edge
    w("big_area.geojson", fc([feat(poly(box(5.0, 43.0, 11.14, 47.5)), "big")]))
    w("big_fields.geojson", fc([feat(point(4.8, 45.0), "W"), feat(point(8.0, 42.8), "S"),
                                feat(point(11.3, 46.0), "E")]))  # fmt: skip
    w("big_zones.geojson", fc([feat(poly(box(6.0, 44.0, 6.5, 44.4)), "Z1"),
                               feat(poly(box(8.0, 45.5, 9.5, 45.8)), "Z2 long"),
                               feat(poly(box(10.0, 46.5, 10.3, 47.0)), "Z3"),
                               feat(poly(box(7.0, 46.8, 7.4, 47.1)), "Z4")]))  # fmt: skip
    rng = np.random.default_rng(5)
    lines = ["lat,lon,probability"]
    for _ in range(300):
        la, lo, pr = rng.uniform(43.2, 47.3), rng.uniform(5.2, 10.9), rng.uniform(0.1, 1)
        lines.append(f"{la:.5f},{lo:.5f},{pr:.4f}")
    lines += [f"43.02,{lon:.4f},1.0" for lon in np.linspace(7.0, 9.0, 21)]  # 2.2 km inside
    (out / "big_prior.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "."))
