"""The one validation layer: coercion, documented ranges, the memory guard, maps and region
files (issue 15 items 5, 6, 8, 12 and 13). Each case is a reproducer from the issue."""

from __future__ import annotations

import copy
import warnings

import numpy as np
import pytest
import yaml

import poc_env
import poc_env.limits as limits
from poc_env.config import load_scenario
from poc_env.errors import ConfigError, GeometryError, MapFileError, as_bool, as_int, as_number
from poc_env.theory.probability_map import Grid, build_prior, load_map, validate_map

# --------------------------------------------------------------------------- the coercion


@pytest.mark.parametrize(
    ("value", "expected"),
    [(3, 3.0), (2.5, 2.5), (np.int64(3), 3.0), (np.float32(0.5), 0.5), (np.array(7), 7.0)],
)
def test_as_number_accepts_real_numbers_and_numpy_scalars(value, expected):
    out = as_number("x", value)
    assert out == expected and type(out) is float


@pytest.mark.parametrize(
    ("value", "hint"),
    [
        ("5", "without quotes"),
        (True, "true/false"),
        (None, "null"),
        (2 + 0j, "complex"),
        ([1], "list"),
        (float("nan"), "finite"),
        (float("inf"), "finite"),
        (10**400, "number"),
    ],
)
def test_as_number_refuses_with_field_value_and_allowed(value, hint):
    with pytest.raises(ConfigError, match=rf"^x: got .*; allowed: .*{hint}") as err:
        as_number("x", value)
    assert err.value.field == "x"


@pytest.mark.parametrize(("value", "expected"), [(3, 3), (3.0, 3), (np.int64(3), 3)])
def test_as_int_accepts_integral_values(value, expected):
    out = as_int("n", value, 0, 10)
    assert out == expected and type(out) is int


@pytest.mark.parametrize("value", [3.5, float("nan"), float("inf"), "3", True, 11, -1, 10**30])
def test_as_int_refuses(value):
    with pytest.raises(ConfigError, match=r"^n: got .*; allowed: an integer in \[0, 10\]"):
        as_int("n", value, 0, 10)


@pytest.mark.parametrize("value", ["no", "false", 0, 1, None])
def test_as_bool_refuses_everything_but_a_flag(value):
    with pytest.raises(ConfigError, match="allowed: true or false"):
        as_bool("flag", value)
    assert as_bool("flag", np.bool_(True)) is True


# --------------------------------------------------------------------------- scenario fields


@pytest.mark.parametrize(
    ("key", "value", "field"),
    [
        ("reward.alpha", "5", "reward.alpha"),  # quoted number
        ("reward.crash_penalty", 10**30, "reward.crash_penalty"),  # beyond a C integer
        ("sensor.samples_per_cell", float("nan"), "sensor.samples_per_cell"),
        ("sensor.samples_per_cell", 2.5, "sensor.samples_per_cell"),
        ("episode.horizon_steps", float("inf"), "episode.horizon_steps"),
        ("episode.detection_ends_episode", "no", "episode.detection_ends_episode"),
        ("map.width_km", 1e30, "map.width_km"),
        ("map.cell_km", 1e-300, "map.cell_km"),
        ("uav.max_speed_kmh", 1e308, "uav.max_speed_kmh"),
        ("episode.dt_s", 1e308, "episode.dt_s"),
        ("map.origin_km", ["1", 2], "map.origin_km"),
        ("name", 5, "name"),
        ("uav.endurance_h", 5e-324, "uav.endurance_h"),  # found by the campaign: inf reward
    ],
)
def test_bad_scenario_values_name_the_field(key, value, field):
    with pytest.raises(ConfigError) as err:
        load_scenario("small", {key: value})
    assert err.value.field == field
    assert "allowed:" in str(err.value)


def test_nan_rotation_is_refused_not_a_uniform_map():
    comp = {"mean_km": [10, 10], "sigma_km": [5, 5], "rotation_deg": float("nan")}
    with pytest.raises(ConfigError, match=r"components\[0\]\.rotation_deg"):
        load_scenario("small", {"map.prior.components": [comp]})


