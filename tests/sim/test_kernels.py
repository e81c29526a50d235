"""The compiled kernels (the package poc_env._kernels) against plain-numpy references.

Each kernel is compared with a numpy reference: the numpy implementations below (pairwise
distances, eq. 20, 21 and 24 checks, the auto topology, observations) or the library's own
numpy paths (``search_theory.segment_pod`` for the hidden target, ``comms`` and ``constraints``
for the step's flags). Floats agree to ``rtol=1e-12`` (:func:`assert_close`); booleans and
integers exactly. Bit-for-bit comparisons are kept only for determinism: the same code run
twice on the same input gives the same bytes. On many seeded random configurations, including
ties, inactive UAVs and non-finite values.
"""

from __future__ import annotations

import ast
import copy
import dataclasses
import importlib
import importlib.util
import inspect
from pathlib import Path

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher as Dispatcher

import poc_env
from poc_env._kernels import observations as obs_kernels
from poc_env._kernels import sensing
from poc_env.config import load_scenario
from poc_env.errors import ConfigError
from poc_env.sim import comms, constraints
from poc_env.sim import core as sim
from poc_env.sim import observations as obs
from poc_env.theory import search_theory
from poc_env.theory.detection import LAW_NAMES, detection_law

# ------------------------------------------------------------------ numpy references


def ref_pairwise_distances(xy):
    p = np.asarray(xy, dtype=float)
    d2 = np.zeros(p.shape[:-1] + p.shape[-2:-1])
    for k in range(p.shape[-1]):
        c = p[..., k]
        d2 += (c[..., :, None] - c[..., None, :]) ** 2
    return np.sqrt(d2)


def ref_outside_boundary(xy, bounds):
    p = np.asarray(xy, dtype=float)
    x0, y0, x1, y1 = (float(v) for v in bounds)
    x, y = p[..., 0], p[..., 1]
    return (x < x0) | (x > x1) | (y < y0) | (y > y1)


def ref_separation_violations(xy, d_s, active=None):
    p = np.asarray(xy, dtype=float)
    n = p.shape[-2]
    pairs = ref_pairwise_distances(p) < float(d_s)
    pairs &= ~np.eye(n, dtype=bool)
    if active is not None:
        act = np.asarray(active, dtype=bool)
        pairs &= act[..., :, None] & act[..., None, :]
    return np.asarray(pairs.any(axis=-1)), pairs


def _ref_active(active, shape):
    if active is None:
        return np.ones(shape, dtype=bool)
    return np.broadcast_to(np.asarray(active, dtype=bool), shape)


def ref_in_range(xy, range_m, active=None):
    p = np.asarray(xy, dtype=float)
    n_envs, n = p.shape[0], p.shape[1]
    adj = ref_pairwise_distances(p) <= float(range_m)
    adj &= ~np.eye(n, dtype=bool)
    act = _ref_active(active, (n_envs, n))
    return adj & act[:, :, None] & act[:, None, :]


def ref_two_neighbour_ok(adj, min_neighbours=2, active=None):
    a = np.asarray(adj, dtype=bool)
    count = a.sum(axis=-1)
    if active is None:
        return count >= int(min_neighbours)
    act = _ref_active(active, count.shape)
    need = np.minimum(int(min_neighbours), act.sum(axis=-1, keepdims=True) - 1)
    return ~act | (count >= need)


def ref_auto_topology(available, xy=None, active=None, min_neighbours=2):
    """The vectorised Prim loop (n rounds over (n_envs, n) arrays) and stable argsort."""
    av = np.asarray(available, dtype=bool)
    n_envs, n = av.shape[0], av.shape[-1]
    act = _ref_active(active, (n_envs, n))
    av = av & act[:, :, None] & act[:, None, :] & ~np.eye(n, dtype=bool)
    dist = ref_pairwise_distances(xy) if xy is not None else np.ones((n_envs, n, n))
    w = np.where(av, dist, np.inf)
    envs = np.arange(n_envs)
    links = np.zeros((n_envs, n, n), dtype=bool)
    visited = ~act.copy()
    key = np.full((n_envs, n), np.inf)
    parent = np.zeros((n_envs, n), dtype=np.intp)
    n_comp = np.zeros(n_envs, dtype=np.int64)
    for _ in range(n):
        remaining = np.asarray(~visited.all(axis=-1))
        k = np.where(visited, np.inf, key)
        j = np.argmin(k, axis=-1)
        grow = remaining & np.isfinite(k[envs, j])
        new_root = remaining & ~grow
        j = np.where(new_root, np.argmax(~visited, axis=-1), j)
        n_comp += new_root
        pj = parent[envs, j]
        links[envs[grow], pj[grow], j[grow]] = True
        visited[envs[remaining], j[remaining]] = True
        wj = w[envs, j, :]
        better = (wj < key) & ~visited & remaining[:, None]
        key = np.where(better, wj, key)
        parent = np.where(better, j[:, None], parent)
    kk = min(int(min_neighbours), n - 1)
    if kk > 0:
        nearest = np.argsort(w, axis=-1, kind="stable")[..., :kk]
        ok = np.isfinite(np.take_along_axis(w, nearest, axis=-1))
        e_idx = np.broadcast_to(envs[:, None, None], nearest.shape)
        i_idx = np.broadcast_to(np.arange(n)[None, :, None], nearest.shape)
        links[e_idx[ok], i_idx[ok], nearest[ok]] = True
    links |= np.swapaxes(links, -1, -2)
    return links, n_comp <= 1, n_comp


def ref_rasters(params, state, poc_scale, hazard):
    e, n = state.flying.shape
    g = params.grid
    with np.errstate(divide="ignore", invalid="ignore"):
        poc = g.coarsen(state.belief, params.s) / poc_scale[:, None, None]
    out = np.zeros((e, n, obs.RASTER_CHANNELS, g.ny, g.nx), dtype=np.float32)
    out[:, :, 0] = np.clip(poc, 0.0, 1.0)[:, None]
    out[:, :, 3] = hazard
    j, i, inside = obs.cell_pixels(params, state.pos[..., :2])
    present = inside & state.flying
    ee, nn = np.nonzero(present)
    own = np.zeros((e, n, g.ny, g.nx), dtype=np.float32)
    own[ee, nn, j[ee, nn], i[ee, nn]] = 1.0
    out[:, :, 1] = own
    counts = np.zeros((e, g.ny, g.nx), dtype=np.float32)
    np.add.at(counts, (ee, j[ee, nn], i[ee, nn]), 1.0)
    out[:, :, 2] = np.clip(counts[:, None] - own, 0.0, 1.0)
    return out


def ref_vectors(params, state):
    sc = params.scenario
    u = sc.uav
    bx0, by0, bx1, by1 = params.bounds
    w, h = bx1 - bx0, by1 - by0
    diag = float(np.hypot(w, h))
    xy = state.pos[..., :2]
    to_land = (params.landing[None] - xy) / diag
    adj = ref_in_range(xy, sc.comms.range_m, state.flying)
    n = state.flying.shape[1]
    v = np.empty((*state.flying.shape, obs.VECTOR_SIZE), dtype=np.float64)
    v[..., 0] = (xy[..., 0] - bx0) / w
    v[..., 1] = (xy[..., 1] - by0) / h
    v[..., 2] = state.pos[..., 2] / u.max_altitude_m
    v[..., 3] = (state.speed - u.min_speed_mps) / (u.max_speed_mps - u.min_speed_mps)
    v[..., 4] = np.sin(state.heading)
    v[..., 5] = np.cos(state.heading)
    v[..., 6] = state.pitch / u.max_pitch_rad
    v[..., 7] = 1.0 - state.elapsed / u.endurance_s
    v[..., 8] = 1.0 - state.elapsed / u.usable_endurance_s
    v[..., 9:11] = to_land
    v[..., 11] = adj.sum(axis=2) / max(n - 1, 1)
    v[..., 12] = state.flying
    v[..., 13] = (state.step / params.horizon)[:, None]
    return np.clip(v, obs.VECTOR_LOW, obs.VECTOR_HIGH).astype(np.float32)


# ------------------------------------------------------------------ helpers


