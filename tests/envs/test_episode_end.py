"""Every adapter ends agents and episodes exactly where the core's rule says
(:func:`poc_env.sim.core.terminal`, :func:`~poc_env.sim.core.truncated`,
:func:`~poc_env.sim.core.episode_over`), and using the environment alone loads no RL or
plotting library."""

from __future__ import annotations

import copy
import subprocess
import sys

import numpy as np
import pytest

from poc_env.envs.gymnasium_env import UAVSearchGym
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.sim import core as sim

#: (overrides, seed): UAV 0 dives and crashes (``_actions``); the short horizon truncates the
#: rest; a certain detection (``_certain_detection``) ends the episode when configured to;
#: ``terminate`` mode crashes UAVs at their first violation.
CASES = {
    "crash_then_horizon": ({"episode.horizon_steps": 10}, 3),
    "detection_ends": ({"episode.detection_ends_episode": True}, 0),
    "terminate_mode": ({"constraints.violation": "terminate", "episode.horizon_steps": 10}, 1),
}


def _actions(rng, n_agents: int, width: int = 3) -> np.ndarray:
    """Random actions (n_agents, width); with eq. 19 actions UAV 0 pitches down all the way."""
    a = rng.uniform(-1, 1, (n_agents, width))
    if width == 3:
        a[0, 2] = -1.0
    return a


def _certain_detection(st, e: int) -> None:
    """Put env ``e``'s hidden target under its first flying UAV: detected in the next step."""
    i = int(np.flatnonzero(st.flying[e])[0])
    st.target[e] = st.pos[e, i, :2]
    st.target_threshold[e] = 1e-9


@pytest.mark.parametrize("case", sorted(CASES))
def test_parallel_env_agrees_with_the_core(case):
    overrides, seed = CASES[case]
    env = UAVSearchParallelEnv("small", overrides=overrides)
    env.reset(seed=seed)
    p = env.params
    rng = np.random.default_rng(seed)
    seen = {"terminated": 0, "truncated": 0}
    steps = 0
    while env.agents:
        if steps == 3 and p.scenario.episode.detection_ends_episode:
            _certain_detection(env.sim_state, 0)
        live = list(env.agents)
        acts = _actions(rng, p.n_agents)
        _, _, term, trunc, _ = env.step({a: acts[env.possible_agents.index(a)] for a in live})
        steps += 1
        st = env.sim_state
        terminal = sim.terminal(p, st)[0]
        truncated = sim.truncated(p, st)[0]
        for a in live:
            i = env.possible_agents.index(a)
            assert term[a] is bool(terminal[i]) and trunc[a] is bool(truncated[i])
            seen["terminated"] += term[a]
            seen["truncated"] += trunc[a]
        still = [a for i, a in enumerate(env.possible_agents) if not terminal[i] | truncated[i]]
        assert env.agents == still
        assert (not env.agents) == bool(sim.episode_over(p, st)[0])
    assert steps < p.horizon or sim.horizon_reached(p, env.sim_state)[0]
    assert seen["terminated"] > 0  # each case exercises termination ...
    if case == "crash_then_horizon":
        assert seen["truncated"] > 0  # ... and this one truncation too


@pytest.mark.parametrize("case", sorted(CASES))
def test_gymnasium_view_agrees_with_the_core(case):
    overrides, seed = CASES[case]
    env = UAVSearchGym(scenario="small", overrides=overrides)
    env.reset(seed=seed)
    p = env.par.params
    rng = np.random.default_rng(seed)
    terminated = truncated = False
    steps = 0
    while not (terminated or truncated):
        if steps == 3 and p.scenario.episode.detection_ends_episode:
            _certain_detection(env.par.sim_state, 0)
        _, _, terminated, truncated, _ = env.step(_actions(rng, p.n_agents).ravel())
        steps += 1
        st = env.par.sim_state
        over = bool(sim.episode_over(p, st)[0])
        assert terminated + truncated == over  # never both
        assert truncated == (over and bool(sim.truncated(p, st)[0].any()))
        assert terminated == (over and bool(sim.terminal(p, st)[0].all()))
    assert truncated == (case == "crash_then_horizon")


