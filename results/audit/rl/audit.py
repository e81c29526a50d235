"""An RL researcher's audit of every registered task (issue 28, i28-audit).

Runs each check on every registered id and prints one line per (check, id) that fails, then a
summary table. Usage: ``OMP_NUM_THREADS=1 python results/audit/rl/audit.py [CHECK ...] [--ids
SUBSTR]`` (checks: rollout, seed, render, close, copy, vec, actions, gymcheck).
"""

from __future__ import annotations

import copy
import json
import pickle
import sys
import traceback
import warnings

import gymnasium
import numpy as np

import poc_env  # noqa: F401
from poc_env import tasks

SHORT = {"episode.horizon_steps": 40}
ALL = list(tasks.TASKS)


def _unexpected(w) -> bool:
    """A warning other than gymnasium's note that an old id (``...-Heading-v0``) has a newer
    version (expected: old ids stay registered with their behaviour)."""
    return "is out of date" not in str(w.message)


def _acts(env, rng, agents):
    return {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in agents}


def check_rollout(tid):
    """Full episodes (natural horizon) of random actions: every observation in its space
    (also the last one of each agent), infos keys stable, agents removed once done, no reward
    or obs for finished agents, terminated xor truncated for the finishing agent; three episodes
    of seeds 0..2 (random and all-east actions)."""
    problems = []
    for seed, policy in ((0, "random"), (1, "random"), (2, "east"), (3, "zero")):
        env = tasks.make_parallel(tid)
        obs, infos = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        keys = None
        for a, o in obs.items():
            if not env.observation_space(a).contains(o):
                problems.append(f"reset obs {a} out of space")
        keys = {a: tuple(i) for a, i in infos.items()}
        done: set = set()
        t = 0
        while env.agents:
            live = list(env.agents)
            if policy == "random":
                acts = _acts(env, rng, live)
            elif policy == "east":
                acts = {a: np.r_[1.0, np.zeros(env.action_space(a).shape[0] - 1)] for a in live}
            else:
                acts = {a: np.zeros(env.action_space(a).shape, np.float32) for a in live}
            obs, rew, term, trunc, infos = env.step(acts)
            t += 1
            for d in (obs, rew, term, trunc, infos):
                if set(d) != set(live):
                    problems.append(f"t={t}: dict keys {sorted(d)} != live {live}")
                    break
            for a, o in obs.items():
                sp = env.observation_space(a)
                if not sp.contains(o):
                    arr = np.asarray(o)
                    bad = np.nonzero((arr < sp.low) | (arr > sp.high))[0]
                    problems.append(
                        f"t={t} seed={seed} {policy}: obs {a} out of space at {bad.tolist()[:8]}"
                        f" values {arr[bad][:8].tolist()} term={term[a]} trunc={trunc[a]}"
                    )
                if tuple(infos[a]) != keys[a]:
                    problems.append(f"t={t}: info keys changed for {a}")
            for a in live:
                if term[a] and trunc[a]:
                    problems.append(f"t={t}: {a} both terminated and truncated")
                if (term[a] or trunc[a]) and a in env.agents:
                    problems.append(f"t={t}: {a} done but still in agents")
                if not (term[a] or trunc[a]) and a not in env.agents:
                    problems.append(f"t={t}: {a} removed without done")
                if not np.isfinite(rew[a]):
                    problems.append(f"t={t}: reward {a} not finite")
            done |= {a for a in live if term[a] or trunc[a]}
            if t > env.max_cycles + 1:
                problems.append("episode longer than its horizon")
                break
        try:
            env.step({})
            problems.append("step after the end did not raise")
        except Exception as e:
            if type(e).__name__ != "EpisodeOverError":
                problems.append(f"step after the end raised {type(e).__name__}")
    return problems[:6]


def check_aec(tid):
    """AEC: random rollout to the end; observe() in space for every agent (done ones too)."""
    problems = []
    env = tasks.make_aec(tid, overrides=SHORT)
    env.reset(seed=4)
    rng = np.random.default_rng(4)
    for agent in env.agent_iter(max_iter=10_000):
        obs, _rew, term, trunc, _info = env.last()
        if not env.observation_space(agent).contains(obs):
            problems.append(f"aec obs of {agent} out of space (term={term}, trunc={trunc})")
        act = None if (term or trunc) else rng.uniform(-1, 1, env.action_space(agent).shape)
        env.step(act)
    return problems[:4]


