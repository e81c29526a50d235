"""The ``particles`` motion model (poc_env.theory.particles): the predict step is the particles'
cell-to-cell transition (mass-conserving, the outside tracked), checked against the grid filter
(``drift``) on particles carried by a uniform current, in the environment (the hidden target
follows one particle), and bad tracks named."""

from __future__ import annotations

import re

import numpy as np
import pytest

from poc_env.config import TargetConfig, load_scenario
from poc_env.errors import ConfigError
from poc_env.sim.engine import Engine
from poc_env.theory import motion, particles

H = 1250.0  # the small scenario's fine cell (5 km / 4)
SHAPE = (32, 32)


def uniform_cloud(vel, rows, cols, per=64, span=3600.0, every=600.0, seed=0):
    """``per`` particles uniform in each fine cell of ``rows x cols``, carried by ``vel``."""
    rng = np.random.default_rng(seed)
    js, is_ = np.mgrid[rows, cols]
    x0 = ((is_.ravel()[:, None] + rng.random((is_.size, per))) * H).ravel()
    y0 = ((js.ravel()[:, None] + rng.random((js.size, per))) * H).ravel()
    ts = np.arange(0.0, span + every / 2, every)
    return particles.ParticleTracks(
        x0[:, None] + vel[0] * ts[None], y0[:, None] + vel[1] * ts[None], ts
    )


def histogram(tracks, t):
    c = np.bincount(tracks.cells(t, H, SHAPE), minlength=SHAPE[0] * SHAPE[1] + 1)
    return c[:-1].reshape(SHAPE) / tracks.n, c[-1] / tracks.n


def moments(b):
    yy, xx = (np.mgrid[: SHAPE[0], : SHAPE[1]] + 0.5) * H
    w = b.sum()
    cx, cy = (b * xx).sum() / w, (b * yy).sum() / w
    return np.array([cx, cy]), np.array(
        [(b * xx * xx).sum() / w - cx**2, (b * yy * yy).sum() / w - cy**2]
    )


def test_from_the_particles_histogram_the_belief_is_their_histogram_at_every_step():
    """Started from the particles' histogram, the Markov belief is the histogram of the
    particles at every later step (exactly: ``h_{k+1} = P_k h_k`` by construction), and
    in-map + out-of-map mass stays 1 to 1e-9 while particles leave the map."""
    tracks = uniform_cloud((2.0, -0.7), slice(4, 20), slice(16, 30), per=16)
    b = histogram(tracks, 0.0)[0][None].copy()
    out = 0.0
    dt = 30.0
    for k in range(120):
        out += particles.predict(tracks, b, k * dt, dt, H)[0]
        want, gone = histogram(tracks, (k + 1) * dt)
        np.testing.assert_allclose(b[0], want, rtol=0, atol=1e-12)
        assert out == pytest.approx(gone, abs=1e-12)
        assert abs(b.sum() + out - 1.0) < 1e-9
    assert out > 0.2  # 2 m/s for an hour: a good share left through the east edge


def test_columns_sum_to_one_with_the_outside_and_empty_cells_keep_their_mass():
    tracks = uniform_cloud((3.0, 1.0), slice(10, 14), slice(28, 32), per=8)
    tr = tracks.transition(600.0, 30.0, H, SHAPE)
    cols = np.asarray(tr.matrix.sum(axis=0)).ravel() + tr.out
    np.testing.assert_allclose(cols, 1.0, rtol=0, atol=1e-12)
    occupied = np.bincount(tracks.cells(600.0, H, SHAPE), minlength=SHAPE[0] * SHAPE[1] + 1)
    empty = np.flatnonzero(occupied[:-1] == 0)
    assert len(empty) > 900
    np.testing.assert_array_equal(tr.matrix[empty][:, empty].diagonal(), 1.0)  # the fallback
    assert tr.out.max() > 0  # the cloud at the east edge leaks out
    # the exact adjoint a bound needs: the transpose of the same sparse matrix
    x, y = np.random.default_rng(1).random((2, SHAPE[0] * SHAPE[1]))
    assert (tr.matrix @ x) @ y == pytest.approx(x @ (tr.matrix.T @ y), rel=1e-12)


