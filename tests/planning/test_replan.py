"""`poc-env replan`: eq. 14 along the flights of the sorties so far, then the next sortie."""

import json

import numpy as np
import pytest

from poc_env.agents.mission.crs import to_geographic
from poc_env.agents.mission.plan import load_plan
from poc_env.agents.planning.replan import searched_belief
from poc_env.cli import main
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.theory.probability_map import build_prior


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    d = tmp_path_factory.mktemp("replan")
    out = d / "p1.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--origin", "46.5,7.9"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    return d, out


def _tracks(path, plan, **extra):
    feats = []
    for u in plan["uavs"]:
        pts = [u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]
        coords = [[lon, lat] for lat, lon in to_geographic(pts, plan["crs"])]
        feats.append(
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "LineString", "coordinates": coords},
            }
        )
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats, **extra}))
    return feats


def test_three_sorties_add_up(first, capsys):
    """Sortie 2 starts from the prior less what sortie 1's routes found (eq. 14 on the sample
    points: the same sweep that scored plan 1, so its POS is plan 1's posc); sortie 3 from
    what both left; the cumulative POS grows and stays a probability."""  # issue 24 item 4
    d, p1 = first
    p2, p3 = d / "p2.json", d / "p3.json"
    assert main(["replan", "--scenario", "small", "--plan", str(p1), "--out", str(p2)]) == 0
    assert main(["replan", "--plan", str(p1), "--plan", str(p2), "--out", str(p3)]) == 0
    assert "sortie 3" in capsys.readouterr().out
    a, b, c = (json.loads(p.read_text()) for p in (p1, p2, p3))
    assert b["sortie"] == 2 and c["sortie"] == 3 and b["crs"] == a["crs"]
    assert b["searched_pos"] == pytest.approx(a["posc"], abs=1e-9)
    # sortie 2 was scored on the cells' belief spread evenly over each cell's sample points;
    # the chain keeps the sample points' own belief (sortie 1 left it uneven within cells)
    assert c["searched_pos"] == pytest.approx(a["posc"] + b["posc"], rel=1e-2)
    assert c["searched_pos"] > b["searched_pos"]
    assert a["posc"] < b["cumulative_posc"] < c["cumulative_posc"] <= 1.0
    load_plan(p3)  # a plan export accepts
    sc = load_scenario("small")
    prior = build_prior(sc.map)
    paths = [np.array([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]]) for u in a["uavs"]]
    belief, found = searched_belief(sc, prior, paths)
    assert belief.sum() + found == pytest.approx(prior.sum(), abs=1e-12)
    assert np.all(belief <= prior + 1e-15) and found > 0


def test_flown_tracks_as_geojson_give_the_same_belief(first, tmp_path):
    _, p1 = first
    plan = json.loads(p1.read_text())
    _tracks(tmp_path / "t.geojson", plan)
    out = tmp_path / "next.json"
    argv = ["replan", "--scenario", "small", "--plan", str(p1), "--tracks"]
    assert main([*argv, str(tmp_path / "t.geojson"), "--out", str(out)]) == 0
    # lon/lat and back moves points by rounding; a sample point at the sensor's cut-off distance
    # of a line may then fall on the other side of it
    assert json.loads(out.read_text())["searched_pos"] == pytest.approx(plan["posc"], rel=1e-3)


def test_bad_tracks_name_the_field_and_write_nothing(first, tmp_path, capsys):
    _, p1 = first
    plan = json.loads(p1.read_text())
    out = tmp_path / "next.json"
    argv = ["replan", "--plan", str(p1), "--out", str(out), "--tracks", str(tmp_path / "t.geojson")]
    feats = _tracks(tmp_path / "t.geojson", plan)
    feats[1]["geometry"]["coordinates"][2] = [9.5, 47.5]  # ~100 km off the map
    (tmp_path / "t.geojson").write_text(
        json.dumps({"type": "FeatureCollection", "features": feats})
    )
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "tracks.features[1].geometry.coordinates[2]" in err and "operating area" in err
    _tracks(tmp_path / "t.geojson", plan, crs={"type": "name", "properties": {"name": "EPSG:3857"}})
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "tracks.crs" in err and "EPSG:3857" in err
    assert main(["replan", "--scenario", "paper_6_2", "--plan", str(p1), "--out", str(out)]) == 2
    assert "plan.scenario" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    "text, field",
    [
        ('{"type": "FeatureCollection", "features": ' + "[" * 5000 + "]" * 5000 + "}", "tracks"),
        ('{"type": "FeatureCollection", "crs": "EPSG:4326", "features": []}', "tracks.crs"),
        ('{"type": "FeatureCollection", "crs": {"properties": 3}, "features": []}', "tracks.crs"),
        ('{"type": "FeatureCollection", "crs": {"properties": {"name": []}}}', "tracks.crs"),
        ('{"type": "LineString", "coordinates": [[NaN, 45], [126, 45]]}', "tracks"),
        (
            '{"type": "LineString", "coordinates": [[1' + "0" * 400 + ", 45], [126, 45]]}",
            "tracks.coordinates",
        ),
    ],
)
def test_hostile_tracks_are_a_clear_error_nothing_written(first, tmp_path, text, field):
    """Issue 27's campaign (datafiles target): deep nesting was a RecursionError, a crs member
    that is not an object an AttributeError and an integer beyond float range (seed 74) an
    OverflowError; each names the field now."""
    _, p1 = first
    bad = tmp_path / "flown.geojson"
    bad.write_text(text)
    out = tmp_path / "out" / "p2.json"
    argv = ["replan", "--plan", str(p1), "--tracks", str(bad), "--out", str(out)]
    assert main(argv) == 2
    assert not out.parent.exists() or not any(out.parent.iterdir())
    from poc_env.agents.planning.replan import read_tracks

    with pytest.raises(ConfigError) as err:
        read_tracks(bad, (46.5, 7.9))
    assert err.value.field == field