def test_integral_floats_become_ints_that_the_env_steps_with():
    sc = load_scenario(
        "small", {"sensor.samples_per_cell": 2.0, "fleet": [{"takeoff": "A", "count": 3.0}]}
    )
    assert type(sc.sensor.samples_per_cell) is int and sc.sensor.samples_per_cell == 2
    assert type(sc.fleet[0].count) is int
    env = poc_env.parallel_env(sc)
    env.reset(seed=0)
    _, rew, *_ = env.step({a: env.action_space(a).sample() for a in env.agents})
    assert all(np.isfinite(list(rew.values())))


def test_huge_weights_keep_their_mixture():
    # two equal components of weight 1e308: the sum of weights overflows unless scaled first
    comps = [
        {"mean_km": [10, 10], "sigma_km": [4, 4], "weight": 1e308},
        {"mean_km": [30, 30], "sigma_km": [4, 4], "weight": 1e308},
    ]
    sc = load_scenario("small", {"map.prior.components": comps, "map.prior.background": 0.0})
    prior = build_prior(sc.map)
    g = Grid.from_config(sc.map)
    j, i = g.cell_of(np.array([[10e3, 10e3], [30e3, 30e3]]))
    assert abs(prior.sum() - 1) < 1e-12
    assert prior[j[0], i[0]] == pytest.approx(prior[j[1], i[1]], rel=1e-6)
    assert prior.max() > 5 / prior.size  # peaked, not uniform


def test_too_many_steps_is_refused():
    with pytest.raises(ConfigError, match=r"episode\.dt_s"):
        load_scenario("paper_6_2", {"episode.dt_s": 1e-4})


# --------------------------------------------------------------------------- the memory guard


def test_memory_guard_refuses_a_huge_map_and_a_flag_raises_the_limit(monkeypatch):
    monkeypatch.delenv("POC_ENV_MAX_MEMORY_GB", raising=False)
    big = {"map.width_km": 2000, "map.height_km": 2000, "map.cell_km": 1}  # 4 million cells
    with pytest.raises(ConfigError, match=r"map\.cell_km.*GiB.*--max-memory-gb") as err:
        load_scenario("small", big)
    assert err.value.field == "map.cell_km" and err.value.value == 1
    assert str(err.value).startswith("map.cell_km: got 1;")
    limits.set_memory_limit_gb(64)
    try:
        assert load_scenario("small", big).map.nx == 2000  # only the check: nothing allocated
    finally:
        limits.set_memory_limit_gb(None)


def test_memory_guard_on_env_batches_and_populations(monkeypatch):
    from poc_env.agents.planning.planner import make_plan
    from poc_env.envs.vector import SwarmVecEnv

    monkeypatch.setenv("POC_ENV_MAX_MEMORY_GB", "0.01")  # 10 MiB
    with pytest.raises(ConfigError, match=r"^n_envs"):
        SwarmVecEnv("small", n_envs=1000, obs_type="flat").reset()
    with pytest.raises(ConfigError, match=r"^popsize"):
        make_plan("small", popsize=10_000, maxiter=1)


def test_planner_settings_are_checked_not_defaulted():
    from poc_env.agents.planning.planner import make_plan

    for bad in (0, -1, 3.5, "100", 10**12):
        with pytest.raises(ConfigError, match=r"^popsize"):
            make_plan("small", popsize=bad, maxiter=1)


@pytest.mark.parametrize(
    ("cells", "n_envs", "comms", "uavs"),
    [
        (10_000, 1, False, 3),
        (40_000, 4, False, 3),
        (10_000, 2, True, 3),
        (10_000, 1, False, 24),
        # comms beliefs keep N x N fine maps per env (State.known): at 12 UAVs the estimate of
        # N maps was a third of the peak, so the guard let through sizes the kernel then killed
        (2_500, 1, True, 12),
        (2_500, 2, True, 24),
    ],
)
def test_memory_estimate_is_an_upper_bound(cells, n_envs, comms, uavs):
    import tracemalloc

    from poc_env.envs.vector import SwarmVecEnv

    side = int(np.sqrt(cells)) * 0.5
    sc = load_scenario(
        "small",
        {
            "map.width_km": side,
            "map.height_km": side,
            "map.cell_km": 0.5,
            "comms.belief_sharing": "comms" if comms else "global",
            "comms.range_km": 1000,  # one connected swarm: every UAV copies every other's map
        },
    ).with_uavs(uavs)
    tracemalloc.start()
    try:
        env = SwarmVecEnv(sc, n_envs=n_envs, obs_type="flat")
        for _ in range(2):  # a second reset builds a new state while the old one is held
            env.reset()
            env.step(np.zeros((env.num_envs, 3), np.float32))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    est = limits.env_bytes(cells, sc.sensor.samples_per_cell, sc.n_uavs, n_envs, comms)
    assert sc.n_uavs == uavs
    assert peak <= est, f"peak {peak / 2**20:.1f} MiB, estimate {est / 2**20:.1f} MiB"