def test_particles_on_a_uniform_current_agree_with_the_drift_filter():
    """Particles carried by a uniform current (no diffusion) and the ``drift`` grid filter with
    that current, from the same prior (the particles' histogram), 40 min of 30 s steps; the
    current moves the cloud by 2 fine cells east and 1 north in that time (``v = (h / 1200 s,
    h / 2400 s)``), so the particles' histogram is then the start's, shifted:

    * the centres of mass agree to 1e-6 m (both moved by exactly ``v t``);
    * the drift filter's variance exceeds the particles' by exactly its upwind scheme's
      numerical diffusion ``2 D_num t``, ``D_num = |u| h / 2 (1 - |u| dt / h)`` per axis
      (documented in poc_env.theory.motion; the particles carry none), to 1e-6 relative;
    * at every step the centres agree within 25 m (a cell's binning) and the L1 distance of
      the two beliefs stays below 0.35 (measured: at most 0.29 on this boxcar prior, the worst
      case of the upwind scheme's numerical diffusion).

    With a Courant number of exactly 1 (one cell per step) the upwind scheme is exact, and the
    two filters agree to 1e-12.
    """
    vel = np.array([H / 1200.0, H / 2400.0])
    tracks = uniform_cloud(vel, slice(8, 20), slice(6, 18), span=2400.0)
    drift = motion.check(TargetConfig(model="drift"), (8, 8), 2400.0)
    start = histogram(tracks, 0.0)[0]
    bp, bd = start[None].copy(), start[None].copy()
    (c0, v0), dt = moments(start), 30.0
    worst = 0.0
    for k in range(80):
        particles.predict(tracks, bp, k * dt, dt, H)
        out = motion.predict(drift, bd, vel[None], k * dt, dt, H, 4)
        assert out[0] < 1e-9  # the cloud stays on the map: moments are exact
        t = (k + 1) * dt
        (cp, vp), (cd, vd) = moments(bp[0]), moments(bd[0])
        np.testing.assert_allclose(cd - c0, vel * t, atol=1e-6)
        np.testing.assert_allclose(cp - c0, vel * t, atol=25.0)
        worst = max(worst, float(np.abs(bp - bd).sum()))
    assert worst < 0.35
    d_num = np.abs(vel) * H / 2 * (1 - np.abs(vel) * dt / H)
    np.testing.assert_allclose(cp - c0, vel * t, atol=1e-6)
    np.testing.assert_allclose(vp, v0, rtol=1e-9)
    np.testing.assert_allclose(vd - vp, 2 * d_num * t, rtol=1e-6)
    # Courant 1: one fine cell per step east, and the particles move exactly so
    fast = np.array([H / dt, 0.0])
    tracks = uniform_cloud(fast, slice(8, 20), slice(2, 10), span=300.0, every=30.0)
    start = histogram(tracks, 0.0)[0]
    bp, bd = start[None].copy(), start[None].copy()
    for k in range(10):
        particles.predict(tracks, bp, k * dt, dt, H)
        motion.predict(drift, bd, fast[None], k * dt, dt, H, 4)
    np.testing.assert_allclose(bp, bd, rtol=0, atol=1e-12)
    np.testing.assert_allclose(bd[0], histogram(tracks, 300.0)[0], atol=1e-12)


def _scenario(tmp_path, tracks, steps=40, **over):
    path = tmp_path / "tracks.npz"
    np.savez(path, x_m=tracks.x, y_m=tracks.y, t_s=tracks.times_s)
    return load_scenario(
        "small",
        {"episode.horizon_steps": steps, "target.model": "particles",
         "target.particles_file": str(path), **over},
    )  # fmt: skip


def test_in_the_environment_the_target_follows_one_particle_and_mass_is_conserved(tmp_path):
    vel = np.array([4.0, -2.0])  # 14.4 km/h east, 7.2 km/h south
    tracks = uniform_cloud(vel, slice(0, 32), slice(0, 32), per=4, span=1200.0, every=300.0)
    sc = _scenario(tmp_path, tracks)
    eng = Engine(sc, 4, control="heading", obs_type="compass", seeds=[1, 2, 3, 4])
    eng.reset()
    st = eng.current
    assert st.target_particle is not None and np.all(st.target_particle >= 0)
    start = st.target.copy()
    # the particle is one of the target's fine cell
    for k, p in enumerate(st.target_particle):
        cell = np.floor((start[k] - sc.map.origin_m) / H)
        np.testing.assert_array_equal(np.floor([tracks.x[p, 0] / H, tracks.y[p, 0] / H]), cell)
    rng = np.random.default_rng(0)
    for _ in range(40):
        eng.step(rng.uniform(-1, 1, (4, eng.n_agents, eng.action_dim)))
        total = st.belief.sum(axis=(1, 2)) + st.posc + st.mass_out
        np.testing.assert_allclose(total, st.initial_mass, rtol=0, atol=1e-9)
    moved = st.target - start
    inside = ~st.target_out
    np.testing.assert_allclose(moved[inside], np.broadcast_to(vel * 1200.0, moved.shape)[inside])
    assert st.mass_out.min() > 0.02  # mass left the map through the east and south edges
    # a target whose fine cell holds no particle stays put
    pick = particles.pick_particle(tracks, np.array([-10.0, 5.0]), H, SHAPE, rng)
    assert pick == -1
    np.testing.assert_array_equal(
        particles.displacement(tracks, np.array([-1, 0]), 0.0, 600.0), [[0, 0], vel * 600.0]
    )


