"""The set observation (``obs_type="set"``, issue 28): any fleet size, the neighbours as a set.

The compiled kernel (:func:`poc_env._kernels.observations.swarm_set`) is checked against a plain
numpy reading of :data:`poc_env.spec.SET_BLOCKS`; the blocks it shares with the compass are the
compass's; the neighbour set does not depend on which index the other UAVs have.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from poc_env import spec, tasks
from poc_env.config import load_scenario
from poc_env.sim import observations as obs_mod
from poc_env.sim.engine import make_engine

B = spec.set_offsets()
K, W = spec.K_NEIGHBOURS, spec.NEIGHBOUR_SIZE


def _engine(n: int, seed: int = 3, steps: int = 25, n_envs: int = 2, obs_type: str = "set"):
    """Engine on ``wide_400`` with ``n`` UAVs after ``steps`` steps of random headings."""
    eng = make_engine(
        n_envs, scenario="wide_400", obs_type=obs_type, control="heading", random_prior=True,
        fleet=spec.fleet_of(n), seeds=list(range(seed, seed + n_envs)),
    )  # fmt: skip
    eng.reset()
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        eng.step(rng.uniform(-1, 1, (n_envs, n, 2)))
    return eng


def _reference(eng) -> np.ndarray:
    """The set blocks after the compass ones, from the spec's words, in numpy."""
    st, p = eng.current, eng.params
    bx0, by0, bx1, by1 = p.bounds
    diag = np.hypot(bx1 - bx0, by1 - by0)
    vmax = p.scenario.uav.max_speed_mps
    e_n, n = st.flying.shape
    out = np.zeros((e_n, n, spec.SET_SIZE - B["role"].start))
    o0 = B["role"].start
    vel = st.speed[..., None] * np.cos(st.pitch)[..., None]
    vel = vel * np.stack([np.cos(st.heading), np.sin(st.heading)], -1)
    fleet = [g.takeoff for g in p.scenario.fleet for _ in range(g.count)]
    for e in range(e_n):
        xy = st.pos[e, :, :2]
        for i in range(n):
            row = out[e, i]
            row[B["role"].start - o0] = (fleet[:i].count(fleet[i]) + 0.5) / fleet.count(fleet[i])
            others = [j for j in range(n) if j != i and st.flying[e, j]]
            if others:
                c = np.clip((xy[others].mean(0) - xy[i]) / diag, -2, 2)
                row[B["centroid"].start - o0 : B["centroid"].stop - o0] = c
            row[B["fleet"].start - o0] = 1 - 1 / n
            row[B["fleet"].start - o0 + 1] = st.flying[e].sum() / n
            d = np.hypot(*(xy[others] - xy[i]).T)
            order = [others[k] for k in np.lexsort((others, d))][:K]
            for r, j in enumerate(order):
                dist = np.hypot(*(xy[j] - xy[i]))
                nb = B["neighbours"].start - o0 + r * W
                row[nb : nb + 2] = np.clip((xy[j] - xy[i]) / diag, -2, 2)
                row[nb + 2 : nb + 4] = np.clip((vel[e, j] - vel[e, i]) / vmax, -2, 2)
                row[nb + 4] = min(dist / diag, 2.0)
                row[nb + 5] = dist <= p.scenario.comms.range_m
                row[nb + 6] = 1.0
    return out


@pytest.mark.parametrize("n", [3, 12])
def test_the_kernel_is_the_spec(n):
    eng = _engine(n)
    eng.current.flying[1, 1] = False  # a UAV that no longer flies is nobody's neighbour
    got = eng.observe()
    want = _reference(eng)
    np.testing.assert_allclose(got[..., B["role"].start :], want, rtol=1e-6, atol=1e-6)
    assert eng.observation_space.contains(got[0, 0])
    assert (got[1, :, B["fleet"].start + 1] == (n - 1) / n).all()


