"""Vertical separation in the exported missions (i24-layers): ``separation_m`` gives each UAV of
a take-off field (or of the fleet) its own altitude layer in every format, refuses a layer above
the ceiling naming the UAV, keeps the terrain clearance, and changes nothing at 0."""

from __future__ import annotations

import dataclasses
import json
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from poc_env.agents.mission.crs import make_crs
from poc_env.agents.mission.export import export_plan
from poc_env.agents.mission.features import with_layers
from poc_env.agents.mission.formats.qgc import validate_qgc
from poc_env.agents.mission.terrain import clearance_violations, load_terrain, profile
from poc_env.agents.testing.terrain import wall_scenario
from poc_env.cli import main
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

ORIGIN = (45.75, 126.65)
FIELD_A, FIELD_B = [20e3, -60e3], [150e3, -60e3]
KML = {"k": "http://www.opengis.net/kml/2.2"}


def _plan(tmp_path, fields=(FIELD_A, FIELD_A), **changes):
    """A flat plan, one UAV per entry of ``fields`` (its take-off and landing field)."""
    rng = np.random.default_rng(0)
    uavs = []
    for k, f in enumerate(fields):
        uavs.append({
            "id": k + 1, "rectangle": None, "spacing_m": 5e3, "takeoff_m": list(f),
            "landing_m": list(f), "waypoints_m": rng.uniform(0, 150e3, (4, 2)).round(3).tolist(),
            "track_length_m": 300e3, "flight_time_s": 9000.0, "pod": 0.79, "poc": 0.2,
            "pos": 0.158, "feasible": True,
        })  # fmt: skip
    plan = {
        "schema": 2, "scenario": "paper_6_2", "seed": 1, "map_source": "builtin",
        "optimizer": {"name": "adaptive_de", "settings": {}}, "runtime_s": 0.4, "posc": 0.3,
        "upper_bound": 0.5, "uavs": uavs, "crs": make_crs("aeqd", ORIGIN),
        "flight": {"altitude_m": 1200.0, "max_altitude_m": 4000.0},
    }  # fmt: skip
    plan.update(changes)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path


def _qgc_alts(files):
    """Per mission: (take-off altitude, waypoint altitudes, approach altitude, land altitude)."""
    out = []
    for f in files:
        doc = json.loads(f.read_text())
        assert validate_qgc(doc) == []
        nav = [i for i in doc["mission"]["items"] if i["command"] in (16, 21, 22)]
        assert all(i["params"][6] == i["Altitude"] for i in nav)
        out.append((nav[0]["Altitude"], [i["Altitude"] for i in nav[1:-2]], *[
            i["Altitude"] for i in nav[-2:]]))  # fmt: skip
    return out


def test_two_uavs_of_one_field_fly_layers_s_apart_in_every_format(tmp_path):
    path = _plan(tmp_path)
    s = 50.0
    (q0, q1) = _qgc_alts(export_plan(path, "qgc", out_dir=tmp_path / "q", separation_m=s))
    assert q0[0] == 1200.0 and q1[0] == 1200.0 + s  # the take-off climbs to the layer
    assert q0[1] == [1200.0] * 4 and q1[1] == [1200.0 + s] * 4  # every waypoint
    assert q0[2:] == q1[2:] == (300.0, 0.0)  # the approach and landing: the plan's
    (gj,) = export_plan(path, "geojson", out_dir=tmp_path / "g", separation_m=s)
    doc = json.loads(gj.read_text())
    routes = [f for f in doc["features"] if f["properties"]["kind"] == "route"]
    zs = [[c[2] for c in r["geometry"]["coordinates"]] for r in routes]
    assert zs[0] == [0.0, *[1200.0] * 4, 0.0] and zs[1] == [0.0, *[1200.0 + s] * 4, 0.0]
    assert [r["properties"]["layer_m"] for r in routes] == [0.0, s]
    assert [r["properties"]["altitude_m"] for r in routes] == [1200.0, 1200.0 + s]
    assert doc["properties"]["altitude_layers"] == {"separation_m": s, "layer_by": "field"}
    kml = export_plan(path, "kml", out_dir=tmp_path / "k", separation_m=s)
    km = next(f for f in kml if f.suffix == ".kml")  # and the prior's PNG
    root = ET.parse(km).getroot()
    lines = [
        pm.find(".//k:coordinates", KML).text
        for pm in root.iterfind(".//k:Placemark", KML)
        if pm.find("k:name", KML).text.endswith("route")
    ]
    assert [[float(c.split(",")[2]) for c in t.split()] for t in lines] == zs
    assert "50 m apart" in root.find("k:Document/k:description", KML).text
    (page,) = export_plan(path, "html", out_dir=tmp_path / "h", separation_m=s)
    text = page.read_text()
    table = text[text.index('<table id="uav-table"') : text.index("</table>")]
    cells = re.findall(r"<td>([^<]*\(home[^<]*)</td>", table)
    assert cells == ["1200 (home, layer +0 m)", "1250 (home, layer +50 m)"]