def test_bad_tracks_are_refused_naming_the_key(tmp_path):
    sc_map = load_scenario("small").map
    ok = uniform_cloud((1.0, 0.0), slice(0, 4), slice(0, 4), per=8, span=2430.0, every=810.0)
    x, y, t = ok.x, ok.y, ok.times_s
    cases = {
        "too few": ((x[:50], y[:50], t), "at least 100 particles"),
        "short": ((x[:, :3], y[:, :3], t[:3]), "covering the episode"),
        "late start": ((x, y, t + 60.0), "covering the episode"),
        "nan": ((np.where(x > 2000, np.nan, x), y, t), "NaN"),
        "shape": ((x, y[:, :2], t), "lon and lat (particles, times)"),
        "order": ((x[:, ::-1], y[:, ::-1], t[::-1]), "increasing"),
    }
    for name, ((a, b, c), text) in cases.items():
        with pytest.raises(ConfigError, match=re.escape(text)) as err:
            particles.tracks_from_lonlat(a, b, c, sc_map, 2430.0, local=True)
        assert err.value.field == "target.particles_file", name
    # lon/lat on a map without a geographic origin
    with pytest.raises(ConfigError) as err:
        particles.tracks_from_lonlat(x * 0 + 10.0, y * 0 + 45.0, t, sc_map, 2430.0)
    assert err.value.field == "map.origin_deg"
    # files: not an .npz, missing arrays, an .npy named .npz
    np.savez(tmp_path / "a.npz", lon=x)
    np.save(tmp_path / "b.npy", x)
    (tmp_path / "b.npy").rename(tmp_path / "b.npz")
    for path, text in ((tmp_path / "a.npz", "t_s"), (tmp_path / "b.npz", "archive"),
                       (tmp_path / "c.csv", "an existing .npz")):  # fmt: skip
        with pytest.raises(ConfigError, match=text) as err:
            particles.load_tracks(str(path), sc_map, 2430.0)
        assert err.value.field == "target.particles_file"
    # the scenario: particles_file if and only if model particles; no extra diffusion
    with pytest.raises(ConfigError, match="particles_file"):
        TargetConfig(model="particles")
    with pytest.raises(ConfigError, match="particles_file"):
        TargetConfig(model="drift", particles_file="t.npz")
    sc = _scenario(tmp_path, ok, **{"target.diffusion_m2_s": 5.0})
    with pytest.raises(ConfigError) as err:
        Engine(sc, 1)
    assert err.value.field == "target.diffusion_m2_s"


def test_the_space_time_planner_predicts_with_the_particles(tmp_path):
    """``spacetime_plan``'s predicted POC (agents.planning.spacetime.comoving_poc, drift 0: the
    ground frame) moves with the particles' transition, not the prior standing still."""
    from poc_env.agents.planning.spacetime import comoving_poc

    vel = np.array([4.0, 0.0])
    tracks = uniform_cloud(vel, slice(8, 24), slice(4, 12), per=4, span=1200.0, every=300.0)
    sc = _scenario(tmp_path, tracks)
    start = histogram(tracks, 0.0)[0]
    poc = comoving_poc(sc, start, np.zeros(2), 4, 1200.0)
    want = np.zeros((8, 8))
    for k in range(40):  # the average over the steps of the particles' coarse histograms
        want += histogram(tracks, (k + 1) * 30.0)[0].reshape(8, 4, 8, 4).sum(axis=(1, 3))
    np.testing.assert_allclose(poc, want / 40, rtol=0, atol=1e-12)
