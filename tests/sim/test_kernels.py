"""The compiled single-env fast paths against the numpy code they replaced, bit for bit.

The references below are the numpy implementations as they were before the kernels (pairwise
distances, eq. 20, 21 and 24 checks, the auto topology, observations, the simulator step and
the PettingZoo wrapper); they live only here. Every comparison is exact (``tobytes``), on many
seeded random configurations, including ties, inactive UAVs and non-finite values.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import poc_env
from poc_env.config import load_scenario
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.errors import ConfigError
from poc_env.sim import comms, constraints
from poc_env.sim import core as sim
from poc_env.sim import observations as obs
from poc_env.sim.rewards import reward_terms, total_reward
from poc_env.theory import search_theory

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


def ref_update_topology(params, state, rngs):
    cc = params.scenario.comms
    xy = state.pos[:, :, :2]
    adj = ref_in_range(xy, cc.range_m, state.flying)
    if cc.link_failure_prob > 0:
        adj = np.stack(
            [comms.link_failures(adj[k], cc.link_failure_prob, r) for k, r in enumerate(rngs)]
        )
    if params.switcher is not None:
        topo = params.switcher.switch(state.topology, adj, xy, state.flying)
        state.topology = np.asarray(topo.topology)
        links, connected = topo.links, topo.connected
    else:
        links, connected, _ = ref_auto_topology(adj, xy, state.flying, cc.min_neighbours)
    state.links = links
    return connected


def ref_step(params, state, actions, rngs):
    """simulator.step as a sequence of numpy calls (before the step kernel)."""
    sc = params.scenario
    u = sc.uav
    ep = sc.episode
    moving = state.flying.copy()
    dv, dalpha, dbeta = sim.scale_actions(params, np.asarray(actions, dtype=float))
    shielded = np.zeros_like(moving)
    if sc.constraints.violation == "shield":
        res = constraints.shield_heading(
            state.pos[..., :2],
            state.heading,
            state.speed * np.cos(state.pitch),
            params.dt,
            dalpha,
            u.max_turn_rate_rad_s * params.dt,
            zones=params.zones if len(params.zones) else None,
            bounds=params.bounds,
            d_s=sc.constraints.safety_distance_m,
            active=moving,
            threat=(params.threat_centers, params.threat_lambdas, sc.map.threat_threshold)
            if len(params.threat_lambdas)
            else None,
        )
        shielded = res.shielded & moving
        dalpha = np.where(moving, res.turn, dalpha)
    a2 = state.pos[..., :2].copy()
    new = sim.kinematics(params, state, dv, dalpha, dbeta, moving)
    b2 = new[..., :2]
    found = sim.sense(params, state, a2, b2)
    state.pos = new
    state.agent_pos += found
    team = found.sum(axis=1)
    state.posc += team
    p_t = search_theory.segment_pod(
        state.target[:, None, :],
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
        state.target_exponent += -np.log1p(-p_t).sum(axis=1)
    detected_now = ~state.detected & (state.target_exponent >= state.target_threshold)
    state.detected |= detected_now
    state.detect_step = np.where(detected_now, state.step + 1, state.detect_step)
    state.elapsed += np.where(moving, params.dt, 0.0)
    usable = u.usable_endurance_s
    overtime = moving & (state.elapsed > usable)
    time_term = np.where(moving, params.dt / usable, 0.0)
    xy = state.pos[..., :2]
    oob = moving & ref_outside_boundary(xy, params.bounds)
    nofly = moving & params.zones.segment_crosses(a2, b2) if len(params.zones) else oob & False
    collision, _ = ref_separation_violations(xy, sc.constraints.safety_distance_m, moving)
    collision &= moving
    if len(params.threat_lambdas):
        threat = moving & constraints.threat_violation(
            xy, params.threat_centers, params.threat_lambdas, sc.map.threat_threshold
        )
    else:
        threat = np.zeros_like(moving)
    adj = ref_in_range(xy, sc.comms.range_m, moving)
    comms_ok = ref_two_neighbour_ok(adj, sc.comms.min_neighbours, moving) | ~moving
    events = sim.Events(
        pos_agent=found,
        pos_team=team,
        time_term=time_term,
        overtime=overtime,
        out_of_bounds=oob,
        no_fly=nofly,
        collision=collision,
        threat=threat,
        comms_ok=comms_ok,
        shielded=shielded,
        landed_now=np.zeros_like(moving),
        crashed_now=np.zeros_like(moving),
        detected_now=detected_now,
        connected=np.ones(moving.shape[0], dtype=bool),
    )
    state.violations += events.violation & moving
    dist = np.hypot(*(xy - params.landing[None]).transpose(2, 0, 1))
    state.left_home |= moving & (dist > ep.landing_radius_m)
    landed_now = (
        moving
        & state.left_home
        & (dist <= ep.landing_radius_m)
        & (state.pos[..., 2] <= ep.landing_max_altitude_m)
        & (state.speed <= ep.landing_max_speed_mps)
    )
    crashed_now = (
        moving & ~landed_now & ((state.pos[..., 2] <= 0.0) | (state.elapsed >= u.endurance_s))
    )
    if sc.constraints.violation == "terminate":
        crashed_now |= moving & ~landed_now & (oob | nofly | collision | threat)
    state.landed |= landed_now
    state.crashed |= crashed_now
    state.flying &= ~(landed_now | crashed_now)
    events.landed_now = landed_now
    events.crashed_now = crashed_now
    events.connected = np.asarray(ref_update_topology(params, state, rngs))
    state.step += 1
    return events


class RefEnv(UAVSearchParallelEnv):
    """The PettingZoo wrapper with the per-agent conversions it had before, on ref_step."""

    def _observations(self):
        st = self.sim_state
        vec = ref_vectors(self.params, st)[0]
        ras = ref_rasters(self.params, st, self._poc_scale, self._hazard)[0]
        out = {}
        for a in self.agents:
            i = self._index[a]
            if self.obs_type == "dict":
                out[a] = {"raster": ras[i], "vector": vec[i]}
            else:
                out[a] = np.concatenate([ras[i].ravel(), vec[i]])
        return out

    def _topology_info(self, connected):
        st = self.sim_state
        links = np.argwhere(np.triu(st.links[0]))
        name = None
        if self.params.switcher is not None:
            name = self.params.switcher.name(int(st.topology[0]))
        return {
            "topology": name or "auto",
            "links": [(int(i), int(j)) for i, j in links],
            "connected": connected,
        }

    def step(self, actions):
        arr = self._actions_array_checked(actions)
        st = self.sim_state
        ev = ref_step(self.params, st, arr, [self._rng])
        terms = reward_terms(self.scenario.reward, ev)
        reward = total_reward(terms)[0]
        live = list(self.agents)
        truncated = bool(st.step[0] >= self.params.horizon)
        detected_end = bool(self.scenario.episode.detection_ends_episode and st.detected[0])
        rewards, terminations, truncations, infos = {}, {}, {}, {}
        topo = self._topology_info(bool(ev.connected[0]))
        for a in live:
            i = self._index[a]
            done = bool(st.landed[0, i] or st.crashed[0, i]) or detected_end
            rewards[a] = float(reward[i])
            terminations[a] = done
            truncations[a] = truncated and not done
            infos[a] = {
                "pos": float(ev.pos_agent[0, i]),
                "pos_team": float(ev.pos_team[0]),
                "posc": float(st.posc[0]),
                "reward_terms": {k: float(v[0, i]) for k, v in terms.items()},
                "violations": {
                    "out_of_bounds": bool(ev.out_of_bounds[0, i]),
                    "no_fly": bool(ev.no_fly[0, i]),
                    "collision": bool(ev.collision[0, i]),
                    "threat": bool(ev.threat[0, i]),
                    "comms": not bool(ev.comms_ok[0, i]),
                    "overtime": bool(ev.overtime[0, i]),
                },
                "shielded": bool(ev.shielded[0, i]),
                "landed": bool(st.landed[0, i]),
                "crashed": bool(st.crashed[0, i]),
                "flight_time_s": float(st.elapsed[0, i]),
                "target_detected": bool(st.detected[0]),
                "time_to_detection_s": float(st.detect_step[0] * self.params.dt)
                if st.detected[0]
                else None,
                **topo,
            }
        observations = self._observations_for(live)
        self.agents = [a for a in live if not (terminations[a] or truncations[a])]
        return observations, rewards, terminations, truncations, infos


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
    diff = same(a, b)
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
        assert_same(constraints.pairwise_distances(xy), ref_pairwise_distances(xy))
        assert_same(constraints.pairwise_distances(xy[0]), ref_pairwise_distances(xy[0]))
        b = (0.0, -10.0, 100.0, 90.0)
        assert_same(constraints.outside_boundary(xy, b), ref_outside_boundary(xy, b))
        d_s, rc = float(rng.uniform(5, 60)), float(rng.uniform(10, 120))
        for a in (act, None):
            assert_same(
                constraints.separation_violations(xy, d_s, a),
                ref_separation_violations(xy, d_s, a),
            )
            adj = comms.in_range(xy, rc, a)
            assert_same(adj, ref_in_range(xy, rc, a))
            dist = ref_pairwise_distances(xy)
            assert_same(comms.in_range(xy, rc, a, dist), adj)
            assert_same(
                constraints.separation_violations(xy, d_s, a, dist),
                ref_separation_violations(xy, d_s, a),
            )
            for m in (0, 1, 2, 3, -1):
                for a2 in (act, None):
                    want = ref_two_neighbour_ok(adj, m, a2)
                    assert_same(comms.two_neighbour_ok(adj, m, a2), want)
        # 2-D (no env axis) separation, as the docstring's "any leading shape"
        assert_same(
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
            assert_same((got.links, got.connected, got.n_components), want)
        # precomputed distances give the same links
        got = comms.auto_topology(avail, xy, act, mn, dist=ref_pairwise_distances(xy))
        want = ref_auto_topology(avail, xy, act, mn)
        assert_same((got.links, got.connected, got.n_components), want)


def test_row_sum_replicates_numpy_add_reduce():
    rng = np.random.default_rng(2)
    for n in range(1, 129):
        x = rng.random((3, n)) * 10.0 ** rng.integers(-12, 6, (3, n)) * rng.choice([-1, 1], (3, n))
        x[1] = -0.0
        x[2, 0] = -0.0
        want = x.sum(axis=1)
        got = np.array([sim._numpy_sum(row) for row in x])
        assert_same(got, want)


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
    vectors, bit for bit, with UAVs outside the grid, on its edges and not flying."""
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
            assert_same(obs.rasters(params, st, scale, hazard), want)
        assert_same(obs.vectors(params, st), ref_vectors(params, st))