def _episode(tid, seed, steps=40):
    env = tasks.make_parallel(tid, overrides=SHORT)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(123)
    out = [np.concatenate([np.ravel(o) for o in obs.values()])]
    for _ in range(steps):
        if not env.agents:
            break
        obs, rew, _term, _trunc, _info = env.step(_acts(env, rng, env.agents))
        out.append(
            np.concatenate([np.ravel(o) for o in obs.values()] + [np.array(list(rew.values()))])
        )
    return out


def check_seed(tid):
    problems = []
    a, b = _episode(tid, 11), _episode(tid, 11)
    if len(a) != len(b) or any(not np.array_equal(x, y) for x, y in zip(a, b)):
        problems.append("same seed, same actions: episodes differ")
    c = _episode(tid, 12)
    differ = len(a) != len(c) or any(not np.array_equal(x, y) for x, y in zip(a, c))
    task = tasks.get_task(tid)
    if task.random_prior and not differ:
        problems.append("random task: seeds 11 and 12 give the same episode")
    return problems


def check_render(tid):
    problems = []
    import matplotlib

    matplotlib.use("Agg")
    for mode in ("rgb_array", "human"):
        env = tasks.make_parallel(tid, render_mode=mode, overrides=SHORT)
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        frame = env.render()
        for _ in range(3):
            env.step(_acts(env, rng, env.agents))
        frame = env.render()
        if mode == "rgb_array" and not (
            isinstance(frame, np.ndarray)
            and frame.ndim == 3
            and frame.shape[2] == 3
            and frame.dtype == np.uint8
        ):
            problems.append(f"rgb_array frame {type(frame)} {getattr(frame, 'shape', None)}")
        env.close()
        env.close()
    g = gymnasium.make(tid, render_mode="rgb_array", overrides=SHORT)
    g.reset(seed=0)
    fr = g.render()
    if not isinstance(fr, np.ndarray):
        problems.append("gym rgb_array render gave no frame")
    g.close()
    g.close()
    return problems


def check_close(tid):
    problems = []
    for make in (
        lambda: tasks.make_parallel(tid, overrides=SHORT),
        lambda: tasks.make_aec(tid, overrides=SHORT),
        lambda: gymnasium.make(tid, overrides=SHORT),
        lambda: gymnasium.make_vec(tid, num_envs=2, overrides=SHORT),
    ):
        env = make()
        env.close()  # before reset
        env = make()
        env.reset(seed=0)
        try:
            env.close()
            env.close()
        except Exception as e:
            problems.append(f"{type(env).__name__}: close twice: {e!r}")
    return problems


