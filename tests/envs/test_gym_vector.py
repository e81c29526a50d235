"""``gymnasium.make_vec``'s batched step (:mod:`poc_env.envs.gym_vector`): the autoreset step of
some envs (every env stepped, the ended ones then reset; or, when the step draws from the env
generators, the ended ones reset first and the others stepped apart) returns exactly what the
sync vector env returns, and never writes into arrays it handed out."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import poc_env  # (also registers the tasks)
from poc_env.sim import core as sim
from poc_env.sim import single

TID = "poc_env/UAVSearch-Small-Heading-v1"


def _same_episodes(overrides: dict, num_envs: int = 6, steps: int = 40, seed: int = 3) -> int:
    """Step both vector envs under the same random actions; return how many steps reset some
    but not all envs (every item compared at every step)."""
    kw = {"num_envs": num_envs, "overrides": overrides}
    v = gymnasium.make_vec(TID, vectorization_mode="vector_entry_point", **kw)
    s = gymnasium.make_vec(TID, vectorization_mode="sync", **kw)
    got, want = v.reset(seed=seed), s.reset(seed=seed)
    np.testing.assert_array_equal(got[0], want[0])
    rng = np.random.default_rng(seed)
    partial = 0
    held: list = []
    for t in range(steps):
        some = v.unwrapped._autoreset.copy()
        partial += int(0 < some.sum() < num_envs)
        a = rng.uniform(-1, 1, v.action_space.shape).astype(np.float32)
        got, want = v.step(a), s.step(a)
        for arr, copy_ in held:  # arrays handed out are never written into later
            np.testing.assert_array_equal(arr, copy_, err_msg=f"step {t}: an earlier array changed")
        held = [(got[0], got[0].copy())] + [(x, np.array(x)) for x in got[4].values()]
        for j in range(4):
            np.testing.assert_array_equal(got[j], want[j], err_msg=f"step {t} item {j}")
        assert set(got[4]) == set(want[4])
        for key, w in want[4].items():
            g = np.asarray(got[4][key])
            assert g.dtype == np.asarray(w).dtype, key
            np.testing.assert_array_equal(g, w, err_msg=f"step {t} {key}")
    return partial


@pytest.mark.parametrize("failures", [0.0, 0.3])
def test_autoreset_of_some_envs_equals_the_sync_vector_env(failures):
    """Envs that end at different steps (violations terminate the UAVs) reset while the others
    go on; with link failures (the step draws from each env's generator) the ended envs are
    reset apart, without the step."""
    overrides = {
        "constraints.violation": "terminate",
        "episode.horizon_steps": 14,
        "comms.link_failure_prob": failures,
    }
    params = sim.make_params(poc_env.config.load_scenario("small", overrides))
    assert sim.step_is_per_env(params) == (failures == 0)
    assert _same_episodes(overrides) >= 2


@pytest.mark.parametrize(
    ("task", "steps"),
    [("poc_env/UAVSearch-Small-Heading-v1", [4, 4, 4, 4]),  # every env stepped once
     ("poc_env/UAVSearch-Small-Drift-Heading-v1", [4, 4, 4])],  # ended envs only reset
)  # fmt: skip
def test_the_autoreset_step_steps_every_env_when_the_step_is_per_env(monkeypatch, task, steps):
    """The autoreset step (here of every env) steps the whole batch once when the step changes
    each env by what it holds alone; with a moving target (its filter sub-steps by the batch's
    fastest current) the ended envs are reset without being stepped."""
    calls: list = []
    step = sim.step
    fast_step = single.SingleStep.step

    def counted(params, state, actions, rngs):
        calls.append(state.flying.shape[0])
        return step(params, state, actions, rngs)

    def counted_fast(self, actions):  # the whole batch's step (make_vec's fast path)
        calls.append(self.engine.current.flying.shape[0])
        return fast_step(self, actions)

    monkeypatch.setattr(sim, "step", counted)
    monkeypatch.setattr(single.SingleStep, "step", counted_fast)
    v = gymnasium.make_vec(task, num_envs=4, vectorization_mode="vector_entry_point", max_cycles=3)
    assert sim.step_is_per_env(v.unwrapped.params) == ("Drift" not in task)
    v.reset(seed=1)
    a = np.zeros(v.action_space.shape, dtype=np.float32)
    for _ in range(4):  # the fourth step autoresets every env
        v.step(a)
    assert calls == steps


@pytest.mark.parametrize(
    ("task", "kwargs"),
    [
        (
            "poc_env/UAVSearch-Small-Heading-v1",
            {"overrides": {"comms.link_failure_prob": 0.3}, "max_cycles": 10},
        ),
        ("poc_env/UAVSearch-Small-Drift-Heading-v1", {"max_cycles": 9}),
        ("poc_env/UAVSearch-Paper62-Random-Heading-v1", {"obs_type": "dict", "max_cycles": 12}),
        (
            "poc_env/UAVSearch-Small-Heading-v1",
            {"overrides": {"constraints.violation": "shield", "episode.horizon_steps": 10}},
        ),
    ],
    ids=["failures", "drift", "paper62-random-dict", "shield"],
)
def test_fast_whole_batch_step_equals_the_engines_step(task, kwargs):
    """The whole batch's step through :class:`~poc_env.sim.single.SingleStep` (``_fast``)
    returns what :meth:`Engine.step` returns (``_fast = None``): observations, rewards, ends
    and every info (keys in order, dtypes, values), over autoresets."""
    kw = {"num_envs": 3, "vectorization_mode": "vector_entry_point", **kwargs}
    fast, ref = gymnasium.make_vec(task, **kw), gymnasium.make_vec(task, **kw)
    assert fast.unwrapped._fast is not None, "the fast step is not used"
    ref.unwrapped._fast = None
    got, want = fast.reset(seed=2), ref.reset(seed=2)
    rng = np.random.default_rng(2)
    resets = 0
    for t in range(30):
        a = rng.uniform(-1.2, 1.2, fast.action_space.shape).astype(np.float32)
        resets += int(fast.unwrapped._autoreset.any())
        got, want = fast.step(a), ref.step(a)
        if isinstance(got[0], dict):
            for key in want[0]:
                np.testing.assert_array_equal(got[0][key], want[0][key], err_msg=key)
        else:
            np.testing.assert_array_equal(got[0], want[0])
        for j in range(1, 4):
            assert got[j].dtype == want[j].dtype
            np.testing.assert_array_equal(got[j], want[j], err_msg=f"step {t} item {j}")
        assert list(got[4]) == list(want[4])
        for key, w in want[4].items():
            g = got[4][key]
            assert g.dtype == w.dtype and g.shape == w.shape, key
            np.testing.assert_array_equal(g, w, err_msg=f"step {t} {key}")
    assert resets >= 1


def test_live_step_kernel_is_the_numpy_bookkeeping():
    """``_kernels.adapters.live_step`` (``_advance``'s bookkeeping of a whole batch's step,
    fewer than 8 agents) gives what the numpy formulation gives, to the bit: the reward mean
    over the agents live before the step (``engine.mean_over``), the ends, the live agents
    after it (written over ``live`` itself, as ``_advance`` lets it), and whether all were
    live; -0.0 and infinite rewards, envs without a live agent."""
    from poc_env._kernels import adapters

    rng = np.random.default_rng(8)
    specials = np.array([0.0, -0.0, np.inf, -np.inf, 1e-310, 0.1, -2.5, 1 / 3])
    for trial in range(400):
        e, n = int(rng.integers(1, 9)), int(rng.integers(1, 8))
        live = rng.random((e, n)) < (1.0 if trial % 4 == 0 else rng.random())
        reward = rng.normal(size=(e, n)) * 10.0 ** rng.integers(-6, 6, (e, n))
        if trial % 3 == 0:
            reward = rng.choice(specials, (e, n))
        term = rng.random((e, n)) < 0.3
        trunc = rng.random((e, n)) < 0.2
        over = rng.random(e) < 0.4
        want_mean = np.array(
            [np.mean(reward[k][live[k]]) if live[k].any() else 0.0 for k in range(e)]
        )
        want_trunc = over & trunc.any(axis=1)
        want_term = over & ~want_trunc
        want_live = live & ~(live & (term | trunc))
        got = np.empty(e), np.empty(e, bool), np.empty(e, bool)
        new_live = live.copy()
        every = adapters.live_step(new_live, reward, term, trunc, over, *got, new_live)
        np.testing.assert_array_equal(got[0].view(np.int64), want_mean.view(np.int64))
        np.testing.assert_array_equal(got[1], want_term)
        np.testing.assert_array_equal(got[2], want_trunc)
        np.testing.assert_array_equal(new_live, want_live)
        assert every == bool(live.all())