def test_vector_clip_matches_numpy_on_special_values():
    params = sim.make_params(load_scenario("small"))
    st = _obs_state(params, np.random.default_rng(3), n_envs=1)
    st.pos[0, :, 2] = [-0.0, np.nan, np.inf]
    st.speed[0] = [params.scenario.uav.min_speed_mps, -np.inf, np.nan]
    st.pitch[0] = [-0.0, 0.0, np.nan]
    st.elapsed[0] = [np.nan, 0.0, np.inf]
    assert_same(obs.vectors(params, st), ref_vectors(params, st))


@pytest.mark.parametrize(("name", "overrides"), CONFIGS)
def test_step_matches_numpy_step(name, overrides):
    """Three envs at once against the numpy step: every State and Events array, every step."""
    params = sim.make_params(load_scenario(name, overrides))
    rng = np.random.default_rng(7)
    states, rng_sets = [], []
    for _ in range(2):
        rngs = [np.random.default_rng(s) for s in (1, 2, 3)]
        states.append(sim.initial(params, rngs))
        rng_sets.append(rngs)
        spread(states[-1], params, np.random.default_rng(11))
    if params.scenario.comms.link_failure_prob == 0:  # no draws: initial()'s topology too
        ref_update_topology(params, states[1], [])
        sim._update_topology(params, states[0], [])
        assert_same(dataclasses.asdict(states[0]), dataclasses.asdict(states[1]))
    for _ in range(30):
        acts = rng.uniform(-1, 1, (3, params.n_agents, 3))
        ev = sim.step(params, states[0], acts, rng_sets[0])
        want = ref_step(params, states[1], acts, rng_sets[1])
        assert_same(dataclasses.asdict(ev), dataclasses.asdict(want))
        assert_same(dataclasses.asdict(states[0]), dataclasses.asdict(states[1]))


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
def test_env_episodes_match_the_numpy_wrapper(name, overrides, obs_type):
    overrides = {**overrides, "episode.horizon_steps": 40, "episode.detection_ends_episode": True}
    for seed in (0, 1):
        got = _episode(poc_env.parallel_env(name, obs_type=obs_type, overrides=overrides), seed)
        want = _episode(RefEnv(name, obs_type=obs_type, overrides=overrides), seed)
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
        assert_same(env._actions_array(acts), env._actions_array_checked(acts))
    env.agents = env.agents[1:]  # a finished agent: zeros in its row
    acts = {k: a[k] for k in env.agents}
    assert_same(env._actions_array(acts), env._actions_array_checked(acts))
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


def test_kernels_are_recompiled_when_their_callees_change():
    """Numba caches a kernel by its own file only; the kernels calling other modules' compiled
    functions close over the hash of those modules' sources, which numba keys the cache on."""
    deps = sim._source_hash(constraints, comms, search_theory)
    for kernel in (sim._step_kernel, sim._target_pod, sim._auto_links):
        cells = [c.cell_contents for c in kernel.py_func.__closure__]
        assert deps in cells
    cells = [c.cell_contents for c in obs._vector_kernel.py_func.__closure__]
    assert sim._source_hash(constraints, comms) in cells
