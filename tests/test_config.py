"""Configs and maps: built-ins load, round-trip, and every bad input names what is wrong."""

import numpy as np
import pytest
import yaml

from poc_env.config import CONFIG_DIR, KM, builtin_scenarios, load_scenario, save_scenario
from poc_env.errors import ConfigError, GeometryError, MapFileError
from poc_env.theory.probability_map import Grid, build_prior, load_map, validate_map


def test_builtin_scenarios_match_the_paper():
    assert {"paper_6_1", "paper_6_2", "small"} <= set(builtin_scenarios())
    s61 = load_scenario("paper_6_1")
    assert (s61.map.nx, s61.map.ny, s61.map.cell_m) == (60, 40, 6 * KM)
    assert s61.n_uavs == 6 and len(s61.airfields) == 2
    s62 = load_scenario("paper_6_2")
    assert (s62.map.nx, s62.map.ny, s62.map.cell_m) == (40, 30, 5 * KM)
    assert sorted({a.position_m for a in s62.airfields}) == [
        (20 * KM, -60 * KM),
        (120 * KM, -60 * KM),
    ]
    assert s62.n_uavs == 6
    u = s62.uav
    assert u.endurance_s == pytest.approx(3 * 3600)
    assert u.usable_endurance_s == pytest.approx(0.85 * 3 * 3600)
    assert u.cruise_speed_mps == pytest.approx(220 / 3.6)
    assert u.search_speed_mps == pytest.approx(180 / 3.6)
    assert s62.sensor.sweep_width_m == pytest.approx(5 * KM)


@pytest.mark.parametrize("name", ["paper_6_1", "paper_6_2", "small"])
def test_round_trip_through_yaml(name, tmp_path):
    sc = load_scenario(name)
    path = save_scenario(sc, tmp_path / "resolved.yaml")
    assert load_scenario(str(path)) == sc
    prior = build_prior(sc.map)
    assert prior.shape == (sc.map.ny, sc.map.nx)
    assert prior.sum() == pytest.approx(1.0) and prior.min() > 0


def test_config_objects_are_immutable():
    sc = load_scenario("small")
    with pytest.raises(AttributeError):
        sc.uav.endurance_s = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("key", "value", "field"),
    [
        ("uav.search_speed_kmh", 0, "uav.search_speed_kmh"),
        ("uav.cruise_speed_kmh", -5, "uav.cruise_speed_kmh"),
        ("uav.endurance_h", 0, "uav.endurance_h"),
        ("sensor.sweep_width_km", -1, "sensor.sweep_width_km"),
        ("map.cell_km", 0, "map.cell_km"),
        ("map.width_km", 41, "map.width_km"),
        ("sensor.law", "magic", "sensor.law"),
        ("uav.endurance_h", "three", "uav.endurance_h"),
        ("sensor.colour", "red", "sensor.colour"),
        ("reward.credit", "mine", "reward.credit"),
    ],
)
def test_bad_values_name_field_value_and_allowed(key, value, field):
    with pytest.raises(ConfigError) as info:
        load_scenario("small", {key: value})
    err = info.value
    assert err.field == field
    assert repr(value) in str(err) and "allowed" in str(err)


def test_unknown_top_level_key_and_scenario():
    with pytest.raises(ConfigError, match="one of the keys"):
        load_scenario("small", {"weather": "fine"})
    with pytest.raises(ConfigError, match="built-in name"):
        load_scenario("no_such_scenario")


def test_self_intersecting_no_fly_zone_is_rejected():
    bowtie = [[0, 0], [10, 10], [10, 0], [0, 10]]
    with pytest.raises(GeometryError, match=r"no_fly_zones_km\[0\].*Self-intersection.*allowed"):
        load_scenario("small", {"map.no_fly_zones_km": [bowtie]})
    with pytest.raises(GeometryError, match="zero area"):
        load_scenario("small", {"map.no_fly_zones_km": [[[0, 0], [1, 1], [2, 2]]]})


def test_airfield_inside_no_fly_zone_is_rejected():
    zone = [[15, -10], [25, -10], [25, 0], [15, 0]]  # around small's airfield (20, -5)
    with pytest.raises(ConfigError, match="airfields"):
        load_scenario("small", {"map.no_fly_zones_km": [zone]})