def check_copy(tid):
    """Pickle and deepcopy mid-episode (parallel, AEC, Gymnasium view, make_vec): the copy
    continues exactly as the original under the same actions."""
    problems = []
    # parallel
    env = tasks.make_parallel(tid, overrides=SHORT)
    env.reset(seed=1)
    rng = np.random.default_rng(1)
    for _ in range(5):
        env.step(_acts(env, rng, env.agents))
    for how in ("pickle", "deepcopy"):
        try:
            clone = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
        except Exception as e:
            problems.append(f"parallel {how}: {e!r}"[:200])
            continue
        r1 = np.random.default_rng(9)
        r2 = np.random.default_rng(9)
        e1 = copy.deepcopy(env)
        for _ in range(5):
            if not e1.agents:
                break
            o1 = e1.step(_acts(e1, r1, e1.agents))
            o2 = clone.step(_acts(clone, r2, clone.agents))
            if o1[1] != o2[1] or any(not np.array_equal(o1[0][a], o2[0][a]) for a in o1[0]):
                problems.append(f"parallel {how}: the copy diverges")
                break
    # gym view
    g = gymnasium.make(tid, overrides=SHORT)
    g.reset(seed=2)
    for _ in range(3):
        g.step(g.action_space.sample())
    for how in ("pickle", "deepcopy"):
        try:
            c = pickle.loads(pickle.dumps(g)) if how == "pickle" else copy.deepcopy(g)
            a = np.full(g.action_space.shape, 0.3, np.float32)
            c2 = copy.deepcopy(g)
            x, y = c.step(a), c2.step(a)
            if not np.array_equal(x[0], y[0]) or x[1] != y[1]:
                problems.append(f"gym {how}: the copy diverges")
        except Exception as e:
            problems.append(f"gym {how}: {e!r}"[:200])
    # aec
    aec = tasks.make_aec(tid, overrides=SHORT)
    aec.reset(seed=3)
    for _ in range(4):
        ag = aec.agent_selection
        done = aec.terminations[ag] or aec.truncations[ag]
        aec.step(None if done else aec.action_space(ag).sample())
    for how in ("pickle", "deepcopy"):
        try:
            c = pickle.loads(pickle.dumps(aec)) if how == "pickle" else copy.deepcopy(aec)
            ag = c.agent_selection
            done = c.terminations[ag] or c.truncations[ag]
            c.step(None if done else np.zeros(c.action_space(ag).shape, np.float32))
        except Exception as e:
            problems.append(f"aec {how}: {e!r}"[:200])
    # vec
    v = gymnasium.make_vec(tid, num_envs=2, overrides=SHORT)
    v.reset(seed=3)
    v.step(np.zeros(v.action_space.shape, np.float32))
    for how in ("pickle", "deepcopy"):
        try:
            c = pickle.loads(pickle.dumps(v)) if how == "pickle" else copy.deepcopy(v)
            a = np.full(v.action_space.shape, -0.2, np.float32)
            c2 = copy.deepcopy(v)
            x, y = c.step(a), c2.step(a)
            if not np.array_equal(x[0], y[0]):
                problems.append(f"vec {how}: the copy diverges")
        except Exception as e:
            problems.append(f"vec {how}: {e!r}"[:200])
    return problems


def check_vec(tid):
    """make_vec (batched core) vs the sync vector env: 3 envs, 50 steps through autoresets."""
    problems = []
    kw = {"overrides": {"episode.horizon_steps": 15}}
    v = gymnasium.make_vec(tid, num_envs=3, vectorization_mode="vector_entry_point", **kw)
    s = gymnasium.make_vec(tid, num_envs=3, vectorization_mode="sync", **kw)
    ov, _iv = v.reset(seed=5)
    os_, _ = s.reset(seed=5)
    if not np.array_equal(ov, os_):
        problems.append("reset obs differ")
    rng = np.random.default_rng(5)
    for t in range(50):
        a = rng.uniform(-1, 1, v.action_space.shape).astype(np.float32)
        got, want = v.step(a), s.step(a)
        for j in range(4):
            if not np.array_equal(got[j], want[j]):
                problems.append(f"step {t} item {j} differs")
                return problems
        for k in want[4]:
            if k not in got[4] or not np.array_equal(np.asarray(got[4][k]), np.asarray(want[4][k])):
                problems.append(f"step {t} info {k} differs")
                return problems
        if not v.single_observation_space.contains(got[0][0]) or not v.observation_space.contains(
            got[0]
        ):
            problems.append(f"step {t}: vec obs out of its space")
            return problems
    return problems


def _edge_cases(view, step, bad, ok):
    """``step`` of each ``bad`` action must raise ConfigError, of each ``ok`` one succeed."""
    from poc_env.errors import ConfigError

    problems = []
    for name, action in bad.items():
        try:
            step(action)
            problems.append(f"{view} {name}: accepted")
        except ConfigError:
            pass
        except Exception as e:
            problems.append(f"{view} {name}: {type(e).__name__}: {e}"[:150])
    for name, action in ok.items():
        try:
            step(action)
        except Exception as e:
            problems.append(f"{view} {name}: {type(e).__name__}: {e}"[:150])
    return problems