def test_layers_are_counted_per_take_off_field_or_over_the_fleet(tmp_path):
    """Field-mates share take-off and homeward legs (results/mission/i24-layers: 124 of the 125
    flown conflict pair-steps between routed UAVs); ``fleet`` separates every pair."""
    path = _plan(tmp_path, fields=(FIELD_A, FIELD_B, FIELD_A))
    plan = json.loads(path.read_text())
    assert [u["layer_m"] for u in with_layers(plan, 40.0)["uavs"]] == [0.0, 0.0, 40.0]
    fleet = with_layers(plan, 40.0, "fleet")["uavs"]
    assert [u["layer_m"] for u in fleet] == [0.0, 40.0, 80.0]
    idle = {**plan["uavs"][0], "waypoints_m": []}  # not exported: it takes no layer
    layered = with_layers({**plan, "uavs": [idle, *plan["uavs"]]}, 40.0)["uavs"]
    assert "layer_m" not in layered[0]
    assert [u["layer_m"] for u in layered[1:]] == [0.0, 0.0, 40.0]
    (gj,) = export_plan(path, "geojson", out_dir=tmp_path / "g", separation_m=40.0,
                        layer_by="fleet")  # fmt: skip
    routes = [
        f for f in json.loads(gj.read_text())["features"] if f["properties"]["kind"] == "route"
    ]
    assert [r["properties"]["altitude_m"] for r in routes] == [1200.0, 1240.0, 1280.0]
    with pytest.raises(ConfigError, match=r"^layer_by: got 'runway'; allowed: one of field, fleet"):
        export_plan(path, "qgc", out_dir=tmp_path / "x", separation_m=40.0, layer_by="runway")
    with pytest.raises(ConfigError, match=r"^separation_m"):
        export_plan(path, "qgc", out_dir=tmp_path / "x", separation_m=-5.0)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("fmt", ["qgc", "geojson"])
def test_a_layer_above_the_ceiling_is_refused_naming_the_uav(tmp_path, fmt):
    path = _plan(tmp_path, fields=(FIELD_A, FIELD_B, FIELD_A))
    out = tmp_path / "o"
    with pytest.raises(
        ConfigError, match=r"^plan\.uavs\[2\] \(UAV 3\): got .*altitude 4300 m .*ceiling .*4000 m"
    ):
        export_plan(path, fmt, out_dir=out, separation_m=900.0, altitude_m=3400.0)
    assert not out.exists()  # nothing written
    export_plan(path, fmt, out_dir=out, separation_m=600.0, altitude_m=3400.0)  # 4000: at it


def test_cli_records_the_separation(tmp_path, capsys):
    path = _plan(tmp_path)
    assert main(["export", str(path), "--format", "qgc", "--separation-m", "30"]) == 0
    alts = _qgc_alts(sorted(tmp_path.glob("plan_uav*.plan")))
    assert [a[0] for a in alts] == [1200.0, 1230.0]


def test_zero_separation_changes_no_byte(tmp_path):
    """``separation_m=0`` writes what an export without it writes, with no layer anywhere
    (results/mission/i24-layers: the same bytes as main's export, sha256, every format)."""
    path = _plan(tmp_path, fields=(FIELD_A, FIELD_B, FIELD_A))
    for fmt in ("qgc", "geojson", "kml", "html"):
        plain = export_plan(path, fmt, out_dir=tmp_path / fmt / "plain")
        zero = export_plan(path, fmt, out_dir=tmp_path / fmt / "zero", separation_m=0.0)
        for a, b in zip(plain, zero, strict=True):
            assert a.read_bytes() == b.read_bytes()
            assert not re.search(
                rb"layer \+|layer_m|altitude_layers|Altitude layers", a.read_bytes()
            )


def test_layers_carried_by_a_plan_file_are_not_flown(tmp_path):
    """``layer_m`` and ``altitude_layers`` are an export's own: a plan.json carrying them (a
    hand edit, or a plan exported in memory and saved) exports as the plan without them, and
    ``separation_m`` alone decides the layers."""
    (tmp_path / "a").mkdir()
    plain = _plan(tmp_path / "a")
    doc = json.loads(plain.read_text())
    for u in doc["uavs"]:
        u["layer_m"] = 1e6
    doc["altitude_layers"] = {"separation_m": 1e6, "layer_by": "fleet"}
    (tmp_path / "b").mkdir()
    stale = tmp_path / "b" / "plan.json"
    stale.write_text(json.dumps(doc))
    for fmt in ("qgc", "geojson", "kml", "html"):
        a = export_plan(plain, fmt, out_dir=tmp_path / fmt / "plain")
        b = export_plan(stale, fmt, out_dir=tmp_path / fmt / "stale")
        for x, y in zip(a, b, strict=True):
            assert x.read_bytes() == y.read_bytes(), (fmt, x.name)
    layered = with_layers(doc, 50.0, "field")
    assert [u["layer_m"] for u in layered["uavs"]] == [0.0, 50.0]
    assert layered["altitude_layers"] == {"separation_m": 50.0, "layer_by": "field"}


# --------------------------------------------------------------------------- terrain


def _wall_terrain():
    """A 600 m valley with a 4,000 m north-south wall at x = 30 km."""
    sc = load_scenario(wall_scenario())
    return sc, load_terrain(sc)