def test_yaml_is_read_safely(tmp_path):
    bad = tmp_path / "evil.yaml"
    bad.write_text("name: !!python/object/apply:os.system ['echo hi']\n")
    with pytest.raises(ConfigError, match="valid YAML"):
        load_scenario(str(bad))
    corrupt = tmp_path / "corrupt.yaml"
    corrupt.write_text("map: [unclosed\n")
    with pytest.raises(ConfigError, match="valid YAML"):
        load_scenario(str(corrupt))


GRID = Grid(4, 3, 1000.0)


@pytest.mark.parametrize(
    ("values", "match"),
    [
        (np.full((3, 4), np.nan), "NaN"),
        (-np.ones((3, 4)), "negative"),
        (np.zeros((3, 4)), "all values are zero"),
        (np.ones((4, 3)), "shape"),
    ],
)
def test_bad_maps(values, match):
    with pytest.raises(MapFileError, match=match):
        validate_map(values, GRID)


def test_unnormalised_map_warns_and_normalises():
    with pytest.warns(UserWarning, match="normalised"):
        out = validate_map(np.ones((3, 4)), GRID)
    assert out.sum() == pytest.approx(1.0)


def test_map_files(tmp_path):
    arr = np.arange(12, dtype=float).reshape(3, 4) + 1
    np.save(tmp_path / "m.npy", arr / arr.sum())
    np.savetxt(tmp_path / "m.csv", arr / arr.sum(), delimiter=",")
    np.testing.assert_allclose(load_map(tmp_path / "m.npy", GRID), arr / arr.sum())
    np.testing.assert_allclose(load_map(tmp_path / "m.csv", GRID), arr / arr.sum())
    with pytest.raises(MapFileError, match="does not exist"):
        load_map(tmp_path / "missing.npy", GRID)
    (tmp_path / "c.npy").write_bytes(b"not a numpy file")
    with pytest.raises(MapFileError, match="corrupt"):
        load_map(tmp_path / "c.npy", GRID)
    np.save(tmp_path / "obj.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(MapFileError, match="corrupt"):
        load_map(tmp_path / "obj.npy", GRID)
    (tmp_path / "m.txt").write_text("1")
    with pytest.raises(MapFileError, match="suffix"):
        load_map(tmp_path / "m.txt", GRID)


def test_overrides_and_with_uavs():
    sc = load_scenario("paper_6_2", {"sensor.sweep_width_km": 4})
    assert sc.sensor.sweep_width_m == pytest.approx(4000)
    s8 = sc.with_uavs(8)
    assert s8.n_uavs == 8 and len(s8.takeoff_m) == 8
    with pytest.raises(ConfigError, match="uavs"):
        sc.with_uavs(0)


def test_resolved_config_is_plain_yaml():
    text = yaml.safe_dump(load_scenario("paper_6_2").to_dict())
    assert "sweep_width_km: 5.0" in text


def test_config_error_survives_pickling():
    """Errors raised in worker processes reach the user with their message intact."""
    import pickle

    err = ConfigError("uav.endurance_h", -1, "a number > 0")
    back = pickle.loads(pickle.dumps(err))
    assert isinstance(back, ConfigError) and str(back) == str(err) and back.field == err.field


@pytest.mark.parametrize(
    "key,value,attr,expected",
    [
        ("uav.endurance_h", np.int64(1), ("uav", "endurance_s"), 3600.0),
        ("uav.endurance_h", np.float32(0.5), ("uav", "endurance_s"), 1800.0),
        ("sensor.sweep_width_km", np.int64(2), ("sensor", "sweep_width_m"), 2000.0),
        ("map.cell_km", np.int64(5), ("map", "cell_m"), 5000.0),
        ("uav.max_speed_kmh", np.float64(250.0), ("uav", "max_speed_mps"), 250 / 3.6),
    ],
)
def test_numpy_scalars_get_the_same_units_as_python_numbers(key, value, attr, expected):
    """A numpy scalar is converted once, like the Python number it holds (np.int64(1) hours
    was once taken as 1 second)."""
    sc = load_scenario("small", overrides={key: value})
    plain = load_scenario("small", overrides={key: value.item()})
    got = getattr(getattr(sc, attr[0]), attr[1])
    assert got == pytest.approx(expected)
    assert got == getattr(getattr(plain, attr[0]), attr[1])


def test_yaml_alias_bomb_is_refused_quickly(tmp_path):
    """A 'billion laughs' document (nine levels of nine aliases, under 1 kB) is refused while
    it is parsed, before anything expands it; a file with a few aliases still loads."""
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    for k in range(1, 10):
        lines.append(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]")
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text("\n".join(lines) + "\n")
    assert bomb.stat().st_size < 1024
    with pytest.raises(ConfigError, match="expands to more than"):
        load_scenario(bomb)
    from poc_env.config import load_yaml_text

    assert load_yaml_text("a: &a [1, 2]\nb: *a\n") == {"a": [1, 2], "b": [1, 2]}
    assert load_scenario("small") == load_scenario(CONFIG_DIR / "small.yaml")


def test_deeply_nested_yaml_is_refused_not_a_recursion_error(tmp_path):
    """Issue 27 item 4: 100,000 nested lists (200 kB, well under the size cap) ended in a
    RecursionError; any nesting past MAX_YAML_DEPTH is a clear error, shallower still loads."""
    from poc_env.config import MAX_YAML_DEPTH, load_yaml_text

    deep = tmp_path / "deep.yaml"
    deep.write_text("name: deep\nmap: " + "[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(ConfigError, match=f"nested more than {MAX_YAML_DEPTH} deep"):
        load_scenario(deep)
    d = MAX_YAML_DEPTH - 1  # inside the top-level mapping: exactly the limit
    nested: list = []
    for _ in range(d - 1):
        nested = [nested]
    assert load_yaml_text("a: " + "[" * d + "]" * d) == {"a": nested}


def test_map_geography_keys():
    from poc_env.config import load_scenario

    sc = load_scenario("small", {"map.origin_deg": [45.7, 126.6], "map.projection": "utm"})
    assert sc.map.origin_deg == (45.7, 126.6) and sc.map.projection == "utm"
    assert load_scenario(sc.to_dict()).map == sc.map  # written and read back
    assert load_scenario("small").map.origin_deg is None
    for bad, field in (
        ({"map.origin_deg": [126.6, 45.7]}, "origin_deg"),  # lon, lat swapped
        ({"map.origin_deg": [45.7, 126.6], "map.projection": "merc"}, "projection"),
        ({"map.projection": "utm"}, "origin_deg"),
        ({"map.origin_deg": [45.7, 126.6], "map.utm_zone": 52}, "utm_zone"),
        (
            {"map.origin_deg": [45.7, 126.6], "map.projection": "utm", "map.utm_zone": 61},
            "utm_zone",
        ),
    ):
        with pytest.raises(ConfigError, match=rf"map\.{field}: got"):
            load_scenario("small", bad)


def test_with_uavs_keeps_the_fleets_own_takeoff_and_landing_pairs() -> None:
    """i24-smallfix, F4: ``--uavs N`` (Scenario.with_uavs) flies the fleet's own pairs: N
    equal to the fleet's size is the fleet, fewer are spread over its groups; the UAVs beyond
    the fleet take off from the airfields in turn (UAV j from airfield j mod 3) and land
    there."""
    sc = load_scenario(
        "paper_6_2",
        {
            "airfields": [
                {"name": "A", "position_km": [20, -60]},
                {"name": "B", "position_km": [120, -60]},
                {"name": "C", "position_km": [220, -60]},
            ],
            "fleet": [
                {"takeoff": "A", "count": 2, "landing": "B"},
                {"takeoff": "B", "count": 1, "landing": "A"},
            ],
        },
    )
    same = sc.with_uavs(sc.n_uavs)
    assert same.fleet == sc.fleet
    assert np.array_equal(same.landing_m, sc.landing_m)
    pairs = {n: [(g.takeoff, g.landing, g.count) for g in sc.with_uavs(n).fleet] for n in (1, 2, 5)}
    assert pairs[1] == [("A", "B", 1)]
    assert pairs[2] == [("A", "B", 1), ("B", "A", 1)]
    assert pairs[5] == [("A", "B", 2), ("B", "A", 1), ("A", "A", 1), ("B", "B", 1)]


def test_with_uavs_spreads_the_built_in_fleets_as_the_size_tasks_do() -> None:
    """The built-in scenarios' fleets spread evenly over their airfields in order and land where
    they took off, so ``with_uavs`` gives them the round-robin fleets the registered size tasks
    fly (:func:`poc_env.spec.fleet_of`)."""
    from poc_env import spec

    for name in ("paper_6_2", "small", "wide_400", "large_400"):
        sc = load_scenario(name)
        fields = [a.name for a in sc.airfields]
        for n in (1, 2, 3, 5, sc.n_uavs, 13, 24):
            want = [(f["takeoff"], f["takeoff"], f["count"]) for f in spec.fleet_of(n, fields)]
            got = [(g.takeoff, g.landing, g.count) for g in sc.with_uavs(n).fleet]
            assert got == want, (name, n)
