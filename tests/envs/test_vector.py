"""The SB3 VecEnv adapter (poc_env.envs.vector)."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.envs.vector import SwarmVecEnv, env_seed_sequences
from poc_env.errors import ConfigError
from poc_env.sim.observations import RASTER_INDEX, VECTOR_INDEX, VECTOR_SIZE

TIME, FLYING, ENDURANCE = VECTOR_INDEX["time"], VECTOR_INDEX["flying"], VECTOR_INDEX["endurance"]


def _slot(obs, k):
    if isinstance(obs, dict):
        return {key: v[k] for key, v in obs.items()}
    return obs[k]


def _assert_obs_equal(a, b):
    if isinstance(a, dict):
        assert set(a) == set(b)
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    else:
        np.testing.assert_array_equal(a, b)


def _is_zero(obs) -> bool:
    if isinstance(obs, dict):
        return all(not np.any(v) for v in obs.values())
    return not np.any(obs)


def _vector(obs, k):
    if isinstance(obs, dict):
        return obs["vector"][k]
    return obs[k][:VECTOR_SIZE]  # the compass features start with the vector


def _compare_with_parallel_env(
    n_envs: int, k: int, seed: int, action_seed: int, control="increments", obs_type="dict"
):
    """Env ``k`` of the adapter against the PettingZoo env seeded with its seed sequence, with
    the same random actions, for the whole first episode; returns how many agents of env k
    finished before the episode ended."""
    kw = {"control": control, "obs_type": obs_type}
    vec = SwarmVecEnv("small", n_envs=n_envs, seed=seed, **kw)
    par = UAVSearchParallelEnv("small", **kw)
    n = vec.n_agents
    agents = par.possible_agents
    obs_v = vec.reset()
    obs_p, _ = par.reset(seed=env_seed_sequences(seed, n_envs)[k])
    # the hidden target and detection threshold come from env k's own generator
    assert vec.state.target[k].tolist() == par.sim_state.target[0].tolist()
    assert vec.state.target_threshold[k] == par.sim_state.target_threshold[0]
    for i, a in enumerate(agents):
        _assert_obs_equal(obs_p[a], _slot(obs_v, k * n + i))
    rng = np.random.default_rng(action_seed)
    early = 0
    steps = 0
    while par.agents:
        acts = rng.uniform(-1, 1, (vec.num_envs, vec.action_space.shape[0])).astype(np.float32)
        live = list(par.agents)
        obs_p, rew_p, term, trunc, _ = par.step(
            {a: acts[k * n + i] for i, a in enumerate(agents) if a in live}
        )
        obs_v, rew_v, done_v, infos = vec.step(acts)
        steps += 1
        ended = not par.agents
        if not ended:
            assert vec.state.posc[k] == par.sim_state.posc[0]
            assert vec.state.target_exponent[k] == par.sim_state.target_exponent[0]
        for i, a in enumerate(agents):
            s = k * n + i
            info = infos[s]
            if a in live:
                assert "inactive" not in info
                assert rew_v[s] == np.float32(rew_p[a])
                assert done_v[s] == (term[a] or trunc[a])
                if done_v[s]:
                    _assert_obs_equal(obs_p[a], info["terminal_observation"])
                    assert info["TimeLimit.truncated"] == trunc[a]
                    if not ended:
                        early += 1
                        assert _is_zero(_slot(obs_v, s))
                else:
                    _assert_obs_equal(obs_p[a], _slot(obs_v, s))
            else:  # finished earlier: placeholder transitions
                assert info["inactive"] is True
                assert rew_v[s] == 0.0
                assert done_v[s] == ended
                if not ended:
                    assert _is_zero(_slot(obs_v, s))
                else:
                    assert _is_zero(info["terminal_observation"])
            if ended:  # auto-reset: the new episode's first observation
                assert done_v[s]
                v = _vector(obs_v, s)
                assert v[TIME] == 0.0 and v[FLYING] == 1.0 and v[ENDURANCE] == 1.0
                assert "episode" in info
    assert steps >= 2
    return early


def test_adapter_matches_parallel_env_for_a_whole_episode():
    early = _compare_with_parallel_env(n_envs=1, k=0, seed=3, action_seed=11)
    assert early >= 1  # random pitch crashes some UAVs before the end: that path is covered


@pytest.mark.parametrize("control", ["heading", "waypoint"])
def test_adapter_matches_parallel_env_at_every_control_level(control):
    # the autopilot levels with the compass observation: same transitions, same landings
    _compare_with_parallel_env(1, 0, seed=4, action_seed=2, control=control, obs_type="compass")
    vec = SwarmVecEnv("small", n_envs=2, control=control)
    assert vec.action_space.shape == (2,)


def test_each_env_of_a_batch_matches_its_own_parallel_env():
    # env 1 of 2 replays the PettingZoo episode seeded with its own seed sequence, while env 0
    # steps (and possibly resets) beside it in the same batch
    _compare_with_parallel_env(n_envs=2, k=1, seed=8, action_seed=5)


def _land_next_step(vec, e, agents):
    st = vec.state
    st.pos[e, agents, :2] = vec.params.landing[agents]
    st.left_home[e, agents] = True  # over the airfield after a flight, slow: lands next step
    st.speed[e, agents] = vec.scenario.uav.min_speed_mps


def test_finished_agent_emits_one_done_then_inactive_placeholders_until_reset():
    horizon = 6
    vec = SwarmVecEnv("small", n_envs=2, seed=0, overrides={"episode.horizon_steps": horizon})
    vec.reset()
    _land_next_step(vec, 0, [0])
    zero = np.zeros((vec.num_envs, 3), dtype=np.float32)
    obs, rew, done, infos = vec.step(zero)
    assert done.tolist() == [True, False, False, False, False, False]
    assert vec.state.landed[0, 0]
    term = infos[0]["terminal_observation"]
    assert term["vector"][FLYING] == 0.0 and not _is_zero(term)  # its real last observation
    assert infos[0]["TimeLimit.truncated"] is False
    assert "inactive" not in infos[0] and "episode" not in infos[0]
    assert _is_zero(_slot(obs, 0))
    returns = rew.astype(float).copy()
    for _t in range(2, horizon):
        obs, rew, done, infos = vec.step(np.ones((vec.num_envs, 3), dtype=np.float32))
        returns += rew
        assert not done.any()
        assert infos[0] == {"inactive": True}
        assert rew[0] == 0.0 and _is_zero(_slot(obs, 0))
        for s in range(1, vec.num_envs):
            assert "inactive" not in infos[s] and not _is_zero(_slot(obs, s))
    assert vec.state.landed[0, 0] and not vec.state.flying[0, 0]
    obs, rew, done, infos = vec.step(zero)  # the horizon: every env truncates and resets
    returns += rew
    assert done.all()
    assert infos[0]["inactive"] is True and _is_zero(infos[0]["terminal_observation"])
    assert infos[0]["TimeLimit.truncated"] is False
    assert infos[0]["episode"]["l"] == 1 and infos[0]["landed"] is True
    for s in range(1, vec.num_envs):
        assert infos[s]["TimeLimit.truncated"] is True
        assert infos[s]["terminal_observation"]["vector"][TIME] == 1.0
        assert infos[s]["episode"]["l"] == horizon
    for s in range(vec.num_envs):
        ep = infos[s]["episode"]
        assert set(ep) >= {"r", "l", "t"} and ep["t"] >= 0
        assert ep["r"] == pytest.approx(returns[s], abs=1e-5)
        assert ep["posc"] == infos[s]["posc"] == infos[(s // 3) * 3]["posc"] > 0  # the env's
        v = _vector(obs, s)
        assert v[TIME] == 0.0 and v[FLYING] == 1.0  # first observation of the new episode
    assert (vec.state.step == 0).all() and vec.state.flying.all()
    returns[:] = 0.0
    for _t in range(horizon):  # the next episode: the slot is live again, returns start at 0
        obs, rew, done, infos = vec.step(zero)
        returns += rew
        assert "inactive" not in infos[0] and not _is_zero(_slot(obs, 0))
    assert done.all()
    for s in range(vec.num_envs):
        assert infos[s]["episode"]["r"] == pytest.approx(returns[s], abs=1e-5)
        assert infos[s]["episode"]["l"] == horizon


def test_env_whose_agents_all_finish_resets_alone():
    vec = SwarmVecEnv("small", n_envs=2, seed=1)
    vec.reset()
    zero = np.zeros((vec.num_envs, 3), dtype=np.float32)
    for _ in range(3):
        vec.step(zero)
    _land_next_step(vec, 0, [0, 1, 2])
    obs, _rew, done, infos = vec.step(zero)
    assert done.tolist() == [True, True, True, False, False, False]
    for s in range(3):
        assert infos[s]["TimeLimit.truncated"] is False
        assert infos[s]["terminal_observation"]["vector"][FLYING] == 0.0  # landed
        assert infos[s]["episode"]["l"] == 4 and infos[s]["landed"] is True
        assert "inactive" not in infos[s]
        assert obs["vector"][s][TIME] == 0.0 and obs["vector"][s][FLYING] == 1.0
    for s in range(3, 6):
        assert infos[s] == {}
        assert obs["vector"][s][TIME] == pytest.approx(4 / vec.params.horizon)
    assert vec.state.step.tolist() == [0, 4]


def test_detection_ends_the_episode_when_configured():
    vec = SwarmVecEnv("small", n_envs=2, seed=0, overrides={"episode.detection_ends_episode": True})
    vec.reset()
    zero = np.zeros((vec.num_envs, 3), dtype=np.float32)
    vec.step(zero)
    st = vec.state
    st.target[1] = st.pos[1, 0, :2]  # under UAV 0 of env 1, certain to be detected
    st.target_threshold[1] = 1e-9
    obs, _rew, done, infos = vec.step(zero)
    assert done.tolist() == [False] * 3 + [True] * 3
    for s in range(3, 6):
        assert infos[s]["TimeLimit.truncated"] is False and infos[s]["episode"]["l"] == 2
        assert obs["vector"][s][TIME] == 0.0


def test_posc_in_episode_info_is_the_envs():
    over = {"episode.horizon_steps": 5, "reward.violation_penalty": 0}
    vec = SwarmVecEnv("small", n_envs=1, seed=2, overrides=over)
    vec.reset()
    total = 0.0
    for _ in range(5):
        _obs, rew, _done, infos = vec.step(np.zeros((vec.num_envs, 3), dtype=np.float32))
        total += float(rew[0])
    # team credit, beta = 0, no penalties (the UAVs start together: collisions): return == POSC
    assert infos[0]["posc"] > 0
    assert infos[0]["episode"]["r"] == pytest.approx(infos[0]["posc"], rel=1e-5)
    assert infos[0]["episode"]["r"] == pytest.approx(total, rel=1e-5)


def test_random_priors_differ_between_resets_and_are_reproducible():
    def priors(seed):
        vec = SwarmVecEnv("small", n_envs=2, seed=seed, random_priors=True)
        out = []
        for _ in range(2):
            obs = vec.reset()
            assert obs["raster"][:, RASTER_INDEX["poc"]].max(axis=(1, 2)) == pytest.approx(1.0)
            coarse = vec.params.grid.coarsen(vec.state.belief, vec.params.s)
            np.testing.assert_allclose(coarse, vec.priors, rtol=1e-12, atol=1e-15)
            out.append(vec.priors.copy())
        return np.stack(out)

    a, b, c = priors(4), priors(4), priors(5)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a[0], a[1])  # a new prior at every reset
    assert not np.allclose(a[0, 0], a[0, 1])  # and per env
    assert not np.allclose(a, c)
    # env e's prior is the first draw of its documented generator ...
    from poc_env.theory.probability_map import random_gaussian_mixture

    grid = SwarmVecEnv("small", n_envs=1).params.grid
    for e in range(2):
        rng = np.random.default_rng(env_seed_sequences(4, 2)[e])
        np.testing.assert_array_equal(a[0, e], random_gaussian_mixture(grid, rng))
    # ... which does not depend on how many envs there are
    wider = SwarmVecEnv("small", n_envs=3, seed=4, random_priors=True)
    wider.reset()
    np.testing.assert_array_equal(wider.priors[:2], a[0])
    fixed = SwarmVecEnv("small", n_envs=1, seed=4)
    fixed.reset()
    np.testing.assert_array_equal(fixed.priors[0], fixed.params.prior)


def test_seed_rederives_the_generators_at_the_next_reset():
    vec = SwarmVecEnv("small", n_envs=2, seed=0, random_priors=True)
    vec.reset()
    vec.seed(9)
    vec.reset()
    other = SwarmVecEnv("small", n_envs=2, seed=9, random_priors=True)
    other.reset()
    np.testing.assert_array_equal(vec.priors, other.priors)
    np.testing.assert_array_equal(vec.state.target, other.state.target)


def test_flat_observations_are_the_dict_ones_concatenated():
    d = SwarmVecEnv("small", n_envs=2, seed=0)
    f = SwarmVecEnv("small", n_envs=2, seed=0, obs_type="flat")
    od, of = d.reset(), f.reset()
    assert of.shape == (6, *f.observation_space.shape)
    flat = np.concatenate([od["raster"].reshape(6, -1), od["vector"]], axis=1)
    np.testing.assert_array_equal(of, flat)
    assert f.observation_space.contains(of[0]) and d.observation_space.contains(_slot(od, 0))


def test_sb3_api_and_errors():
    from stable_baselines3.common.monitor import Monitor

    vec = SwarmVecEnv("small", n_envs=2, seed=0)
    assert vec.num_envs == 6 and vec.action_space.shape == (3,)
    assert vec.get_attr("n_agents") == [3] * 6 and vec.get_attr("n_agents", [1]) == [3]
    vec.set_attr("random_priors", True)
    assert vec.random_priors
    with pytest.raises(ConfigError, match="indices"):
        vec.set_attr("random_priors", False, indices=[0])
    vec.set_attr("random_priors", False)
    assert vec.env_is_wrapped(Monitor) == [True] * 6
    assert vec.env_method("seed", 1, indices=[0, 1]) == [[1] * 6] * 2
    prior = (np.arange(64.0).reshape(8, 8) + 1) / 2080
    vec.set_options({"prior": prior})  # like the PettingZoo env's options={"prior": ...}
    vec.reset()
    np.testing.assert_allclose(vec.priors, np.broadcast_to(prior / prior.sum(), (2, 8, 8)))
    vec.reset()  # options apply to one reset
    np.testing.assert_array_equal(vec.priors[0], vec.params.prior)
    with pytest.raises(ConfigError, match="actions"):
        vec.step(np.zeros((5, 3)))
    with pytest.raises(ConfigError, match="actions"):
        vec.step(np.full((6, 3), np.nan))
    vec.close()
    for bad in (0, -2, 1.5, True, "4"):
        with pytest.raises(ConfigError, match="n_envs"):
            SwarmVecEnv("small", n_envs=bad)
    with pytest.raises(ConfigError, match="obs_type"):
        SwarmVecEnv("small", obs_type="pixels")
    with pytest.raises(ConfigError, match="seed"):
        SwarmVecEnv("small", seed=-1)


def test_compass_without_the_agent_index():
    """``agent_index=False``: the same transitions, the index block of every slot at zero."""
    from poc_env.sim.observations import N_IDS

    kw = {"n_envs": 2, "seed": 3, "obs_type": "compass", "control": "heading"}
    a = SwarmVecEnv("small", **kw)
    b = SwarmVecEnv("small", agent_index=False, **kw)
    oa, ob = a.reset(), b.reset()
    act = np.random.default_rng(0).uniform(-1, 1, (a.num_envs, 2)).astype(np.float32)
    for _ in range(3):
        assert oa[:, -N_IDS:].any() and not ob[:, -N_IDS:].any()
        np.testing.assert_array_equal(oa[:, :-N_IDS], ob[:, :-N_IDS])
        oa, ra, *_ = a.step(act)
        ob, rb, *_ = b.step(act)
        np.testing.assert_array_equal(ra, rb)
    with pytest.raises(ConfigError, match="agent_index"):
        SwarmVecEnv("small", agent_index="no", **kw)


def test_return_autopilot_at_the_increments_level():
    """``return_autopilot``: straight level flight (zero increments) lands every UAV home once
    eq. 18 says so; without it (the registered tasks) the same flight ends in crashes."""
    outcome = {}
    for flag in (False, True):
        env = SwarmVecEnv(
            "small", n_envs=2, seed=0, obs_type="compass", control="increments",
            return_autopilot=flag,
        )  # fmt: skip
        env.reset()
        ends = []
        for _ in range(300):
            *_, infos = env.step(np.zeros((env.num_envs, 3), np.float32))
            ends += [(i["landed"], i["crashed"]) for i in infos if "landed" in i]
        outcome[flag] = ends
    assert outcome[True] and all(landed and not crashed for landed, crashed in outcome[True])
    assert outcome[False] and not any(landed for landed, _ in outcome[False])
    with pytest.raises(ConfigError, match="return_autopilot"):
        SwarmVecEnv("small", control="increments", return_autopilot=1)


def _same_infos(a: list[dict], b: list[dict]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert list(x) == list(y)
        for key in x:
            if key == "episode":  # its "t" is wall time
                assert {k: v for k, v in x[key].items() if k != "t"} == {
                    k: v for k, v in y[key].items() if k != "t"
                }
            elif key == "terminal_observation":
                _assert_obs_equal(x[key], y[key])
            else:
                assert type(x[key]) is type(y[key]) and x[key] == y[key], key


@pytest.mark.parametrize(
    ("scenario", "kwargs"),
    [
        ("paper_6_2", {"obs_type": "compass", "control": "heading_clip", "random_priors": True}),
        ("small", {"obs_type": "dict", "overrides": {"comms.link_failure_prob": 0.3}}),
        ("small", {"obs_type": "flat", "control": "waypoint", "return_autopilot": False}),
    ],
    ids=["paper62-compass-random", "small-dict-failures", "small-flat-waypoint"],
)
def test_fast_step_equals_the_engines_step(scenario, kwargs):
    """The adapter's step through :class:`~poc_env.sim.single.SingleStep` (``_fast``) gives
    what it gives through :meth:`Engine.step` (``_fast = None``), bit for bit: observations,
    rewards, dones and infos over episodes with finished agents and autoresets."""
    overrides = {"episode.horizon_steps": 25, **kwargs.pop("overrides", {})}
    fast = SwarmVecEnv(scenario, n_envs=3, seed=4, overrides=overrides, **kwargs)
    ref = SwarmVecEnv(scenario, n_envs=3, seed=4, overrides=overrides, **kwargs)
    assert fast._fast is not None, "the fast step is not used"
    ref._fast = None
    _assert_obs_equal(fast.reset(), ref.reset())
    rng = np.random.default_rng(5)
    ends = 0
    for _ in range(60):
        acts = rng.uniform(-1.2, 1.2, (fast.num_envs, *fast.action_space.shape))
        got, want = fast.step(acts), ref.step(acts)
        _assert_obs_equal(got[0], want[0])
        for x, y in zip(got[1:3], want[1:3], strict=True):
            assert x.dtype == y.dtype and np.array_equal(x, y)
        _same_infos(got[3], want[3])
        ends += sum("episode" in info for info in got[3])
    assert ends >= 2 * fast.n_agents  # autoresets were compared


def _numpy_slot_step(active, reward, finished, truncated, over, returns, lengths):
    """``step_wait``'s bookkeeping in numpy (what ``_kernels.adapters.slot_step`` compiles)."""
    r = np.where(active, reward, 0.0)
    returns += r
    lengths += active
    fin = active & finished
    still = active & ~fin
    env_end = over | np.all(~still, axis=1)
    done = (fin | env_end[:, None]).ravel()
    return r.ravel().astype(np.float32), done, (still & truncated).ravel(), still, env_end