def same(a, b, path="") -> list[str]:
    """Differences between two nested results: types, dict key order and bytes must match."""
    if type(a) is not type(b):
        return [f"{path}: {type(a).__name__} vs {type(b).__name__}"]
    if isinstance(a, dict):
        if list(a) != list(b):
            return [f"{path}: keys {list(a)} vs {list(b)}"]
        return [d for k in a for d in same(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            return [f"{path}: length {len(a)} vs {len(b)}"]
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in same(x, y, f"{path}[{k}]")]
    if isinstance(a, np.ndarray):
        ok = a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
        return [] if ok else [f"{path}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"]
    if isinstance(a, float) and np.isnan(a):
        return [] if np.isnan(b) else [f"{path}: nan vs {b}"]
    return [] if a == b else [f"{path}: {a!r} vs {b!r}"]


def assert_same(a, b):
    """Bit-for-bit equality: only for determinism (the same code run twice)."""
    diff = same(a, b)
    assert not diff, "\n".join(diff[:20])


def close(a, b, path="", rtol=1e-12) -> list[str]:
    """Differences between a kernel's result and its reference: dtypes, shapes and dict keys
    must match; floats agree to ``rtol`` (NaN where NaN), everything else exactly."""
    if isinstance(a, (dict, list, tuple)):
        if type(a) is not type(b) or len(a) != len(b):
            return [f"{path}: {type(a).__name__}[{len(a)}] vs {type(b).__name__}"]
        if isinstance(a, dict):
            if list(a) != list(b):
                return [f"{path}: keys {list(a)} vs {list(b)}"]
            return [d for k in a for d in close(a[k], b[k], f"{path}.{k}", rtol)]
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in close(x, y, f"{path}[{k}]", rtol)]
    if isinstance(a, np.ndarray) and a.dtype.kind == "f":
        if not isinstance(b, np.ndarray) or a.dtype != b.dtype or a.shape != b.shape:
            return [f"{path}: {a.dtype}{a.shape} vs {getattr(b, 'dtype', type(b))}"]
        try:
            np.testing.assert_allclose(a, b, rtol=rtol, atol=0.0, equal_nan=True)
        except AssertionError as err:
            return [f"{path}: {err}"]
        return []
    return same(a, b, path)


def assert_close(a, b, rtol=1e-12):
    diff = close(a, b, rtol=rtol)
    assert not diff, "\n".join(diff[:20])


def random_swarm(rng, n_envs, n, ties):
    xy = rng.uniform(0, 100, (n_envs, n, 2))
    if ties:  # coincident UAVs and equal distances
        xy = np.round(xy / 25) * 25
    return xy


NOFLY = {"map.no_fly_zones_km": [[[24, 15], [30, 15], [30, 25], [24, 25]]]}
THREAT = {"map.threat_peaks": [{"center_km": [8, 8], "lambda_per_km2": 0.05}]}
CONFIGS = [
    ("paper_6_2", {"episode.horizon_steps": 40}),
    ("small", {}),
    ("small", {**NOFLY, **THREAT, "constraints.violation": "shield"}),
    ("small", {**NOFLY, **THREAT, "constraints.violation": "terminate"}),
    ("small", {"constraints.safety_distance_km": 3, "comms.min_neighbours": 0}),
    ("small", {"comms.link_failure_prob": 0.3, "comms.range_km": 15}),
    ("small", {"comms.range_km": 12, "comms.min_neighbours": 3}),
    (
        "small",
        {"fleet": [{"takeoff": "A", "count": 5}], "comms.topology": "table2", "comms.range_km": 25},
    ),
    ("small", {"sensor.law": "exponential", "sensor.samples_per_cell": 3, "episode.dt_s": 60}),
    ("small", {"sensor.law": "definite_range", "sensor.samples_per_cell": 1}),
    ("small", {"sensor.sweep_width_km": 8, "reward.credit": "individual", "reward.beta": 0.5}),
    ("small", {"fleet": [{"takeoff": "A", "count": 9}], "comms.range_km": 14}),
    ("small", {"fleet": [{"takeoff": "A", "count": 1}]}),
]


def spread(state, params, rng):
    """UAVs over the search area, some of them having left home (landings happen)."""
    x0, y0, x1, y1 = params.grid.bounds
    state.pos[..., 0] = rng.uniform(x0, x1, state.pos.shape[:2])
    state.pos[..., 1] = rng.uniform(y0, y1, state.pos.shape[:2])
    state.heading = rng.uniform(-np.pi, np.pi, state.heading.shape)
    state.left_home[:] = rng.random(state.left_home.shape) < 0.5


# ------------------------------------------------------------------ kernels vs references


def test_pairwise_and_constraint_kernels_match_numpy():
    rng = np.random.default_rng(0)
    for t in range(200):
        n_envs, n = int(rng.integers(1, 5)), int(rng.integers(1, 10))
        d = 3 if t % 4 == 0 else 2
        xy = rng.uniform(-50, 150, (n_envs, n, d))
        if t % 3 == 0:
            xy = np.round(xy / 25) * 25
        if t % 17 == 0:
            xy[0, 0, 0] = np.nan
        act = rng.random((n_envs, n)) < 0.8
        assert_close(constraints.pairwise_distances(xy), ref_pairwise_distances(xy))
        assert_close(constraints.pairwise_distances(xy[0]), ref_pairwise_distances(xy[0]))
        b = (0.0, -10.0, 100.0, 90.0)
        assert_close(constraints.outside_boundary(xy, b), ref_outside_boundary(xy, b))
        d_s, rc = float(rng.uniform(5, 60)), float(rng.uniform(10, 120))
        for a in (act, None):
            assert_close(
                constraints.separation_violations(xy, d_s, a),
                ref_separation_violations(xy, d_s, a),
            )
            adj = comms.in_range(xy, rc, a)
            assert_close(adj, ref_in_range(xy, rc, a))
            dist = ref_pairwise_distances(xy)
            assert_close(comms.in_range(xy, rc, a, dist), adj)
            assert_close(
                constraints.separation_violations(xy, d_s, a, dist),
                ref_separation_violations(xy, d_s, a),
            )
            for m in (0, 1, 2, 3, -1):
                for a2 in (act, None):
                    want = ref_two_neighbour_ok(adj, m, a2)
                    assert_close(comms.two_neighbour_ok(adj, m, a2), want)
        # 2-D (no env axis) separation, as the docstring's "any leading shape"
        assert_close(
            constraints.separation_violations(xy[0], d_s, act[0]),
            ref_separation_violations(xy[0], d_s, act[0]),
        )


def test_auto_topology_matches_the_vectorised_prim_loop():
    rng = np.random.default_rng(1)
    for t in range(600):
        n_envs, n = int(rng.integers(1, 6)), int(rng.integers(1, 11))
        xy = random_swarm(rng, n_envs, n, ties=t % 3 == 0)
        act = rng.random((n_envs, n)) < 0.8 if t % 2 else None
        avail = comms.link_failures(ref_in_range(xy, rng.uniform(20, 90), act), 0.25, rng)
        mn = int(rng.integers(-1, 5))
        for x in (xy, None):
            want = ref_auto_topology(avail, x, act, mn)
            got = comms.auto_topology(avail, x, act, mn)
            assert_close((got.links, got.connected, got.n_components), want)
        # precomputed distances give the same links
        got = comms.auto_topology(avail, xy, act, mn, dist=ref_pairwise_distances(xy))
        want = ref_auto_topology(avail, xy, act, mn)
        assert_close((got.links, got.connected, got.n_components), want)


def _obs_state(params, rng, n_envs=2):
    rngs = [np.random.default_rng(k) for k in range(n_envs)]
    st = sim.initial(params, rngs)
    x0, y0, x1, y1 = params.grid.bounds
    w, h = x1 - x0, y1 - y0
    st.pos[..., 0] = rng.uniform(x0 - 0.1 * w, x1 + 0.1 * w, st.pos.shape[:2])
    st.pos[..., 1] = rng.uniform(y0 - 0.1 * h, y1 + 0.1 * h, st.pos.shape[:2])
    st.pos[0, 0, :2] = (x1, y1)  # on the far edges: the last cell
    st.pos[-1, -1, :2] = (x0, y0)
    st.pos[..., 2] = rng.uniform(-100, 6000, st.pos.shape[:2])
    st.heading = rng.uniform(-4, 4, st.heading.shape)
    st.heading[0, 0] = -0.0
    st.speed = rng.uniform(20, 80, st.speed.shape)
    st.pitch = rng.uniform(-0.5, 0.5, st.pitch.shape)
    st.elapsed = rng.uniform(0, 2 * params.scenario.uav.endurance_s, st.elapsed.shape)
    st.flying = rng.random(st.flying.shape) < 0.7
    st.step = rng.integers(0, 2 * params.horizon, n_envs)
    st.belief *= rng.uniform(0, 2, st.belief.shape)
    st.belief[0, :3] = -0.0
    return st