def test_terrain_layers_stack_on_the_clearance_within_the_ceiling():
    sc, t = _wall_terrain()
    over = [[-10e3, 20e3], [27e3, 0.0], [33e3, 0.0], [33e3, 2e3], [26e3, 2e3], [0.0, 18e3]]
    base = profile(t, over, "UAV 1", [-10e3, 20e3])
    lay = profile(t, over, "UAV 2", [-10e3, 20e3], layer_m=300.0)
    assert clearance_violations(t, lay, step_m=50.0) == 0  # never below the clearance
    grad = np.abs(np.diff(lay.amsl_m)) / np.hypot(*np.diff(lay.points_m, axis=0).T)
    assert grad.max() <= np.tan(sc.uav.max_pitch_rad) + 1e-9  # eq. 19 kept
    assert lay.amsl_m[0] == base.amsl_m[0] + 300.0 == 600.0 + sc.uav.cruise_altitude_m + 300.0
    assert lay.amsl_m.max() == pytest.approx(base.amsl_m.max() + 300.0)  # over the wall too
    assert lay.amsl_m[-1] == base.amsl_m[-1]  # the approach: the landing glide's
    low = dataclasses.replace(t, ceiling_m=4000.0 + t.min_clearance_m + 200.0)
    with pytest.raises(
        ConfigError, match=r"^UAV 2: got .*altitude \d+ m AMSL.*layer 300 m.*ceiling"
    ):
        profile(low, over, "UAV 2", [-10e3, 20e3], layer_m=300.0)
    profile(low, over, "UAV 1", [-10e3, 20e3])  # without the layer: within it


def test_terrain_export_gives_field_mates_layers(tmp_path):
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan

    sc, _ = _wall_terrain()
    plan = make_plan(sc, planner="allocation", refine=0)
    assert sum(bool(u["waypoints_m"]) for u in plan["uavs"]) == 2
    write_plan(plan, tmp_path / "plan.json")
    s = 80.0
    files = export_plan(tmp_path / "plan.json", "qgc", out_dir=tmp_path / "q", separation_m=s)
    (a, b) = _qgc_alts(files)
    assert b[0] == pytest.approx(a[0] + s)  # take-off climb targets over the one field
    assert a[3] == b[3]  # one field, one landing elevation


def test_terrain_ceiling_refusal_adds_up():
    """The refusal's figures add up (i24-dayaudit: it read "altitude 5152 m AMSL (layer 2000 m
    over ground 2152 m)", leaving out the 1000 m over the ground the plan flies there)."""
    _, t = _wall_terrain()
    low = dataclasses.replace(t, ceiling_m=4000.0 + t.min_clearance_m + 200.0)
    over = [[-10e3, 20e3], [27e3, 0.0], [33e3, 0.0], [0.0, 18e3]]
    with pytest.raises(ConfigError) as e:
        profile(low, over, "UAV 2", [-10e3, 20e3], layer_m=300.0)
    m = re.search(
        r"altitude (\d+) m AMSL .*\((\d+) m: (\d+) m over ground (\d+) m, \+ layer (\d+) m\)",
        str(e.value),
    )
    assert m, str(e.value)
    alt, plan, above, ground, layer = map(int, m.groups())
    assert layer == 300 and plan + layer == alt and abs(above + ground - plan) <= 1


def test_cli_layer_by_without_a_separation_is_refused(tmp_path, capsys):
    """``--layer-by fleet`` alone wrote every UAV at one altitude without a word (i24-dayaudit):
    refused naming the option, nothing written; with ``--separation-m`` it layers."""
    path = _plan(tmp_path)
    out = tmp_path / "o"
    args = ["export", str(path), "--format", "qgc", "--out", str(out), "--layer-by", "fleet"]
    assert main(args) == 2
    assert "layer_by: got 'fleet'" in capsys.readouterr().err
    assert not out.exists()
    assert main([*args, "--separation-m", "30"]) == 0
    assert [a[0] for a in _qgc_alts(sorted(out.glob("plan_uav*.plan")))] == [1200.0, 1230.0]


def test_a_separation_below_a_metre_is_refused(tmp_path, capsys):
    """``--separation-m 1e-9`` wrote ``altitude_layers`` with every ``layer_m`` 0.0
    (i24-dayaudit, i24-smallfix): refused naming the field and value, nothing written; 1 m
    (:data:`~poc_env.agents.mission.features.MIN_SEPARATION_M`) layers."""
    path = _plan(tmp_path)
    out = tmp_path / "o"
    args = ["export", str(path), "--format", "geojson", "--out", str(out), "--separation-m"]
    assert main([*args, "1e-9"]) == 2
    err = capsys.readouterr().err
    assert "separation_m: got 1e-09; allowed: 0 (no layers) or 1 to 1000 m" in err
    assert not out.exists()
    with pytest.raises(ConfigError, match=r"^separation_m: got 0\.5"):
        export_plan(path, "qgc", out_dir=tmp_path / "x", separation_m=0.5)
    assert not (tmp_path / "x").exists()
    assert main([*args, "1"]) == 0