@pytest.mark.parametrize(
    ("name", "over", "uavs", "popsize"),
    [
        # many members on a small map: DE/rand/1 draws its (P, P) keys, quadratic in P
        ("small", {}, 3, 2000),
        # the issue-24 size: 160 x 160 cells, 24 UAVs; the compiled plan pass keeps no
        # (P, n, cells) array, so the old 48 B a member, UAV and cell was 86 times the peak
        ("large_400", {"map.cell_km": 2.5}, 24, 100),
    ],
)
def test_planner_population_estimate_is_an_upper_bound_and_not_far_over(name, over, uavs, popsize):
    """``limits.plan_bytes`` (scale-audit): at least the DE plan's measured peak, and within
    ten times it, so that the guard neither lets a 2.3 GB population (popsize 10,000 on
    ``small``, estimated 88 MiB) through nor refuses a 70 MB plan (64 UAVs on 160 x 160 cells,
    estimated 7.4 GiB)."""
    import tracemalloc

    from poc_env.agents.planning.planner import make_plan

    sc = load_scenario(name, over)
    cells = sc.map.nx * sc.map.ny
    est = limits.plan_bytes(popsize, uavs, cells)
    tracemalloc.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a one-generation plan may be infeasible
            make_plan(sc, uavs=uavs, popsize=popsize, maxiter=1)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= est <= 10 * peak, f"peak {peak / 2**20:.1f} MiB, estimate {est / 2**20:.1f} MiB"


# --------------------------------------------------------------------------- maps


@pytest.fixture()
def grid():
    return Grid.from_config(load_scenario("small").map)


def test_huge_finite_map_values_are_normalised_not_zeroed(grid):
    a = np.zeros(grid.shape)
    a[0, 0] = a[1, 1] = 1e308
    with pytest.warns(UserWarning, match="normalised"):
        m = validate_map(a, grid)
    assert m[0, 0] == m[1, 1] == 0.5 and m.sum() == 1.0


def test_a_map_near_one_is_renormalised(grid):
    a = np.full(grid.shape, (1 + 5e-7) / grid.nx / grid.ny)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # within 1e-6: no warning, but divided
        m = validate_map(a, grid)
    assert abs(m.sum() - 1.0) < 1e-12


def test_complex_maps_are_refused(grid):
    with pytest.raises(MapFileError, match=r"complex.*allowed:"):
        validate_map(np.ones(grid.shape, complex), grid)


def test_map_file_errors_say_what_is_allowed(grid, tmp_path):
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"\x93NUMPY garbage")
    huge = tmp_path / "huge.npy"
    m = np.lib.format.open_memmap(huge, mode="w+", dtype=np.float64, shape=(20000, 20000))
    del m  # a sparse 3.2 GB file: its shape is refused before its data are read
    npz = tmp_path / "archive.npy"  # an np.savez archive under a .npy name
    with npz.open("wb") as f:
        np.savez(f, prior=np.ones(grid.shape))
    cases = [
        (tmp_path, "is a folder"),
        ("/dev/null", "not a regular file"),
        (tmp_path / "none.npy", "does not exist"),
        (bad, "corrupt"),
        (huge, r"shape \(20000, 20000\)"),
        (npz, r"\.npz archive"),  # np.load reads it by content: was an AttributeError
    ]
    for path, match in cases:
        with pytest.raises(MapFileError, match=match) as err:
            load_map(path, grid)
        assert "allowed:" in str(err.value)


# --------------------------------------------------------------------------- region files

_REGIONS = {
    "name": "t",
    "scenario": "paper_6_1",
    "regions": [
        {
            "id": 1,
            "kind": "polygon",
            "airfield": "A",
            "spacing_km": 12,
            "vertices_km": [[0, 0], [100, 0], [100, 100], [0, 100]],
        }
    ],
}