@pytest.mark.parametrize(
    ("s", "cells_km", "width_km"),
    [(1, 5, 40), (2, 5, 40), (3, 5, 40), (4, 10, 40), (7, 10, 40), (9, 10, 40), (2, 5, 5)],
)
def test_observations_match_numpy(s, cells_km, width_km):
    """Rasters (own sub-cell sums for s < 8 over several columns, else Grid.coarsen) and
    vectors against numpy, with UAVs outside the grid, on its edges and not flying."""
    params = sim.make_params(
        load_scenario(
            "small",
            {
                "sensor.samples_per_cell": s,
                "map.cell_km": cells_km,
                "map.width_km": width_km,
                "fleet": [{"takeoff": "A", "count": 5}],
            },
        )
    )
    rng = np.random.default_rng(s)
    hazard = (rng.random(params.grid.shape) < 0.3).astype(np.float32)
    for _ in range(20):
        st = _obs_state(params, rng)
        for scale in (np.array([0.05, 0.2]), np.array([-0.1, 0.0])):
            want = ref_rasters(params, st, scale, hazard)
            assert_close(obs.rasters(params, st, scale, hazard), want)
        assert_close(obs.vectors(params, st), ref_vectors(params, st))


def test_vector_clip_matches_numpy_on_special_values():
    params = sim.make_params(load_scenario("small"))
    st = _obs_state(params, np.random.default_rng(3), n_envs=1)
    st.pos[0, :, 2] = [-0.0, np.nan, np.inf]
    st.speed[0] = [params.scenario.uav.min_speed_mps, -np.inf, np.nan]
    st.pitch[0] = [-0.0, 0.0, np.nan]
    st.elapsed[0] = [np.nan, 0.0, np.inf]
    assert_close(obs.vectors(params, st), ref_vectors(params, st))


def _stepped(params, n_steps, seed=7):
    """Three envs spread over the area, stepped with seeded random actions; yields each step's
    (state before, actions, events, state after)."""
    rng = np.random.default_rng(seed)
    rngs = [np.random.default_rng(s) for s in (1, 2, 3)]
    state = sim.initial(params, rngs)
    spread(state, params, np.random.default_rng(11))
    for _ in range(n_steps):
        before = copy.deepcopy(state)
        acts = rng.uniform(-1, 1, (3, params.n_agents, 3))
        ev = sim.step(params, state, acts, rngs)
        yield before, acts, ev, state


@pytest.mark.parametrize(("name", "overrides"), CONFIGS)
def test_step_is_deterministic(name, overrides):
    """The same code on the same input twice: every State and Events array, bit for bit."""
    params = sim.make_params(load_scenario(name, overrides))
    runs = [list(_stepped(params, 30)) for _ in range(2)]
    for (_, _, ev0, st0), (_, _, ev1, st1) in zip(*runs, strict=True):
        assert_same(dataclasses.asdict(ev0), dataclasses.asdict(ev1))
        assert_same(dataclasses.asdict(st0), dataclasses.asdict(st1))


@pytest.mark.parametrize(("name", "overrides"), CONFIGS)
def test_step_kernel_matches_numpy_references(name, overrides):
    """Each part of the compiled step (swarm.step and auto_links, sensing.target_pod) against
    the numpy functions of the library: eq. 12-13 sums, the target's detection exponent
    (search_theory.segment_pod), eq. 17-18 time, eq. 20, 21 and 24 flags, landing and crashes,
    and the topology the step leaves (comms.in_range + comms.auto_topology)."""
    params = sim.make_params(load_scenario(name, overrides))
    sc = params.scenario
    u, ep = sc.uav, sc.episode
    for before, _, ev, st in _stepped(params, 30):
        moving = before.flying
        a2, b2 = before.pos[..., :2], st.pos[..., :2]
        # eq. 12-13: the team's POS and POSC (two summation orders: 1e-12)
        assert_close(ev.pos_team, ev.pos_agent.sum(axis=1))
        assert_close(st.posc, before.posc + ev.pos_agent.sum(axis=1))
        assert_close(st.agent_pos, before.agent_pos + ev.pos_agent)
        # mass conservation: POSC + sum(POC) = initial mass; values ~1, so an atol
        np.testing.assert_allclose(
            st.posc + st.belief.sum(axis=(1, 2)), st.initial_mass, rtol=0, atol=1e-12
        )
        # the hidden target: the law's POD at its exact position (numpy path)
        p_t = search_theory.segment_pod(
            before.target[:, None, :],
            a2,
            b2,
            sc.sensor.sweep_width_m,
            sc.sensor.law,
            params.cutoff_m,
            params.grid.cell_m,
            params.grid.origin_m,
        )
        p_t = np.where(moving, np.minimum(p_t, 1.0), 0.0)
        with np.errstate(divide="ignore"):
            want = before.target_exponent + -np.log1p(-p_t).sum(axis=1)
        assert_close(st.target_exponent, want)
        now = ~before.detected & (st.target_exponent >= st.target_threshold)
        assert_same(ev.detected_now, now)
        assert_same(st.detect_step, np.where(now, before.step + 1, before.detect_step))
        assert_same(st.step, before.step + 1)
        # eq. 17-18: the time model
        assert_close(st.elapsed, before.elapsed + np.where(moving, params.dt, 0.0))
        assert_same(ev.overtime, moving & (st.elapsed > u.usable_endurance_s))
        assert_close(ev.time_term, np.where(moving, params.dt / u.usable_endurance_s, 0.0))
        # eq. 20, 21, 24 on the new positions, with the library's numpy-facing functions
        xy = st.pos[..., :2]
        assert_same(ev.out_of_bounds, moving & constraints.outside_boundary(xy, params.bounds))
        coll, _ = constraints.separation_violations(xy, sc.constraints.safety_distance_m, moving)
        assert_same(ev.collision, coll & moving)
        adj = comms.in_range(xy, sc.comms.range_m, moving)
        assert_same(
            ev.comms_ok, comms.two_neighbour_ok(adj, sc.comms.min_neighbours, moving) | ~moving
        )
        viol = ev.out_of_bounds | ev.no_fly | ev.collision | ev.threat | ~ev.comms_ok
        assert_same(st.violations, before.violations + (viol & moving))
        # landing and crashes
        home = np.hypot(*(xy - params.landing[None]).transpose(2, 0, 1))
        left = before.left_home | (moving & (home > ep.landing_radius_m))
        assert_same(st.left_home, left)
        land = (
            moving
            & left
            & (home <= ep.landing_radius_m)
            & (st.pos[..., 2] <= ep.landing_max_altitude_m)
            & (st.speed <= ep.landing_max_speed_mps)
        )
        crash = moving & ~land & ((st.pos[..., 2] <= 0.0) | (st.elapsed >= u.endurance_s))
        if sc.constraints.violation == "terminate":
            unsafe = ev.out_of_bounds | ev.no_fly | ev.collision | ev.threat
            crash |= moving & ~land & unsafe
        assert_same((ev.landed_now, ev.crashed_now), (land, crash))
        assert_same(st.flying, moving & ~(land | crash))
        # the topology among the UAVs still flying (the auto rule, without failures)
        if sc.comms.link_failure_prob == 0 and params.switcher is None:
            avail = comms.in_range(xy, sc.comms.range_m, st.flying)
            topo = comms.auto_topology(avail, xy, st.flying, sc.comms.min_neighbours)
            assert_same(st.links, topo.links)
            assert_same(ev.connected, np.asarray(topo.connected))


def ref_kinematics(params, state, actions, moving, turn=None):
    """Eq. 19 in plain numpy (the formulation the compiled kinematics replaced): the actions
    clipped and scaled to their per-step limits, the heading wrapped, the pitch clipped (0 when
    not moving), the position moved with the old speed, then the speed clipped."""
    u = params.scenario.uav
    a = np.clip(actions, -1.0, 1.0)
    dt = params.dt
    dv = a[..., 0] * u.max_accel_mps2 * dt
    dalpha = a[..., 1] * u.max_turn_rate_rad_s * dt if turn is None else turn
    dbeta = a[..., 2] * u.max_pitch_rate_rad_s * dt
    alpha = np.where(moving, state.heading + dalpha, state.heading)
    alpha = (alpha + np.pi) % (2.0 * np.pi) - np.pi
    beta = np.where(moving, np.clip(state.pitch + dbeta, -u.max_pitch_rad, u.max_pitch_rad), 0.0)
    step = np.where(moving, state.speed * dt, 0.0)
    new = state.pos.copy()
    new[..., 0] += step * np.cos(alpha) * np.cos(beta)
    new[..., 1] += step * np.sin(alpha) * np.cos(beta)
    new[..., 2] = np.minimum(new[..., 2] + step * np.sin(beta), u.max_altitude_m)
    speed = np.clip(state.speed + dv, u.min_speed_mps, u.max_speed_mps)
    scaled = (dv, a[..., 1] * u.max_turn_rate_rad_s * dt, dbeta)
    return new, alpha, beta, np.where(moving, speed, state.speed), scaled