def _vec_env(kind: str, overrides):
    if kind == "swarm":
        from poc_env.envs.vector import SwarmVecEnv

        return SwarmVecEnv("small", n_envs=2, seed=0, overrides=overrides), 3
    from poc_env.agents.rl.pilot import PilotVecEnv

    return PilotVecEnv("small", n_envs=2, seed=0, overrides=overrides), 2


@pytest.mark.parametrize("kind", ["swarm", "pilot"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_vector_envs_agree_with_the_core(kind, case):
    overrides, seed = CASES[case]
    vec, width = _vec_env(kind, overrides)
    p, n = vec.params, vec.n_agents
    vec.reset()
    before_reset: list[sim.State] = []
    new_episodes = vec._new_episodes

    def spy(envs):  # the finished envs' last state, before the auto-reset overwrites it
        before_reset.append(copy.deepcopy(vec.state))
        return new_episodes(envs)

    vec._new_episodes = spy
    rng = np.random.default_rng(seed)
    live = np.ones((vec.n_envs, n), dtype=bool)
    ends = 0
    for t in range(25):
        if t == 3 and p.scenario.episode.detection_ends_episode:
            _certain_detection(vec.state, 1)
        before_reset.clear()
        acts = np.concatenate([_actions(rng, n, width) for _ in range(vec.n_envs)])
        _, _, done, infos = vec.step(acts)
        st = before_reset[0] if before_reset else vec.state
        terminal = sim.terminal(p, st)
        truncated = sim.truncated(p, st)
        own = vec._rl_done(st)  # the pilot's home-bound UAVs; False for the plain VecEnv
        finished = live & (terminal | own)
        over = sim.episode_over(p, st, ~(live & ~finished))
        assert over.any() == bool(before_reset)
        assert done.reshape(vec.n_envs, n).tolist() == (finished | over[:, None]).tolist()
        for s in np.flatnonzero(done):
            e, i = divmod(int(s), n)
            expect = bool(live[e, i] and not finished[e, i] and truncated[e, i])
            assert infos[s]["TimeLimit.truncated"] is expect
        live = np.where(over[:, None], True, live & ~finished)
        ends += int(over.sum())
    assert ends > 0


def test_env_use_does_not_load_torch_sb3_or_matplotlib():
    code = (
        "import sys\n"
        "import gymnasium\n"
        "import numpy as np\n"
        "import poc_env\n"
        "env = poc_env.parallel_env('small')\n"
        "env.reset(seed=0)\n"
        "for _ in range(3):\n"
        "    env.step({a: np.zeros(3, np.float32) for a in env.agents})\n"
        "aec = poc_env.env('small')\n"
        "aec.reset(seed=0)\n"
        "aec.step(np.zeros(3, np.float32))\n"
        "g = gymnasium.make('poc_env/UAVSearch-v0', scenario='small')\n"
        "g.reset(seed=0)\n"
        "g.step(np.zeros(g.action_space.shape, np.float32))\n"
        "heavy = ('torch', 'stable_baselines3', 'matplotlib', 'tensorboard')\n"
        "loaded = [m for m in heavy if m in sys.modules]\n"
        "assert not loaded, f'the environment loaded {loaded}'\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


@pytest.mark.parametrize("missing", ["stable_baselines3", "torch"])
def test_vector_env_without_the_rl_extra_names_it(missing):
    code = (
        "import sys\n"
        f"sys.modules[{missing!r}] = None  # as if not installed\n"
        "from poc_env.errors import MissingExtraError\n"
        "try:\n"
        "    import poc_env.envs.vector\n"
        "except MissingExtraError as err:\n"
        "    assert err.extra == 'rl', err\n"
        "    print(err)\n"
        "else:\n"
        "    raise SystemExit('imported without the rl extra')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "needs the 'rl' extra: pip install 'poc-env[rl]'" in out.stdout
