"""Rendering: rgb_array frames of the simulator state and animated GIFs of episodes."""

import copy
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim import core as sim
from poc_env.viz.rendering import Renderer, random_policy, render_episode, write_gif

#: a no-fly square and a threat peak inside the small scenario's 40 km x 40 km area
ZONE_KM = [[28, 28], [36, 28], [36, 36], [28, 36]]
THREAT = {"center_km": [8, 8], "lambda_per_km2": 0.05}  # Th_s = 0.5 -> r = 3.72 km
OVERRIDES = {"map.no_fly_zones_km": [ZONE_KM], "map.threat_peaks": [THREAT]}


@pytest.fixture(scope="module")
def params():
    return sim.make_params(load_scenario("small", OVERRIDES))


@pytest.fixture(scope="module")
def plain_params():
    return sim.make_params(load_scenario("small"))


@pytest.fixture(scope="module")
def episode(params):
    """The state at reset and after 40 steps of gentle random flight (with its history)."""
    rngs = [np.random.default_rng(3)]
    state = sim.initial(params, rngs)
    start = copy.deepcopy(state)
    history = [state.pos[0, :, :2].copy()]
    arng = np.random.default_rng(1)
    for _ in range(40):
        actions = random_policy(state, arng)
        actions[..., 1] *= 0.3
        sim.step(params, state, actions, rngs)
        history.append(state.pos[0, :, :2].copy())
    assert state.posc[0] > 0.05  # the map was searched
    return start, state, history


def _renderer(params, start, history=(), state=None):
    """A renderer whose colour scale was fixed by ``start`` and which recorded ``history``."""
    r = Renderer(params, "rgb_array")
    r.record(start)
    if state is not None:
        for k, xy in enumerate(history[1:], start=1):
            s = copy.deepcopy(state)
            s.step[:] = k
            s.pos[0, :, :2] = xy
            r.record(s)
    return r


def _box(r, params):
    """Pixel slices (rows, cols) of the heat map (the grid) in the last frame, with its edge."""
    x0, y0, x1, y1 = params.grid.bounds
    (c0, r0), (c1, r1) = r.data_to_pixel([[x0, y1], [x1, y0]])
    return slice(int(r0) - 1, int(r1) + 2), slice(int(c0) - 1, int(c1) + 2)


def _changed(a, b):
    return np.any(a != b, axis=-1)


# ---------------------------------------------------------------------- import