@pytest.mark.parametrize("name", ["small", "paper_6_2"])
def test_kinematics_kernel_equals_numpy_bit_for_bit(name):
    """The compiled eq. 19 step (sim.core.kinematics, scale_actions) gives the numpy
    formulation's positions, headings, pitches, speeds and increments exactly: actions
    outside [-1, 1], headings to wrap, pitches and speeds at their limits, UAVs that do not
    move, a NaN action and speed (NaN stays NaN, as np.clip), and a shield's turn."""
    params = sim.make_params(load_scenario(name))
    rng = np.random.default_rng(2)
    for trial in range(6):
        st = sim.initial(params, [np.random.default_rng(trial + k) for k in range(8)])
        st.heading = rng.uniform(-10, 10, st.heading.shape)
        st.pitch = rng.uniform(-1, 1, st.pitch.shape)
        st.speed = rng.uniform(0, 100, st.speed.shape)
        st.pos[..., 2] = rng.uniform(-100, 2 * params.scenario.uav.max_altitude_m, st.pos.shape[:2])
        moving = rng.random(st.flying.shape) < 0.8
        actions = rng.uniform(-2, 2, (*moving.shape, 3))
        actions[0, 0, 1] = np.nan
        st.speed[1, 0] = np.nan
        turn = rng.uniform(-0.3, 0.3, moving.shape) if trial % 2 else None
        kept = {key: getattr(st, key).copy() for key in ("pos", "heading", "pitch", "speed")}
        *want, inc = ref_kinematics(params, st, actions, moving, turn)
        got_state = dataclasses.replace(st)
        new = sim.kinematics(params, got_state, actions, moving, turn)
        got = (new, got_state.heading, got_state.pitch, got_state.speed)
        for w, g in zip(want, got, strict=True):
            assert g.dtype == w.dtype
            np.testing.assert_array_equal(g, w)
        for w, g in zip(inc, sim.scale_actions(params, actions), strict=True):
            np.testing.assert_array_equal(g, w)
        # the inputs are not written: new arrays replace them (the previous state stays valid)
        for key in ("pos", "heading", "pitch", "speed"):
            np.testing.assert_array_equal(getattr(st, key), kept[key])


@pytest.mark.parametrize("name", ["small", "paper_6_2"])
def test_autopilot_kernel_equals_the_numpy_autopilot(name):
    """The compiled autopilot (control.swarm_increments of the heading, heading_clip and
    waypoint levels) against the numpy rules it copies (decode_vector, heading_increments,
    waypoint_goal, steer, return_home): UAVs inside and outside the grid, with and without the
    return rule, many of them due home, zero, tiny, out-of-range and NaN actions, finished
    UAVs. The increments are float32-rounded, and numpy's AVX-512 arctan2 may differ from the C
    library's in the last bit, which can move a rounding by one float32 unit: hence the atol
    (with numpy's baseline dispatch the two are bit-equal) and the share that must be exact."""
    from poc_env.sim import control

    params = sim.make_params(load_scenario(name))
    rng = np.random.default_rng(9)
    u = params.scenario.uav
    exact = total = 0
    for trial in range(6):
        st = sim.initial(params, [np.random.default_rng(trial + k) for k in range(16)])
        x0, y0, x1, y1 = params.bounds
        shape = st.flying.shape
        st.pos[..., 0] = rng.uniform(x0 - 1e4, x1 + 1e4, shape)
        st.pos[..., 1] = rng.uniform(y0 - 1e4, y1 + 1e4, shape)
        st.pos[..., 2] = rng.uniform(0, u.max_altitude_m, shape)
        st.heading = rng.uniform(-np.pi, np.pi, shape)
        st.pitch = rng.uniform(-u.max_pitch_rad, u.max_pitch_rad, shape)
        st.speed = rng.uniform(u.min_speed_mps, u.max_speed_mps, shape)
        st.elapsed = rng.uniform(0, u.endurance_s, shape)
        st.flying = rng.random(shape) < 0.9
        action = rng.uniform(-1.5, 1.5, (*shape, 2)).astype(np.float32)
        action[0, 0] = 0.0
        action[1, 0] = 1e-7
        action[2, 0, 0] = np.nan
        e, n = shape
        q = obs.decode_vector(params, obs.vectors(params, st).reshape(e * n, -1))
        k = np.tile(np.arange(n), e)
        for level in ("heading", "heading_clip", "waypoint"):
            for auto_return in (True, False):
                inc = control.to_increments(
                    params, level, q, action.reshape(e * n, 2).astype(float), k, auto_return
                )
                want = np.where(st.flying[..., None], inc.reshape(e, n, 3), 0.0)
                got = control.swarm_increments(params, level, st, action, auto_return)
                assert got.shape == want.shape and got.dtype == want.dtype
                np.testing.assert_allclose(got, want, rtol=0, atol=1.2e-7)
                exact += int(np.sum((got == want) | (np.isnan(got) & np.isnan(want))))
                total += got.size
    assert exact >= 0.999 * total


def test_target_pod_kernel_matches_segment_pod():
    """sensing.target_pod against search_theory.segment_pod (numpy path), every law."""
    rng = np.random.default_rng(4)
    for law in LAW_NAMES:
        for _ in range(20):
            target = rng.uniform(-2000, 12000, (5, 2))
            a = rng.uniform(-2000, 12000, (5, 4, 2))
            b = a + rng.uniform(-3000, 3000, (5, 4, 2))
            b[0, 0] = a[0, 0]
            moving = rng.random((5, 4)) < 0.8
            origin = (-700.0, 300.0)
            w, cutoff, cell = 1500.0, 6000.0, 2000.0
            out = np.empty((5, 4))
            hit = sensing.target_pod(
                target, a, b, moving, *origin, detection_law(law).code, w, cutoff, cell, out
            )
            want = search_theory.segment_pod(target[:, None, :], a, b, w, law, cutoff, cell, origin)
            want = np.where(moving, np.minimum(want, 1.0), 0.0)
            assert_close(out, want)
            assert hit == bool(np.any(want != 0.0))


def _episode(env, seed):
    rng = np.random.default_rng(seed + 100)
    trace = [env.reset(seed=seed)]
    spread(env.sim_state, env.params, rng)
    k = 0
    while env.agents:
        acts = {a: rng.uniform(-1, 1, 3) * [1, 1, 0.2] for a in env.agents}
        if k % 4 == 1:  # float32 arrays and lists
            acts = {
                a: (v.astype(np.float32) if i % 2 else list(v))
                for i, (a, v) in enumerate(acts.items())
            }
        if k % 5 == 2:
            acts = dict(reversed(list(acts.items())))
        trace.append(env.step(acts))
        trace.append(env.state())
        k += 1
    return trace


@pytest.mark.parametrize(("name", "overrides"), CONFIGS[:4] + CONFIGS[7:8] + CONFIGS[10:])
@pytest.mark.parametrize("obs_type", ["dict", "flat"])
def test_env_episodes_are_deterministic(name, overrides, obs_type):
    """The PettingZoo env over the compiled core, run twice: identical traces, bit for bit."""
    overrides = {**overrides, "episode.horizon_steps": 40, "episode.detection_ends_episode": True}
    for seed in (0, 1):
        got = _episode(poc_env.parallel_env(name, obs_type=obs_type, overrides=overrides), seed)
        want = _episode(poc_env.parallel_env(name, obs_type=obs_type, overrides=overrides), seed)
        assert_same(got, want)


def test_fast_action_path_equals_the_checked_one():
    env = poc_env.parallel_env("small")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    a = {k: rng.uniform(-1, 1, 3) for k in env.agents}
    variants = [
        a,
        dict(reversed(list(a.items()))),
        {k: list(v) for k, v in a.items()},
        {k: v.astype(np.float32) for k, v in a.items()},
        {k: np.int64([1, 0, -1]) for k in a},
    ]
    for acts in variants:
        assert_close(env._actions_array(acts), env._actions_array_checked(acts))
    env.agents = env.agents[1:]  # a finished agent: zeros in its row
    acts = {k: a[k] for k in env.agents}
    assert_close(env._actions_array(acts), env._actions_array_checked(acts))
    bad = [
        {**acts, "uav_1": np.array([np.nan, 0, 0])},
        {**acts, "uav_1": np.zeros((3, 1))},
        {**acts, "uav_1": np.zeros(4)},
        {k: np.zeros(3) for k in ["uav_0", *env.agents[1:]]},  # a finished one instead
        {**acts, "uav_9": np.zeros(3)},
    ]
    for acts in bad:
        with pytest.raises(ConfigError) as fast:
            env._actions_array(acts)
        with pytest.raises(ConfigError) as checked:
            env._actions_array_checked(acts)
        assert str(fast.value) == str(checked.value)