def check_actions(tid):
    """Edge-case actions on the four views: NaN/inf, wrong shape -> ConfigError; out of bounds
    -> documented clipping (accepted, finite obs); dtypes float16/float64/int accepted."""
    from poc_env.errors import ConfigError

    problems = []
    par = tasks.make_parallel(tid, overrides=SHORT)
    par.reset(seed=0)
    d = par.action_space("uav_0").shape[0]
    for name, bad in (
        ("nan", [np.nan] * d),
        ("inf", [np.inf] * d),
        ("shape", [0.0] * (d + 1)),
        ("str", ["a"] * d),
        ("none", None),
    ):
        acts = {a: np.zeros(d) for a in par.agents}
        acts["uav_0"] = bad
        try:
            par.step(acts)
            problems.append(f"parallel {name}: accepted")
        except ConfigError:
            pass
        except Exception as e:
            problems.append(f"parallel {name}: {type(e).__name__}: {e}"[:150])
    for name, ok in (
        ("big", [5.0] * d),
        ("f16", np.zeros(d, np.float16)),
        ("int", [1] * d),
        ("f64", np.zeros(d)),
        ("neg", [-7.0] * d),
    ):
        acts = {a: np.zeros(d) for a in par.agents}
        acts["uav_0"] = ok
        try:
            o = par.step(acts)[0]
            if not all(np.isfinite(np.ravel(x)).all() for x in o.values()):
                problems.append(f"parallel {name}: non-finite obs")
        except Exception as e:
            problems.append(f"parallel {name}: {type(e).__name__}: {e}"[:150])
        if not par.agents:
            par.reset(seed=0)
    g = gymnasium.make(tid, overrides=SHORT, disable_env_checker=True)
    g.reset(seed=0)
    n = g.action_space.shape[0]
    bad = {"nan": np.full(n, np.nan), "inf": np.full(n, -np.inf), "shape": np.zeros(n + 1)}
    bad["obj"] = np.array([None] * n)
    ok = {"big": np.full(n, 9.0), "f16": np.zeros(n, np.float16), "int": np.ones(n, int)}
    ok["2d"] = np.zeros((n // d, d))
    problems += _edge_cases("gym", g.step, bad, ok)
    v = gymnasium.make_vec(tid, num_envs=2, overrides=SHORT)
    v.reset(seed=0)
    shp = v.action_space.shape
    bad = {"nan": np.full(shp, np.nan), "inf": np.full(shp, np.inf)}
    bad |= {"shape": np.zeros((2, shp[1] + 1)), "flat": np.zeros(shp[1])}
    bad["str"] = np.full(shp, "a")
    ok = {"big": np.full(shp, 9.0), "f16": np.zeros(shp, np.float16), "int": np.ones(shp, int)}
    problems += _edge_cases("vec", v.step, bad, ok)
    aec = tasks.make_aec(tid, overrides=SHORT)
    aec.reset(seed=0)
    for name, bad in (("nan", np.full(d, np.nan)), ("shape", np.zeros(d + 2))):
        try:
            aec.step(bad)
            # AEC buffers the action; the error comes when the cycle's last agent steps
            for _ in range(len(aec.agents)):
                aec.step(np.zeros(d))
            problems.append(f"aec {name}: accepted")
        except ConfigError:
            pass
        except Exception as e:
            problems.append(f"aec {name}: {type(e).__name__}: {e}"[:150])
        aec.reset(seed=0)
    return problems


def check_gymcheck(tid):
    """gymnasium's check_env with the render check, and the passive checker's warnings
    over 30 steps of gymnasium.make (env checker on)."""
    from gymnasium.utils.env_checker import check_env

    problems = []
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        env = gymnasium.make(tid, render_mode="rgb_array", overrides=SHORT)
        check_env(env.unwrapped)
        env.reset(seed=0)
        for _ in range(30):
            _, _, te, tr, _ = env.step(env.action_space.sample())
            if te or tr:
                env.reset()
        env.close()
    msgs = sorted({f"{x.category.__name__}: {x.message}"[:200] for x in w if _unexpected(x)})
    problems += [f"warning: {m}" for m in msgs]
    return problems


def check_gymrollout(tid):
    """The Gymnasium view over full episodes of random actions: obs in space at every step,
    the last one included; finite reward; the same info keys; never both flags."""
    problems = []
    env = gymnasium.make(tid, disable_env_checker=True)
    for seed in (0, 1):
        obs, info = env.reset(seed=seed)
        keys = set(info)
        env.action_space.seed(seed)
        if not env.observation_space.contains(obs):
            problems.append("reset obs out of space")
        for t in range(10_000):
            obs, r, te, tr, info = env.step(env.action_space.sample())
            if not env.observation_space.contains(obs):
                sp = env.observation_space
                bad = np.nonzero((obs < sp.low) | (obs > sp.high))[0]
                problems.append(f"t={t} obs out of space at {bad[:6].tolist()} {obs[bad][:6]}")
            if set(info) != keys or not np.isfinite(r) or (te and tr):
                problems.append(f"t={t} info keys/reward/flags")
            if te or tr:
                break
    return problems[:4]


def check_state(tid):
    """state() within state_space over a rollout to the end (all agents done)."""
    problems = []
    env = tasks.make_parallel(tid, overrides=SHORT)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    sp = env.state_space
    for t in range(100):
        st = env.state()
        if not sp.contains(st):
            bad = np.nonzero((st < sp.low) | (st > sp.high))[0]
            problems.append(f"t={t} state out of space at {bad[:6].tolist()} {st[bad][:6]}")
            break
        if not env.agents:
            break
        env.step(_acts(env, rng, env.agents))
    return problems


def check_reseed(tid):
    """reset(seed=s) then reset() twice: the same sequence of episodes on a fresh env."""
    problems = []
    runs = []
    for _ in range(2):
        env = tasks.make_parallel(tid, overrides=SHORT)
        env.reset(seed=7)
        o2, _ = env.reset()
        o3, _ = env.reset()
        runs.append(
            [np.concatenate([np.ravel(v) for v in o.values()]) for o in (o2, o3)]
            + [env.sim_state.belief.copy()]
        )
    if any(not np.array_equal(a, b) for a, b in zip(*runs)):
        problems.append("reset() after reset(seed) is not reproducible")
    return problems


def check_swarmvec(tid):
    """SwarmVecEnv (SB3): observations in the observation space over a rollout."""
    from poc_env.envs.vector import SwarmVecEnv

    problems = []
    t = tasks.get_task(tid)
    if t.motion != "static" or t.n_uavs is not None:
        return problems
    venv = SwarmVecEnv(
        t.scenario,
        n_envs=2,
        seed=0,
        obs_type=t.obs,
        control=t.kwargs["control"],
        random_priors=t.random_prior,
        overrides=SHORT,
    )
    obs = venv.reset()
    sp = venv.observation_space
    rng = np.random.default_rng(0)
    for k in range(60):
        bad = [i for i in range(len(obs)) if not sp.contains(obs[i].astype(sp.dtype))]
        if bad:
            problems.append(f"step {k}: slots {bad[:4]} out of space")
            break
        obs, _r, d, infos = venv.step(rng.uniform(-1, 1, (venv.num_envs, *venv.action_space.shape)))
        for i in np.nonzero(d)[0]:
            term = infos[i].get("terminal_observation")
            if term is not None and not sp.contains(term.astype(sp.dtype)):
                problems.append(f"step {k}: terminal_observation of slot {i} out of space")
    return problems[:4]


def check_seeddiff(tid):
    """Where the task has randomness beyond the hidden target (random priors, a drifting
    target's current), different seeds give different observations."""
    task = tasks.get_task(tid)
    if not (task.random_prior or task.motion != "static"):
        return []
    a, c = _episode(tid, 21), _episode(tid, 22)
    if len(a) == len(c) and all(np.array_equal(x, y) for x, y in zip(a, c)):
        return ["seeds 21 and 22 give the same episode"]
    return []


def check_torchrl(tid):
    """TorchRL's check_env_specs on the task's PettingZooWrapper (torchrl_env)."""
    from torchrl.envs.utils import check_env_specs

    from poc_env.agents.rl.frameworks import torchrl_env

    env = torchrl_env(tid, overrides=SHORT)
    check_env_specs(env, seed=0)
    env.rollout(30)
    env.close()
    return []


def check_sb3(tid):
    """stable-baselines3's own check_env on the Gymnasium view."""
    from stable_baselines3.common.env_checker import check_env as sb3_check

    problems = []
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        sb3_check(gymnasium.make(tid, overrides=SHORT, disable_env_checker=True).unwrapped)
    problems += sorted({f"{x.category.__name__}: {x.message}"[:200] for x in w if _unexpected(x)})
    return problems


def check_async(tid):
    """make_vec(vectorization_mode='async') runs and equals the batched core."""
    kw = {"overrides": {"episode.horizon_steps": 15}}
    a = gymnasium.make_vec(tid, num_envs=2, vectorization_mode="async", **kw)
    v = gymnasium.make_vec(tid, num_envs=2, **kw)
    oa, _ = a.reset(seed=3)
    ov, _ = v.reset(seed=3)
    problems = [] if np.array_equal(oa, ov) else ["reset differs"]
    rng = np.random.default_rng(3)
    for t in range(20):
        act = rng.uniform(-1, 1, v.action_space.shape).astype(np.float32)
        x, y = a.step(act), v.step(act)
        if any(not np.array_equal(x[j], y[j]) for j in range(4)):
            problems.append(f"step {t} differs")
            break
    a.close()
    v.close()
    return problems


def check_pzrender(tid):
    """PettingZoo's render_test."""
    import matplotlib

    matplotlib.use("Agg")
    from pettingzoo.test import render_test

    render_test(
        lambda render_mode=None: tasks.make_aec(tid, render_mode=render_mode, overrides=SHORT)
    )
    return []


def check_corners(tid):
    """Constant actions at every corner of the action Box (and a constant turn at full
    climb), full episodes at the natural horizon: observations, state and rewards stay inside
    their spaces and finite whatever the policy does."""
    import itertools

    problems = []
    env = tasks.make_parallel(tid)
    d = env.action_space("uav_0").shape[0]
    for corner in itertools.product((-1.0, 1.0), repeat=d):
        env.reset(seed=5)
        a = np.array(corner, np.float32)
        t = 0
        while env.agents:
            obs, rew, term, trunc, _ = env.step({ag: a for ag in env.agents})
            t += 1
            for ag, o in obs.items():
                sp = env.observation_space(ag)
                if not sp.contains(o):
                    bad = np.nonzero((o < sp.low) | (o > sp.high))[0]
                    problems.append(
                        f"corner {corner} t={t} {ag} out at {bad[:5].tolist()}"
                        f" {o[bad][:5]} term={term[ag]} trunc={trunc[ag]}"
                    )
            if not all(np.isfinite(list(rew.values()))):
                problems.append(f"corner {corner} t={t} reward not finite")
            st = env.state()
            if not env.state_space.contains(st):
                problems.append(f"corner {corner} t={t} state out of space")
            if problems:
                return problems[:3]
    return problems


CHECKS = {
    "corners": check_corners,
    "seeddiff": check_seeddiff,
    "torchrl": check_torchrl,
    "sb3": check_sb3,
    "async": check_async,
    "pzrender": check_pzrender,
    "gymrollout": check_gymrollout,
    "state": check_state,
    "reseed": check_reseed,
    "swarmvec": check_swarmvec,
    "rollout": check_rollout,
    "aec": check_aec,
    "seed": check_seed,
    "render": check_render,
    "close": check_close,
    "copy": check_copy,
    "vec": check_vec,
    "actions": check_actions,
    "gymcheck": check_gymcheck,
}


def main(argv):
    ids = ALL
    if "--ids" in argv:
        i = argv.index("--ids")
        sub = argv[i + 1]
        argv = argv[:i] + argv[i + 2 :]
        ids = [t for t in ALL if sub in t]
    names = argv or list(CHECKS)
    summary = {}
    for name in names:
        fails = 0
        for tid in ids:
            try:
                probs = CHECKS[name](tid)
            except Exception as e:
                probs = [
                    f"crashed: {type(e).__name__}: {e}"[:300]
                    + " | "
                    + traceback.format_exc().splitlines()[-3][:200]
                ]
            if probs:
                fails += 1
                for p in probs:
                    print(f"FAIL {name} {tid.split('/')[1]}: {p}", flush=True)
        summary[name] = f"{len(ids) - fails}/{len(ids)} pass"
        print(f"== {name}: {summary[name]}", flush=True)
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main(sys.argv[1:])