def test_import_does_not_load_matplotlib():
    code = (
        "import sys\n"
        "from poc_env.viz import rendering\n"
        "from poc_env.sim import core as simulator\n"
        "from poc_env.config import load_scenario\n"
        "assert 'matplotlib' not in sys.modules, 'import loaded matplotlib'\n"
        "assert 'PIL' not in sys.modules, 'import loaded PIL'\n"
        "rendering.Renderer(simulator.make_params(load_scenario('small')), 'human')\n"
        "assert 'matplotlib' not in sys.modules, 'construction loaded matplotlib'\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


# ---------------------------------------------------------------------- frames


def test_frame_is_uint8_rgb_of_the_fixed_size(params, episode):
    start, state, _ = episode
    r = Renderer(params, "rgb_array")
    r.record(start)
    f0 = r.frame(start)
    f1 = r.frame(state)
    for f in (f0, f1):
        assert f.dtype == np.uint8 and f.shape == (480, 640, 3)
    assert f0.std() > 10  # a picture, not a blank canvas
    small = Renderer(params, "rgb_array", figsize=(4.0, 3.0), dpi=50).frame(start)
    assert small.shape == (150, 200, 3)


def test_frames_of_different_states_differ_and_repeat_exactly(params, episode):
    start, state, _ = episode
    r = Renderer(params, "rgb_array")
    r.record(start)
    a = r.frame(start)
    b = r.frame(state)
    assert _changed(a, b).sum() > 1000
    np.testing.assert_array_equal(r.frame(start), a)  # the dynamic layer is fully redrawn
    np.testing.assert_array_equal(r.frame(state), b)


def test_searched_map_drains_in_the_heat_map(params, episode):
    """Only the belief differs: the change is inside the heat map and nowhere else."""
    start, state, _ = episode
    undrained = copy.deepcopy(state)
    undrained.belief[:] = start.belief
    r = _renderer(params, start)
    searched = r.frame(state)
    rows, cols = _box(r, params)
    original = r.frame(undrained)
    diff = _changed(searched, original)
    assert diff[rows, cols].mean() > 0.05
    outside = diff.copy()
    outside[rows, cols] = False
    assert not outside.any()
    # bone_r: searched (drained) cells are lighter
    assert searched[rows, cols].astype(int).sum() > original[rows, cols].astype(int).sum()


def test_colour_scale_is_fixed_at_reset(params, episode):
    """Halving the whole belief changes the picture (an autoscaled map would not change)."""
    start, state, _ = episode
    r = _renderer(params, start)
    a = r.frame(state)
    halved = copy.deepcopy(state)
    halved.belief *= 0.5
    b = r.frame(halved)
    rows, cols = _box(r, params)
    assert _changed(a, b)[rows, cols].mean() > 0.2
    # a new history fixes a new scale: the halved prior looks like the prior did
    r.reset_history()
    half_start = copy.deepcopy(start)
    half_start.belief *= 0.5
    r.record(half_start)
    c = r.frame(half_start)
    r2 = _renderer(params, start)
    d = r2.frame(start)
    np.testing.assert_array_equal(c[rows, cols], d[rows, cols])


def test_tracks_are_drawn_from_the_history(params, episode):
    start, state, history = episode
    with_tracks = _renderer(params, start, history, state)
    assert with_tracks.n_recorded == len(history)
    a = with_tracks.frame(state)
    b = Renderer(params, "rgb_array").frame(state)  # no history: current positions only
    assert _changed(a, b).sum() > 300
    # recording the same step again does not grow the history; a step back starts anew
    with_tracks.record(state)
    assert with_tracks.n_recorded == len(history)
    with_tracks.record(start)
    assert with_tracks.n_recorded == 1
    with_tracks.reset_history()
    assert with_tracks.n_recorded == 0


def test_swath_is_the_last_segment_buffered_by_half_the_sweep_width(params, episode):
    start = episode[0]
    moved = copy.deepcopy(start)
    moved.step[:] = 1
    a = start.pos[0, 0, :2]
    moved.pos[0, 0, :2] = a + np.array([8e3, 0.0])  # one long eastward segment for UAV 0
    with_segment = _renderer(params, start)
    with_segment.record(moved)
    f = with_segment.frame(moved)
    no_segment = Renderer(params, "rgb_array")
    no_segment.record(moved)
    g = no_segment.frame(moved)
    half = params.scenario.sensor.sweep_width_m / 2
    mid = a + np.array([4e3, 0.0])
    for offset, inside in ((0.6 * half, True), (-0.6 * half, True), (1.6 * half, False)):
        c, rr = with_segment.data_to_pixel(mid + np.array([0.0, offset]))
        sl = (slice(int(rr) - 1, int(rr) + 2), slice(int(c) - 1, int(c) + 2))
        assert _changed(f[sl], g[sl]).any() == inside, offset


def test_target_star_only_once_detected(params, episode):
    _, state, _ = episode
    hidden = copy.deepcopy(state)
    hidden.detected[:] = False
    shown = copy.deepcopy(state)
    shown.detected[:] = True
    shown.detect_step[:] = 7
    r = Renderer(params, "rgb_array")

    def lime_near_target(frame):
        c, rr = r.data_to_pixel(state.target[0])
        win = frame[int(rr) - 8 : int(rr) + 9, int(c) - 8 : int(c) + 9].astype(int)
        return ((win[..., 1] > 200) & (win[..., 0] < 90) & (win[..., 2] < 90)).sum()

    assert lime_near_target(r.frame(hidden)) == 0
    assert lime_near_target(r.frame(shown)) > 5


def test_no_fly_zone_and_threat_are_drawn(params, plain_params, episode):
    start, _, _ = episode
    zoned = Renderer(params, "rgb_array")
    plain = Renderer(plain_params, "rgb_array")
    a, b = zoned.frame(start), plain.frame(start)
    c0, r0 = zoned.data_to_pixel([29e3, 35e3])  # inside the zone, clear of its edge
    c1, r1 = zoned.data_to_pixel([35e3, 29e3])
    sl = (slice(int(r0), int(r1)), slice(int(c0), int(c1)))

    def red(f):
        x = f[sl].astype(int)
        return ((x[..., 0] > 200) & (x[..., 1] < 120) & (x[..., 2] < 120)).sum()

    assert red(a) > 10 and red(b) == 0
    # the threat circle (radius sqrt(ln 2 / lambda)) is outlined in orange
    radius = np.sqrt(np.log(2) / 0.05e-6)
    ring = [8e3 + radius * np.cos(t) for t in (0.0, np.pi)]
    for x in ring:
        c, rr = zoned.data_to_pixel([x, 8e3])
        win = a[int(rr) - 3 : int(rr) + 4, int(c) - 3 : int(c) + 4].astype(int)
        orange = (win[..., 0] > 200) & (win[..., 1] > 90) & (win[..., 1] < 190) & (win[..., 2] < 80)
        assert orange.any()


def test_links_are_drawn_between_flying_uavs_only(params, episode):
    _, state, _ = episode
    r = Renderer(params, "rgb_array")
    linked, unlinked = copy.deepcopy(state), copy.deepcopy(state)
    linked.links[:] = True
    unlinked.links[:] = False
    assert _changed(r.frame(linked), r.frame(unlinked)).sum() > 50
    for s in (linked, unlinked):
        s.flying[:] = False
    np.testing.assert_array_equal(r.frame(linked), r.frame(unlinked))


def test_crashed_and_landed_markers_differ(params, episode):
    _, state, _ = episode
    r = Renderer(params, "rgb_array")
    base = r.frame(state)
    crashed = copy.deepcopy(state)
    crashed.crashed[0, 0] = True
    landed = copy.deepcopy(state)
    landed.landed[0, 0] = True
    c, rr = r.data_to_pixel(state.pos[0, 0, :2])
    sl = (slice(int(rr) - 6, int(rr) + 7), slice(int(c) - 6, int(c) + 7))
    frames = [base, r.frame(crashed), r.frame(landed)]
    for i in range(3):
        for j in range(i + 1, 3):
            assert _changed(frames[i][sl], frames[j][sl]).any()


def test_renderer_modes_and_close(params, episode):
    start, _, _ = episode
    with pytest.raises(ConfigError, match="render_mode"):
        Renderer(params, "ansi")
    Renderer(params, "human").close()  # lazy: no window until the first frame
    r = Renderer(params, "rgb_array")
    a = r.frame(start)
    r.close()
    r.close()
    np.testing.assert_array_equal(r.frame(start), a)  # a closed renderer draws again


# ---------------------------------------------------------------------- GIFs


def test_write_gif_rejects_other_suffixes(tmp_path):
    frame = np.zeros((8, 8, 3), dtype=np.uint8)
    with pytest.raises(ConfigError) as err:
        write_gif([frame], tmp_path / "episode.png")
    assert err.value.field == "out"
    assert not any(tmp_path.iterdir())
    with pytest.raises(ConfigError):
        write_gif([], tmp_path / "empty.gif")
    with pytest.raises(ConfigError):
        write_gif([frame, np.zeros((8, 9, 3), dtype=np.uint8)], tmp_path / "mixed.gif")


def test_write_gif_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    frames = []
    for k in range(5):
        f = np.full((40, 60, 3), 255, dtype=np.uint8)
        f[5 : 15 + k * 4, 10:30] = (255, 215, 0)  # a small gold patch that grows
        f[30:35, 40:50] = rng.integers(0, 256, 3)
        frames.append(f)
    out = write_gif(frames, tmp_path / "sub" / "t.gif", fps=10)
    assert out.exists() and [p.name for p in out.parent.iterdir()] == ["t.gif"]
    with Image.open(out) as im:
        assert im.n_frames == 5 and im.info["duration"] == 100 and im.info["loop"] == 0
        for k, f in enumerate(frames):
            im.seek(k)
            np.testing.assert_allclose(np.asarray(im.convert("RGB")), f, atol=8)


def test_render_episode_writes_a_deterministic_gif(tmp_path):
    a = render_episode("small", random_policy, tmp_path / "a.gif", seed=4, max_steps=15)
    b = render_episode("small", random_policy, tmp_path / "b.gif", seed=4, max_steps=15)
    c = render_episode("small", random_policy, tmp_path / "c.gif", seed=5, max_steps=15, every=4)
    with Image.open(a) as im:
        assert im.n_frames == 16  # reset + 15 steps
        assert im.size == (640, 480)
    with Image.open(c) as im:
        assert im.n_frames == 5  # steps 0, 4, 8, 12 and the last, 15
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()
    with pytest.raises(ConfigError, match="out"):
        render_episode("small", random_policy, tmp_path / "a.mp4", max_steps=2)
    with pytest.raises(ConfigError, match="every"):
        render_episode("small", random_policy, tmp_path / "d.gif", max_steps=2, every=0)


def test_render_episode_stops_when_no_uav_flies(tmp_path, plain_params):
    calls = []

    def policy(state, rng):
        calls.append(int(state.step[0]))
        state.flying[:] = False  # e.g. everything landed: the episode ends after this step
        return np.zeros((1, plain_params.n_agents, 3))

    out = render_episode("small", policy, tmp_path / "e.gif", max_steps=50)
    assert calls == [0]
    with Image.open(out) as im:
        assert im.n_frames == 2


def test_render_episode_stops_where_the_episode_stops(tmp_path):
    """With ``detection_ends_episode`` the GIF ends at the detection, while UAVs still fly."""
    from poc_env.config import load_scenario

    sc = load_scenario("small", {"episode.detection_ends_episode": True})
    calls = []

    def policy(state, rng):
        calls.append(int(state.step[0]))
        if int(state.step[0]) == 2:  # the target under UAV 0, found with certainty
            state.target[0] = state.pos[0, 0, :2]
            state.target_threshold[0] = 1e-9
        return np.zeros((1, sc.n_uavs, 3))

    out = render_episode(sc, policy, tmp_path / "d.gif", max_steps=50)
    assert calls == [0, 1, 2]  # the episode is over after the third step
    with Image.open(out) as im:
        assert im.n_frames == 4  # reset + 3 steps


def test_random_policy_is_level_and_bounded():
    class S:
        pos = np.zeros((2, 5, 3))

    a = random_policy(S, np.random.default_rng(0))
    assert a.shape == (2, 5, 3)
    assert np.all(np.abs(a[..., :2]) <= 1) and a[..., :2].std() > 0.3
    assert np.all(a[..., 2] == 0)