def _project_modules():
    root = Path(poc_env.__file__).resolve().parents[1]
    for pkg in ("poc_env", "agents"):  # agents/ is the sub-package poc_env.agents
        for f in sorted((root / pkg).rglob("*.py")):
            parts = f.relative_to(root).with_suffix("").parts
            parts = ("poc_env", *parts) if pkg == "agents" else parts
            yield ".".join(parts[:-1] if parts[-1] == "__init__" else parts), f


def _is_kernel_module(name: str) -> bool:
    """The kernel modules: the package ``poc_env._kernels`` and every module named ``_kernels``
    or inside a ``_kernels`` package (the planner's ``poc_env.agents.planning._kernels``)."""
    return "_kernels" in name.split(".")


def kernel_modules() -> list[tuple[str, Path]]:
    return [(name, path) for name, path in _project_modules() if _is_kernel_module(name)]


#: What a kernel module may import: the standard library's math helpers, numpy, numba and
#: llvmlite (numba's code generator). Nothing of the project, nor any relative import.
KERNEL_IMPORTS = frozenset({"__future__", "math", "functools", "numpy", "numba", "llvmlite"})


def cache_rule_violations(path: Path) -> list[str]:
    """Imports of ``path`` that break the cache rule of :mod:`poc_env._kernels`: a kernel module
    imports nothing but :data:`KERNEL_IMPORTS`, so every compiled function it calls, every
    constant it freezes and its compile options are in its own file (``line: import``)."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            mods = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mods = ["." * node.level + (node.module or "")]
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "__import__":
            mods = ["__import__(...)"]
        else:
            continue
        bad += [f"{node.lineno}: {m}" for m in mods if m.split(".")[0] not in KERNEL_IMPORTS]
    return bad


def foreign_compiled_calls(module) -> list[str]:
    """Compiled functions of ``module`` that reach a compiled function (a numba dispatcher,
    ufunc or intrinsic) defined in another file through their globals."""
    from numba.core.extending import _Intrinsic

    def source(obj) -> Path:
        fn = getattr(obj, "py_func", None) or getattr(obj, "_defn", None) or obj
        return Path(inspect.getsourcefile(fn) or "").resolve()

    def names(code) -> set[str]:
        out = set(code.co_names)
        for const in code.co_consts:
            if inspect.iscode(const):
                out |= names(const)
        return out

    own = Path(module.__file__).resolve()
    bad = []
    for name, value in vars(module).items():
        if not isinstance(value, Dispatcher):
            continue
        for used in sorted(names(value.py_func.__code__)):
            target = value.py_func.__globals__.get(used)
            if isinstance(target, (Dispatcher, _Intrinsic)) and source(target) != own:
                bad.append(f"{module.__name__}.{name} calls {used} of {source(target).name}")
    return bad


@pytest.mark.parametrize("name,path", kernel_modules(), ids=[m for m, _ in kernel_modules()])
def test_kernel_modules_import_nothing_of_the_project(name, path):
    """The cache rule (:mod:`poc_env._kernels`), read from the source: a kernel module imports
    only the standard library's math helpers, numpy, numba and llvmlite."""
    bad = cache_rule_violations(path)
    assert not bad, f"{name} breaks the cache rule of poc_env._kernels: {bad}"


def test_cache_rule_catches_a_call_into_another_kernel_module(tmp_path):
    """The checkers themselves: a kernel that imports and calls another module's compiled
    function is reported, from the source and from the loaded module."""
    src = tmp_path / "bad_kernels.py"
    src.write_text(
        "from numba import njit\n"
        "from poc_env._kernels.swarm import in_range\n"
        "from . import sensing\n"
        "\n"
        "\n"
        "@njit(cache=False)\n"
        "def adjacency(dist, range_m, act, out):\n"
        "    in_range(dist, range_m, act, out)\n",
        encoding="utf-8",
    )
    assert cache_rule_violations(src) == ["2: poc_env._kernels.swarm", "3: ."]
    spec = importlib.util.spec_from_file_location("bad_kernels", src)
    module = importlib.util.module_from_spec(spec)
    code = src.read_text(encoding="utf-8").replace("from . import sensing\n", "")
    exec(compile(code, str(src), "exec"), module.__dict__)
    assert foreign_compiled_calls(module) == ["bad_kernels.adjacency calls in_range of swarm.py"]


@pytest.mark.parametrize("name", [m for m, _ in kernel_modules()])
def test_compiled_functions_call_only_their_own_module(name):
    """The loaded kernels: every dispatcher of a kernel module is defined in its file, and the
    compiled functions it calls through its globals too (no closures: the old source-hash key)."""
    module = importlib.import_module(name)
    own = Path(module.__file__).resolve()
    for value in vars(module).values():
        if isinstance(value, Dispatcher):
            assert Path(inspect.getsourcefile(value.py_func) or "").resolve() == own, value
            assert value.py_func.__closure__ is None, value
    assert not foreign_compiled_calls(module)


def test_compiled_code_lives_only_in_kernel_modules():
    """No other module imports numba or llvmlite, and every numba dispatcher reachable from the
    library modules that call kernels comes from a kernel module."""
    callers = []
    for name, path in _project_modules():
        if _is_kernel_module(name):
            continue
        text = path.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            mods = []
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                mods = [node.module or ""]
            assert not any(m.split(".")[0] in ("numba", "llvmlite") for m in mods), (
                f"{name} imports numba: compiled code belongs in a kernel module (poc_env._kernels)"
            )
        if "_kernels" in text:
            callers.append(name)
    assert len(callers) >= 8  # the walk found the callers
    kernel_files = {path.resolve() for _, path in kernel_modules()}
    for name in callers:
        module = importlib.import_module(name)
        for value in vars(module).values():
            if isinstance(value, Dispatcher):
                src = Path(inspect.getsourcefile(value.py_func) or "").resolve()
                assert src in kernel_files, f"{name}: {value} compiled outside the kernel modules"


def test_step_constants_are_named_once():
    """The step's constants array: every name of ``STEP_CONSTANTS`` once, no other, read-only."""
    from poc_env._kernels import swarm

    params = sim.make_params(load_scenario("small"))
    c = params.step_constants
    assert c is params.step_constants  # packed once per Params
    assert c.shape == (len(swarm.STEP_CONSTANTS),) and not c.flags.writeable
    assert c[swarm.STEP_CONSTANTS.index("dt_s")] == params.dt
    with pytest.raises(TypeError):
        swarm.step_constants(dt_s=1.0)


# ------------------------------------------------------------ rectangle membership (issue 12)


def _random_rectangles(rng, grid, n_ind, n_uav):
    """Rectangles of every kind: random, on cell edges (centre, sides and angle on the lattice),
    axis-aligned, reaching outside the map, wholly outside it, and copies of earlier ones."""
    x0, y0, x1, y1 = grid.bounds
    h = grid.cell_m
    cx = rng.uniform(x0 - 3 * h, x1 + 3 * h, (n_ind, n_uav))
    cy = rng.uniform(y0 - 3 * h, y1 + 3 * h, (n_ind, n_uav))
    ln = rng.uniform(0.2 * h, 9 * h, (n_ind, n_uav))
    wd = rng.uniform(0.2 * h, 9 * h, (n_ind, n_uav))
    th = rng.uniform(0.0, np.pi, (n_ind, n_uav))
    kind = rng.integers(0, 5, (n_ind, n_uav))
    edge = kind == 1  # centre on a cell corner, sides whole numbers of cells, axis-aligned
    cx[edge] = x0 + h * rng.integers(0, grid.nx + 1, edge.sum())
    cy[edge] = y0 + h * rng.integers(0, grid.ny + 1, edge.sum())
    ln[edge] = 2 * h * rng.integers(1, 5, edge.sum())
    wd[edge] = 2 * h * rng.integers(1, 5, edge.sum())
    th[edge] = rng.choice([0.0, 0.5 * np.pi, np.pi], edge.sum())
    th[kind == 2] = rng.choice([0.0, 0.25 * np.pi, 0.5 * np.pi], (kind == 2).sum())
    far = kind == 3  # wholly outside the map
    cx[far] = x1 + 20 * h
    copy_ = np.zeros_like(edge)
    copy_[:, 1:] = kind[:, 1:] == 4  # a copy of the UAV before it
    for k in range(1, n_uav):
        m = copy_[:, k]
        for arr in (cx, cy, ln, wd, th):
            arr[m, k] = arr[m, k - 1]
    return np.stack([cx, cy], axis=-1), ln, wd, th


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rectangle_membership_kernel_matches_shapely(seed):
    """The membership kernel (with its wholly-inside column runs) against exact shapely areas:
    every cell's fraction, plain and exclusive (§3.1.6), to 1e-9 of a cell, and the weighted
    masses of the sparse path (no dense array) equal the dense fractions times the weights."""
    import shapely

    from poc_env.geometry import rectangle_polygon
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.regions import area_fractions, exclusive_fractions, rectangle_mass

    grid = Grid.from_config(load_scenario("paper_6_2").map)
    rng = np.random.default_rng(seed)
    center, ln, wd, th = _random_rectangles(rng, grid, 12, 4)
    boxes = np.array(grid.cell_boxes(), dtype=object)
    plain = area_fractions(grid, center, ln, wd, th)
    excl = exclusive_fractions(grid, center, ln, wd, th)
    weights = rng.random(grid.shape)
    for p in range(center.shape[0]):
        earlier = []
        for k in range(center.shape[1]):
            rect = rectangle_polygon(center[p, k], ln[p, k], wd[p, k], th[p, k])
            own = rect.difference(shapely.union_all(earlier)) if earlier else rect
            earlier.append(rect)
            ref_plain = shapely.area(shapely.intersection(rect, boxes)).reshape(grid.shape)
            ref_excl = shapely.area(shapely.intersection(own, boxes)).reshape(grid.shape)
            area = grid.cell_area_m2
            np.testing.assert_allclose(plain[p, k], ref_plain / area, rtol=0, atol=1e-9)
            np.testing.assert_allclose(excl[p, k], ref_excl / area, rtol=0, atol=1e-9)
    for exclusive, dense in ((False, plain), (True, excl)):
        mass = rectangle_mass(grid, center, ln, wd, th, exclusive=exclusive, weights=weights)
        np.testing.assert_allclose(mass, np.sum(dense * weights, axis=(-2, -1)), rtol=1e-12)