def test_the_compass_blocks_are_the_compass_observation_without_the_index():
    a, b = _engine(6), _engine(6, obs_type="compass")
    assert a.current.pos.tobytes() == b.current.pos.tobytes()
    c = spec.compass_offsets()
    np.testing.assert_array_equal(a.observe()[..., : c["index"].start], b.observe()[..., :55])
    assert B["mean_poc"].stop == c["index"].start == 55


def test_the_neighbours_are_a_set_padded_with_a_mask():
    eng = _engine(3)
    obs = eng.observe()
    rows = obs[..., B["neighbours"]].reshape(2, 3, K, W)
    assert (rows[:, :, :2, -1] == 1).all()  # the two others, then zero padding
    assert (rows[:, :, 2:] == 0).all()
    d = rows[..., 4]
    assert (np.diff(d[:, :, :2], axis=-1) >= 0).all()  # nearest first
    # relabelling the other UAVs (swap the states of UAVs 1 and 2) leaves UAV 0's set unchanged
    st = eng.current
    before = obs[:, 0].copy()
    for f in dataclasses.fields(st):
        arr = getattr(st, f.name)
        if isinstance(arr, np.ndarray) and arr.ndim >= 2 and arr.shape[:2] == (2, 3):
            arr[:, [1, 2]] = arr[:, [2, 1]]
    after = eng.observe()[:, 0]
    np.testing.assert_array_equal(after[:, B["neighbours"]], before[:, B["neighbours"]])


def test_uavs_of_one_airfield_differ_at_takeoff_by_their_role_only():
    eng = make_engine(1, scenario="wide_400", obs_type="set", fleet=spec.fleet_of(24), seeds=[0])
    obs, _ = eng.reset()
    roles = obs[0, :, B["role"].start]
    assert len(set(roles.tolist())) == 8  # 8 UAVs per airfield: 8 distinct roles ...
    assert len({o.tobytes() for o in obs[0]}) == 24  # ... so no two UAVs see the same
    same = obs[0, 0].copy()
    same[B["role"]] = obs[0, 3, B["role"]]  # UAVs 0 and 3 share airfield A
    np.testing.assert_array_equal(same, obs[0, 3])


def test_size_tasks_fly_their_fleet_spread_as_with_uavs():
    sc = load_scenario("wide_400")
    assert tuple(a.name for a in sc.airfields) == spec.SIZE_AIRFIELDS
    for part in spec.SIZE_PARTS:
        n = int(part.value)
        task = next(t for t in tasks.TASKS.values() if t.n_uavs == n)
        got = load_scenario(task.scenario, {"fleet": task.kwargs["fleet"]})
        assert got.fleet == sc.with_uavs(n).fleet and got.n_uavs == n
        assert tasks.make_parallel(task.id).params.n_agents == n


def test_roles_rank_the_uavs_of_each_airfield():
    eng = make_engine(1, scenario="wide_400", obs_type="set", fleet=spec.fleet_of(7))
    np.testing.assert_allclose(
        obs_mod.roles(eng.params), [1 / 6, 3 / 6, 5 / 6, 1 / 4, 3 / 4, 1 / 4, 3 / 4]
    )


def test_the_compass_index_says_when_a_fleet_outgrows_it():
    """The compass's index block is a one-hot of k mod 8: beyond 8 UAVs two UAVs read the same
    index. Documented (docs/environment.md); said where it happens too, as a warning naming
    the fleet, so a compass policy flown or trained at 12 or 24 UAVs does not alias silently
    (scale-audit). The set observation, and the compass without the index, say nothing."""
    import warnings

    with pytest.warns(UserWarning, match=r"12 UAVs.*k mod 8.*UAVs 0 and 8"):
        _engine(12, steps=0, obs_type="compass")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _engine(8, steps=0, obs_type="compass")
        _engine(12, steps=0, obs_type="set")
        sc = load_scenario("wide_400")
        eng = make_engine(1, scenario=sc, obs_type="compass", control="heading", agent_index=False)
        assert eng.scenario.n_uavs == 12