def _regions(tmp_path, **change):
    from poc_env.agents.planning.survey import load_regions

    d = copy.deepcopy(_REGIONS)
    d["regions"][0].update(change)
    path = tmp_path / "r.yaml"
    path.write_text(yaml.safe_dump(d))
    return load_regions(path)


@pytest.mark.parametrize(
    ("change", "error", "match"),
    [
        ({"id": None}, ConfigError, r"regions\[0\]\.id: got None"),
        ({"id": "3"}, ConfigError, r"regions\[0\]\.id: got '3'"),
        ({"spacing_km": 10**400}, ConfigError, r"regions\[0\]\.spacing_km"),
        ({"spacing_km": 1e-9}, ConfigError, r"spacing_km.*at most 10000 lines"),
        ({"second_search": "no"}, ConfigError, "second_search.*true or false"),
        ({"holes_km": [[[1, 1], [2, 2]]]}, GeometryError, "region 1 hole 0.*allowed"),
        (
            {"vertices_km": [[0, 0], [100, 100], [100, 0], [0, 100]]},
            GeometryError,
            "region 1: invalid polygon .Self-intersection",
        ),
        ({"direction_deg": float("nan")}, ConfigError, "direction_deg"),
        ({"vertices_km": "abc"}, ConfigError, "vertices_km"),
    ],
)
def test_region_file_errors_name_the_region_and_field(tmp_path, change, error, match):
    with pytest.raises(error, match=match):
        _regions(tmp_path, **change)


def test_subnormal_radius_is_refused_not_divided_by(tmp_path):
    # found by the campaign (seed 37): radius_km 1.1e-308 passed "> 0", then divided by zero
    circle = {"kind": "circle", "pattern": "expanding_square", "center_km": [50, 50]}
    with pytest.raises(ConfigError, match=r"radius_km: got 1.1e-308; allowed: a number in \[1e-09"):
        _regions(tmp_path, **circle, radius_km=1.1e-308, vertices_km=[])


def test_second_search_false_halves_the_expanding_square(tmp_path):
    circle = {
        "kind": "circle",
        "pattern": "expanding_square",
        "center_km": [50, 50],
        "radius_km": 20,
        "vertices_km": [],
    }
    one = _regions(tmp_path, **circle, second_search=False).regions[0].track()
    two = _regions(tmp_path, **circle, second_search=True).regions[0].track()
    assert two.length_m > 1.8 * one.length_m


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("learning_rate", float("inf")),
        ("learning_rate", 1e300),
        ("learning_rate", 0.0),
        ("gamma", float("nan")),
        ("ent_coef", "0.1"),
        ("n_envs", 10**9),
        ("n_steps", 2.5),
        ("seed", -1),
        ("total_timesteps", True),
    ],
)
def test_training_options_are_checked_before_training(field, value):
    from poc_env.agents.rl.args import TrainArgs

    with pytest.raises(ConfigError) as err:
        TrainArgs(**{field: value})
    assert err.value.field == field


def test_an_output_path_that_is_not_a_regular_file_is_never_replaced(tmp_path):
    """A fresh-clone CI run (as root) replaced /dev/null with a plain file: the campaign gave
    `plan --out /dev/null` and the atomic write renamed its temporary file over the device.
    Every atomic write and the CLI's output check refuse anything but a regular file; a FIFO
    stands in for the device here."""
    import os
    import stat

    from poc_env.cli import main
    from poc_env.io import check_replaceable, write_text_atomic

    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="FIFO"):
        write_text_atomic(fifo, "x")
    with pytest.raises(ConfigError, match=r"out.*FIFO"):
        check_replaceable(fifo, "out")
    argv = ["plan", "--scenario", "small", "--maxiter", "1", "--popsize", "4", "--quiet"]
    assert main([*argv, "--out", str(fifo)]) == 2
    assert main([*argv, "--out", str(tmp_path / "p.json"), "--plot", str(fifo)]) == 2
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    (tmp_path / "regular.json").write_text("old")  # a regular file is replaced as before
    write_text_atomic(tmp_path / "regular.json", "new")
    assert (tmp_path / "regular.json").read_text() == "new"