def test_slot_bookkeeping_kernel_is_the_numpy_formulation():
    """``_kernels.adapters.slot_step`` (SwarmVecEnv.step_wait's bookkeeping) writes what the
    numpy formulation gives, bit for bit, and its flags say what the arrays hold: random
    placeholders, finished agents, cuts and ends; rewards with -0.0, NaN and float32 rounding."""
    from poc_env._kernels import adapters as slots

    rng = np.random.default_rng(3)
    specials = np.array([0.0, -0.0, np.nan, 1e-320, 0.1, -3.7, 1 / 3, 1e30])
    for trial in range(300):
        e, n = int(rng.integers(1, 6)), int(rng.integers(1, 7))
        active = rng.random((e, n)) < rng.random()
        finished = rng.random((e, n)) < rng.random()
        truncated = rng.random((e, n)) < 0.3
        over = rng.random(e) < 0.3
        reward = rng.normal(size=(e, n)) * 10.0 ** rng.integers(-8, 8, (e, n))
        if trial % 3 == 0:
            reward = rng.choice(specials, (e, n))
        returns = rng.normal(size=(e, n))
        lengths = rng.integers(0, 100, (e, n))
        want_ret, want_len = returns.copy(), lengths.copy()
        want = _numpy_slot_step(active, reward, finished, truncated, over, want_ret, want_len)
        got = (
            np.empty(e * n, np.float32), np.empty(e * n, bool), np.empty(e * n, bool),
            np.empty((e, n), bool), np.empty(e, bool),
        )  # fmt: skip
        flags = slots.slot_step(active, reward, finished, truncated, over, returns, lengths, *got)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == w.dtype and g.shape == w.shape
            np.testing.assert_array_equal(g.view(np.uint8), w.view(np.uint8))
        np.testing.assert_array_equal(returns.view(np.int64), want_ret.view(np.int64))
        np.testing.assert_array_equal(lengths, want_len)
        _, done, _, still, env_end = want
        assert bool(flags & slots.SOME_INACTIVE) == (not active.all())
        assert bool(flags & slots.SOME_DONE) == done.any()
        assert bool(flags & slots.SOME_STOPPED) == (not still.all())
        assert bool(flags & slots.SOME_ENV_ENDS) == env_end.any()