def ref_compass(params, raster, vector, k):
    """The compass features in plain numpy (the formulation the kernel replaced)."""
    from poc_env.sim.observations import (
        FEATURES,
        N_IDS,
        N_RINGS,
        N_SECTORS,
        OTHERS_RADIUS_M,
        RASTER_INDEX,
        RING_EDGES_M,
        VECTOR_SIZE,
        decode_vector,
    )  # fmt: skip

    raster = np.asarray(raster, dtype=np.float32)
    vector = np.asarray(vector, dtype=np.float32)
    b = vector.shape[0]
    out = np.zeros((b, FEATURES), dtype=np.float32)
    out[:, :VECTOR_SIZE] = vector
    centers = params.grid.centers.reshape(-1, 2).astype(float)
    xy = decode_vector(params, vector)["xy"]
    d = centers[None, :, :] - xy[:, None, :]
    dist = np.hypot(d[..., 0], d[..., 1])
    ang = np.arctan2(d[..., 1], d[..., 0])
    sector = np.floor((ang + np.pi) / (2 * np.pi) * N_SECTORS).astype(np.int64) % N_SECTORS
    sector = (sector + N_SECTORS // 2) % N_SECTORS
    ring = np.searchsorted(np.asarray(RING_EDGES_M), dist, side="right")
    rows = np.arange(b)[:, None]
    poc = raster[:, RASTER_INDEX["poc"]].reshape(b, -1).astype(float)
    total = poc.sum(axis=1)
    mass = np.bincount(
        (rows * (N_SECTORS * N_RINGS) + sector * N_RINGS + ring).ravel(),
        weights=poc.ravel(),
        minlength=b * N_SECTORS * N_RINGS,
    ).reshape(b, -1)
    share = np.divide(mass, total[:, None], out=np.zeros_like(mass), where=total[:, None] > 0)
    out[:, VECTOR_SIZE : VECTOR_SIZE + N_SECTORS * N_RINGS] = share
    others = raster[:, RASTER_INDEX["others"]].reshape(b, -1).astype(float)
    others *= dist <= OTHERS_RADIUS_M
    count = np.bincount(
        (rows * N_SECTORS + sector).ravel(), weights=others.ravel(), minlength=b * N_SECTORS
    ).reshape(b, -1)
    k0 = VECTOR_SIZE + N_SECTORS * N_RINGS
    out[:, k0 : k0 + N_SECTORS] = np.minimum(count / max(params.n_agents - 1, 1), 1.0)
    out[:, k0 + N_SECTORS] = poc.mean(axis=1)
    out[np.arange(b), k0 + N_SECTORS + 1 + np.asarray(k) % N_IDS] = 1.0
    return out


@pytest.mark.parametrize("name", ["small", "paper_6_2"])
def test_compass_kernel_equals_numpy_bit_for_bit(name):
    """The compiled compass sums give the numpy formulation's features exactly (so tasks keep
    their version): UAVs inside and outside the grid, on cell centres (angle ties) and on
    sector boundaries, with a belief partly searched."""
    params = sim.make_params(load_scenario(name))
    rng = np.random.default_rng(7)
    feats = obs.CompassFeatures(params)
    hazard = obs.hazard_mask(params)
    for trial in range(6):
        st = sim.initial(params, [np.random.default_rng(trial + k) for k in range(3)])
        x0, y0, x1, y1 = params.grid.bounds
        st.pos[..., 0] = rng.uniform(x0 - 30e3, x1 + 30e3, st.pos.shape[:2])
        st.pos[..., 1] = rng.uniform(y0 - 30e3, y1 + 30e3, st.pos.shape[:2])
        if trial % 2:  # exactly on cell centres: neighbours at 0, 45, 90 ... degrees
            c = params.grid.centers.reshape(-1, 2)
            st.pos[..., :2] = c[rng.integers(0, len(c), st.pos.shape[:2])]
        st.belief *= rng.random(st.belief.shape)
        ras = obs.rasters(params, st, np.ones(3), hazard)
        vec = obs.vectors(params, st)
        m = ras.shape[0] * ras.shape[1]
        r2, v2 = ras.reshape(m, *ras.shape[2:]), vec.reshape(m, -1)
        k = np.arange(m) % params.n_agents
        np.testing.assert_array_equal(feats(r2, v2, k), ref_compass(params, r2, v2, k))


def test_compass_bins_on_boundaries_equal_the_defining_formula():
    """Cells exactly on sector boundaries (axes, diagonals), exactly at ring edges and at the
    others radius, and next to them: the kernel's comparisons agree with arctan2/hypot."""
    from poc_env.sim.observations import N_RINGS, N_SECTORS, OTHERS_RADIUS_M, RING_EDGES_M

    rng = np.random.default_rng(3)
    px, py = np.array([1234.5, -7e3]), np.array([-42.0, 5e3])
    offs = []
    for d in (*RING_EDGES_M, OTHERS_RADIUS_M, 5e3, 1.0):
        for ux, uy in ((1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, 1), (-1, -1), (1, -1)):
            offs.append((ux * d, uy * d))
            offs.append((ux * d * (1 + 1e-12), uy * d))
    offs += [tuple(v) for v in rng.normal(0, 30e3, (200, 2))]
    offs.append((0.0, 0.0))
    off = np.array(offs)
    cx, cy = px[0] + off[:, 0], py[0] + off[:, 1]
    poc, others = rng.random((2, len(cx))), rng.random((2, len(cx)))
    edges = np.asarray(RING_EDGES_M, dtype=float)
    mass, count = obs_kernels.compass_bins(
        cx, cy, px, py, poc, others, edges, float(OTHERS_RADIUS_M), N_SECTORS
    )
    for i in range(2):
        dx, dy = cx - px[i], cy - py[i]
        dist = np.hypot(dx, dy)
        sector = np.floor((np.arctan2(dy, dx) + np.pi) / (2 * np.pi) * N_SECTORS).astype(int)
        sector = (sector % N_SECTORS + N_SECTORS // 2) % N_SECTORS
        ring = np.searchsorted(edges, dist, side="right")
        want_m = np.bincount(sector * N_RINGS + ring, poc[i], N_SECTORS * N_RINGS)
        want_c = np.bincount(sector, others[i] * (dist <= OTHERS_RADIUS_M), N_SECTORS)
        np.testing.assert_array_equal(mass[i], want_m)
        np.testing.assert_array_equal(count[i], want_c)


def _compass_positions(rng, cx, cy, n_random):
    """UAV positions for the compass kernel's pins: at random over and around the grid, and
    on cell centres, on the axes and diagonals through them, at the ring edges and the others
    radius from a cell centre along the axes, the diagonals and Pythagorean directions (where
    ``dx^2 + dy^2`` rounds but ``hypot`` is exact), each also 1e-12 off."""
    from poc_env.sim.observations import OTHERS_RADIUS_M, RING_EDGES_M

    lo, hi = min(cx.min(), cy.min()) - 40e3, max(cx.max(), cy.max()) + 40e3
    px, py = list(rng.uniform(lo, hi, n_random)), list(rng.uniform(lo, hi, n_random))
    dirs = ((1, 0), (0, 1), (1, 1), (-1, 1), (0.6, 0.8), (-0.8, 0.6), (5 / 13, -12 / 13),
            (-8 / 17, -15 / 17))  # fmt: skip
    for d in (*RING_EDGES_M, OTHERS_RADIUS_M, 5000.0, 0.0):
        for eps in (0.0, 1e-12, -1e-12):
            for ux, uy in dirs:
                j = rng.integers(0, len(cx))
                px.append(cx[j] + ux * d * (1 + eps))
                py.append(cy[j] + uy * d * (1 + eps))
    return np.array(px), np.array(py)


@pytest.mark.parametrize("n_sectors", [8, 6])
@pytest.mark.parametrize(("nx", "ny"), [(8, 8), (40, 30)])
def test_compass_cell_bins_and_sums_equal_the_cell_by_cell_kernel_bit_for_bit(n_sectors, nx, ny):
    """The compass kernel's sums (``_cell_bins``: each cell's bin in a branch-free pass, the
    cells next to a boundary decided by ``_classify``; then ``_bin_sums``: three UAVs' sums of
    a shared row interleaved, each bin summed in cell order) equal the cell-by-cell kernel
    (``compass_bins``) bit for bit, on Small's 8 x 8 grid and Paper62's 40 x 30: UAVs at random
    and on the boundary positions of :func:`_compass_positions`, float32 POC over 13 orders of
    magnitude (a sum in another order rounds differently) with zeros, ties and -0.0, groups of
    one, two and three UAVs (padded by a spare), and sectors other than octants (every cell by
    the defining formula)."""
    from poc_env.sim.observations import OTHERS_RADIUS_M, RING_EDGES_M

    xs = np.arange(nx) * 5000.0 + 2500.0
    ys = np.arange(ny) * 5000.0 + 2500.0
    cx, cy = np.tile(xs, ny), np.repeat(ys, nx)
    n_cells = nx * ny
    rng = np.random.default_rng(5 + nx)
    px, py = _compass_positions(rng, cx, cy, 120 if nx < 16 else 30)
    poc = rng.random((len(px), n_cells)) * 10.0 ** rng.integers(-12, 1, (len(px), n_cells))
    poc[rng.random(poc.shape) < 0.3] = 0.0
    poc[:, 5] = -0.0
    poc[::7, :] = 0.25  # equal values
    poc = poc.astype(np.float32)  # what the kernel sums: raster channel 0
    edges = np.asarray(RING_EDGES_M, dtype=float)
    radius = float(OTHERS_RADIUS_M)
    n_bins = n_sectors * (len(edges) + 1)
    spare_bins = np.zeros(n_cells, dtype=np.intp)
    for group in (1, 2, 3):
        for start in range(0, len(px) - group + 1, group):
            k = np.arange(start, start + group)
            row = poc[start]
            want, _c = obs_kernels.compass_bins(
                cx, cy, px[k], py[k], np.tile(row.astype(float), (group, 1)),
                np.zeros((group, n_cells)), edges, radius, n_sectors,
            )  # fmt: skip
            mass = np.zeros((4, n_bins + 1))  # row 3, column n_bins: the spares
            bins = np.full((3, n_cells), -7, dtype=np.intp)
            obs_kernels._cell_bins(cx, cy, px, py, start, group, edges, radius, n_sectors, bins)
            b = [bins[u] if u < group else spare_bins for u in range(3)]
            m = [mass[u] if u < group else mass[3] for u in range(3)]
            obs_kernels._bin_sums(row, *b, *m, n_bins)
            np.testing.assert_array_equal(
                mass[:group, :n_bins], want, err_msg=f"UAVs {k} at {px[k]}, {py[k]}"
            )


@pytest.mark.parametrize("seed", [0, 1])
def test_boundary_masses_equal_the_dense_fractions_and_shapely(seed):
    """``rectangle_masses`` (Green's theorem on the row-wise cumulative weights, no per-cell
    areas) against the dense fractions times the weights and against shapely, plain and
    exclusive (§3.1.6), to 1e-12 of the rectangle's plain mass: random rectangles, ones on
    cell edges, axis-aligned, reaching outside or wholly outside the map, copies of the UAV
    before, tiny (sides of 0.01-0.05 cell) and huge (sides up to 4 times the map)."""
    import shapely

    from poc_env.geometry import rectangle_polygon
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.regions import area_fractions, boundary_mass, exclusive_fractions

    grid = Grid.from_config(load_scenario("paper_6_2").map)
    h = grid.cell_m
    rng = np.random.default_rng(100 + seed)
    center, ln, wd, th = _random_rectangles(rng, grid, 16, 5)
    size = rng.integers(0, 4, ln.shape)  # 1 tiny, 2 huge, else as drawn
    size[:, 1:][np.all(center[:, 1:] == center[:, :-1], axis=-1)] = 0  # keep copies copies
    tiny, huge = size == 1, size == 2
    ln[tiny] = h * rng.uniform(0.01, 0.05, tiny.sum())
    wd[tiny] = h * rng.uniform(0.01, 0.05, tiny.sum())
    ln[huge] = h * rng.uniform(20, 160, huge.sum())
    wd[huge] = h * rng.uniform(20, 160, huge.sum())
    weights = rng.random(grid.shape)
    weights[rng.random(grid.shape) < 0.2] = 0.0
    plain = np.sum(area_fractions(grid, center, ln, wd, th) * weights, axis=(-2, -1))
    excl = np.sum(exclusive_fractions(grid, center, ln, wd, th) * weights, axis=(-2, -1))
    assert np.any(excl < plain - 0.01 * plain.max())  # overlaps (and copies) are present
    assert np.any(plain == 0) and np.any(huge & (plain > 0)) and np.any(tiny & (plain > 0))
    new_plain = boundary_mass(grid, center, ln, wd, th, weights, exclusive=False)
    new_excl = boundary_mass(grid, center, ln, wd, th, weights, exclusive=True)
    assert np.all(np.abs(new_plain - plain) <= 1e-12 * plain)
    assert np.all(np.abs(new_excl - excl) <= 1e-12 * plain)
    boxes = np.array(grid.cell_boxes(), dtype=object)
    for p in range(center.shape[0]):
        earlier = []
        for k in range(center.shape[1]):
            rect = rectangle_polygon(center[p, k], ln[p, k], wd[p, k], th[p, k])
            own = rect.difference(shapely.union_all(earlier)) if earlier else rect
            earlier.append(rect)
            # shapely works in metres about the map's origin: its own rounding of a tiny
            # rectangle's corners is about 1e-12 of its mass, so a looser bound there
            tol = (1e-10 if tiny[p, k] else 1e-12) * plain[p, k]
            for geom, got in ((rect, new_plain[p, k]), (own, new_excl[p, k])):
                ref = np.sum(shapely.area(shapely.intersection(geom, boxes)) * weights.ravel())
                assert abs(got - ref / grid.cell_area_m2) <= tol, (p, k)
    with pytest.raises(ConfigError):
        boundary_mass(grid, center, ln, wd, th, weights[:-1], exclusive=True)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_boundary_masses_dense_fallback_equals_inclusion_exclusion(seed):
    """Many overlapping rectangles (issue 24: 42 UAVs from one airfield took minutes):
    ``rectangle_masses``' per-cell fallback (forced with ``max_overlap=0``) gives the
    inclusion-exclusion numbers (forced with a limit above the rectangle count) to 1e-12 of
    the plain mass, on random small clusters where both apply; beyond the default limit the
    fallback is what runs (the default equals the forced fallback bit for bit)."""
    from poc_env._kernels.rectangles import MAX_TERMS_OVERLAP
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.regions import boundary_mass

    grid = Grid.from_config(load_scenario("small").map)
    h = grid.cell_m
    rng = np.random.default_rng(300 + seed)
    n_uav = 9
    centre = np.array([grid.bounds[0] + 4 * h, grid.bounds[1] + 4 * h])
    center = centre + rng.normal(0, 0.6 * h, (4, n_uav, 2))
    ln = h * rng.uniform(0.5, 5, (4, n_uav))
    wd = h * rng.uniform(0.5, 5, (4, n_uav))
    th = rng.uniform(0, np.pi, (4, n_uav))
    center[:, 3] = center[:, 2]  # a copy of the rectangle before
    ln[:, 3], wd[:, 3], th[:, 3] = ln[:, 2], wd[:, 2], th[:, 2]
    weights = rng.random(grid.shape)
    plain = boundary_mass(grid, center, ln, wd, th, weights, exclusive=False)
    terms = boundary_mass(grid, center, ln, wd, th, weights, exclusive=True, max_overlap=64)
    dense = boundary_mass(grid, center, ln, wd, th, weights, exclusive=True, max_overlap=0)
    assert np.any(terms < plain - 0.1 * plain.max())  # they do overlap
    assert np.all(np.abs(dense - terms) <= 1e-12 * plain)
    # a cluster larger than the default limit: the fallback runs (bit for bit), and quickly
    many = MAX_TERMS_OVERLAP + 30
    center = centre + rng.normal(0, 0.3 * h, (1, many, 2))
    ln = h * rng.uniform(3, 6, (1, many))
    wd = h * rng.uniform(3, 6, (1, many))
    th = rng.uniform(0, np.pi, (1, many))
    default = boundary_mass(grid, center, ln, wd, th, weights, exclusive=True)
    dense = boundary_mass(grid, center, ln, wd, th, weights, exclusive=True, max_overlap=0)
    np.testing.assert_array_equal(default, dense)
    # and it is right: the exclusive masses add up to the union's mass (shapely)
    import shapely

    from poc_env.geometry import rectangle_polygon

    union = shapely.union_all(
        [rectangle_polygon(center[0, k], ln[0, k], wd[0, k], th[0, k]) for k in range(many)]
    )
    boxes = np.array(grid.cell_boxes(), dtype=object)
    ref = np.sum(shapely.area(shapely.intersection(union, boxes)) * weights.ravel())
    assert default.sum() == pytest.approx(ref / grid.cell_area_m2, rel=1e-9)


@pytest.mark.parametrize(
    ("name", "sharing"), [("small", "global"), ("paper_6_2", "global"), ("small", "comms")]
)
def test_compass_of_state_equals_the_features_of_the_rasters_bit_for_bit(name, sharing):
    """The batched compass (from each env's coarse POC and the positions, no rasters) equals
    the features of the raster and vector observations exactly: UAVs inside and outside the
    grid, several in one cell, on cell centres, landed, with and without the agent index, and
    each UAV's own belief under belief_sharing "comms"; for the kernel's row walk, UAVs placed
    so that diagonals, ring edges and the others radius pass through cell centres (rows on or
    tangent to a ring)."""
    params = sim.make_params(load_scenario(name, {"comms.belief_sharing": sharing}))
    rng = np.random.default_rng(11)
    hazard = obs.hazard_mask(params)
    for trial in range(8):
        rngs = [np.random.default_rng(trial + k) for k in range(3)]
        st = sim.initial(params, rngs)
        if sharing == "comms":  # the UAVs' beliefs part
            st.pos[:, :, :2] = params.grid.centers.reshape(-1, 2)[: params.n_agents]
            for _ in range(3):
                sim.step(params, st, np.zeros((3, params.n_agents, 3)), rngs)
        x0, y0, x1, y1 = params.grid.bounds
        st.pos[..., 0] = rng.uniform(x0 - 30e3, x1 + 30e3, st.pos.shape[:2])
        st.pos[..., 1] = rng.uniform(y0 - 30e3, y1 + 30e3, st.pos.shape[:2])
        if trial % 2:  # on a few cell centres: shared cells, angle ties
            c = params.grid.centers.reshape(-1, 2)[:4]
            st.pos[..., :2] = c[rng.integers(0, len(c), st.pos.shape[:2])]
        if trial % 4 == 3:
            st.flying[:, 0] = False
        if trial >= 4:  # boundaries through cell centres: diagonals, ring edges, tangent rows
            c = params.grid.centers.reshape(-1, 2)
            pick = c[rng.integers(0, len(c), st.pos.shape[:2])]
            d = np.array([*obs.RING_EDGES_M, obs.OTHERS_RADIUS_M])[
                rng.integers(0, 4, st.pos.shape[:2])
            ]
            shift = [(d, d), (d, 0 * d), (0 * d, d), (-d, 0.5 * d)][trial - 4]
            st.pos[..., 0] = pick[..., 0] + shift[0]
            st.pos[..., 1] = pick[..., 1] + shift[1]
        st.belief *= rng.random(st.belief.shape)
        scale = rng.uniform(0.5, 2.0, 3)
        ras = obs.rasters(params, st, scale, hazard)
        vec = obs.vectors(params, st)
        m = ras.shape[0] * ras.shape[1]
        k = np.arange(m) % params.n_agents
        for index in (True, False):
            feats = obs.CompassFeatures(params, index)
            want = feats(ras.reshape(m, *ras.shape[2:]), vec.reshape(m, -1), k)
            got = obs.observe(params, st, scale, hazard, "compass", feats)
            np.testing.assert_array_equal(got.reshape(m, -1), want)


@pytest.mark.parametrize("s", [1, 2, 3, 4, 5, 7])
def test_coarse_poc_is_numpys_coarsening_bit_for_bit(s):
    """Raster channel 0 from the kernel's own sub-cell sums (s < 8; cell by cell for s = 2 and 4)
    is the float32 of ``Grid.coarsen`` / scale clipped to [0, 1], bit for bit (what the
    recorded episodes saw), on a belief with partly searched, zero and tiny cells."""
    params = sim.make_params(
        load_scenario("small", {"sensor.samples_per_cell": s, "map.cell_km": 5})
    )
    rng = np.random.default_rng(40 + s)
    st = _obs_state(params, rng)
    st.belief *= rng.random(st.belief.shape) ** 3
    st.belief[:, :s, :] = 0.0
    st.belief[:, -1, :] *= 1e-300
    scale = np.array([0.01, 0.3])
    want = np.clip(params.grid.coarsen(st.belief, s) / scale[:, None, None], 0.0, 1.0)
    got = obs.coarse_poc(params, st, scale)[:, 0]
    np.testing.assert_array_equal(got, want.astype(np.float32))
    sums, poc = np.empty(params.grid.shape), np.empty(params.grid.shape, dtype=np.float32)
    for e in range(2):  # the float64 sums themselves (the kernel's scratch)
        obs_kernels._coarse_poc(st.belief, e, s, obs._NO_COARSE, True, scale[e], sums, poc)
        np.testing.assert_array_equal(sums, params.grid.coarsen(st.belief[e], s))
    np.testing.assert_array_equal(
        obs.rasters(params, st, scale, obs.hazard_mask(params))[:, 0, 0], got
    )


def test_np_sum_is_numpys_sum_bit_for_bit():
    """The compass kernel's totals (``np_sum``) are numpy's float64 sums exactly: lengths 1 to
    300 (one running sum below 8, eight up to 128, halves above), values over 15 orders of
    magnitude (any other order of additions rounds differently), zeros and -0.0."""
    rng = np.random.default_rng(26)
    for n in [*range(1, 40), 63, 64, 65, 127, 128, 129, 136, 200, 255, 256, 300]:
        for _ in range(5):
            a = rng.random(n) * 10.0 ** rng.integers(-12, 3, n)
            a[rng.random(n) < 0.2] = 0.0
            if n > 2:
                a[1] = -0.0
            a = a.astype(np.float32).astype(float)  # what the kernel sums: float32 POC
            assert obs_kernels.np_sum(a) == a.sum(), n
            assert np.signbit(obs_kernels.np_sum(a)) == np.signbit(a.sum())
    assert np.signbit(obs_kernels.np_sum(np.array([-0.0])))  # numpy: -0.0 + -0.0


def test_vectors_reuse_sines_only_of_the_same_headings():
    """``observations.vectors`` reuses the last large call's sines and cosines only when the
    headings are the same bits: headings written in place since (one UAV turned, a zero's
    sign flipped, a NaN), a new array of other values and a batch of another shape each give
    the vectors of their own headings (numpy's ``sin``/``cos`` of them)."""
    params = sim.make_params(load_scenario("small"))
    rng = np.random.default_rng(6)
    st = sim.initial(params, [np.random.default_rng(k) for k in range(120)])  # 360 UAVs
    st.heading = rng.uniform(-np.pi, np.pi, st.heading.shape)

    def expected(state):
        n = state.flying.shape[1]
        out = np.empty((*state.flying.shape, obs.VECTOR_SIZE), np.float32)
        h = state.heading
        obs_kernels.vectors_of(
            state.pos, state.speed, np.sin(h), np.cos(h), state.pitch, state.elapsed,
            state.flying, state.step, params.landing, *obs._vector_constants(params, n), out,
        )  # fmt: skip
        return out

    def check(state):
        got = obs.vectors(params, state)
        np.testing.assert_array_equal(got.view(np.int32), expected(state).view(np.int32))

    check(st)
    check(st)  # the same headings: reused
    st.heading[3, 1] += 1e-12  # written in place
    check(st)
    st.heading[7, 0] = 0.0
    check(st)
    st.heading[7, 0] = -0.0  # equal as numbers, not as bits: sin(-0.0) is -0.0
    check(st)
    st.heading[9, 2] = np.nan
    check(st)
    st.heading = rng.uniform(-np.pi, np.pi, st.heading.shape)  # a new array
    check(st)
    small = sim.initial(params, [np.random.default_rng(k) for k in range(100)])  # 300 UAVs
    check(small)
    check(st)
