"""The pilot recipe (poc_env.agents.rl.pilot): features, the autopilot, and its VecEnv."""

from __future__ import annotations

import numpy as np
import pytest

from poc_env.agents.rl.pilot import (
    OBSERVATION_SPACE,
    PilotFeatures,
    PilotVecEnv,
    grid_distance,
    pilot_actions,
)
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.sim.autopilot import must_return
from poc_env.sim.observations import FEATURES, N_RINGS, N_SECTORS, VECTOR_SIZE, decode_vector

COMPASS = slice(VECTOR_SIZE, VECTOR_SIZE + N_SECTORS * N_RINGS)


def _env(scenario="paper_6_2", **kw):
    env = UAVSearchParallelEnv(scenario, **kw)
    obs, _ = env.reset(seed=0)
    return env, obs


def _one_cell_prior(env, row, col):
    g = env.params.grid
    prior = np.full(g.shape, 1e-9)
    prior[row, col] = 1.0
    return prior / prior.sum()


def test_compass_points_at_the_mass():
    env, _ = _env()
    g = env.params.grid
    # all mass in one cell; UAV 0 starts at airfield A (20 km, -60 km)
    for (row, col), sector in (((0, 39), 0), ((29, 0), 2), ((15, 25), 1)):
        obs, _ = env.reset(seed=0, options={"prior": _one_cell_prior(env, row, col)})
        o = obs["uav_0"]
        f = PilotFeatures(env.params)(o["raster"][None], o["vector"][None], np.array([0]))[0]
        compass = f[COMPASS].reshape(N_SECTORS, N_RINGS)
        assert compass.sum() == pytest.approx(1.0, abs=1e-6)
        s, r = np.unravel_index(np.argmax(compass), compass.shape)
        centre = g.centers[row, col]
        d = centre - env.params.landing[0]
        want = int(np.floor(np.arctan2(d[1], d[0]) % (2 * np.pi) / (2 * np.pi / N_SECTORS)))
        assert s == want == sector
        assert r == np.searchsorted([10e3, 30e3, 70e3], np.hypot(*d), side="right")


def test_features_stay_in_the_space_and_carry_the_agent_index():
    env, obs = _env()
    feats = PilotFeatures(env.params)
    ras = np.stack([obs[a]["raster"] for a in env.agents])
    vec = np.stack([obs[a]["vector"] for a in env.agents])
    f = feats(ras, vec, np.arange(len(env.agents)))
    assert f.shape == (6, FEATURES) and OBSERVATION_SPACE.contains(f[0])
    ids = f[:, -8:]
    np.testing.assert_array_equal(ids[:, :6], np.eye(6))  # breaks the symmetry at takeoff
    # same vector + raster, different index: different features
    assert not np.array_equal(feats(ras[:1], vec[:1], [0]), feats(ras[:1], vec[:1], [1]))
    np.testing.assert_array_equal(f[:, :VECTOR_SIZE], vec)
    # the ablation without the index: the same features with the index block at zero
    g = PilotFeatures(env.params, agent_index=False)(ras, vec, np.arange(len(env.agents)))
    assert not g[:, -8:].any()
    np.testing.assert_array_equal(g[:, :-8], f[:, :-8])


def test_autopilot_heads_where_told_within_limits():
    env, obs = _env()
    vec = np.stack([obs[a]["vector"] for a in env.agents])
    k = np.arange(6)
    for direction in ([1, 0], [0, 1], [-1, 0], [0.3, -0.7]):
        act = pilot_actions(env.params, vec, np.tile(direction, (6, 1)), k)
        assert act.shape == (6, 3) and np.all(np.abs(act) <= 1.0)
    # fly north for a while: every UAV ends up north of where it started
    y0 = env.sim_state.pos[0, :, 1].copy()
    for _ in range(10):
        vec = np.stack([obs[a]["vector"] for a in env.agents])
        act = pilot_actions(env.params, vec, np.tile([0.0, 1.0], (6, 1)), k)
        obs, *_ = env.step({a: act[i] for i, a in enumerate(env.agents)})
    assert np.all(env.sim_state.pos[0, :, 1] > y0 + 15e3)
    heading = env.sim_state.heading[0]
    np.testing.assert_allclose(np.sin(heading), 1.0, atol=1e-3)


def test_autopilot_takes_over_to_come_home_and_land():
    env, obs = _env("small")
    overridden = 0
    while env.agents:
        live = list(env.agents)
        vec = np.stack([obs[a]["vector"] for a in live])
        idx = np.array([env.possible_agents.index(a) for a in live])
        act = pilot_actions(env.params, vec, np.tile([1.0, 1.0], (len(live), 1)), idx)
        for j in range(len(live)):
            q = decode_vector(env.params, vec[j])
            if must_return(env.params, q, idx[j]):  # the policy's action no longer matters
                other = pilot_actions(env.params, vec[j : j + 1], [[-1.0, 0.3]], idx[j : j + 1])
                np.testing.assert_array_equal(other[0], act[j])
                overridden += 1
        obs, *_ = env.step({a: act[j] for j, a in enumerate(live)})
    st = env.sim_state
    assert overridden > 0
    assert st.landed[0].all() and not st.crashed[0].any()


def test_vec_env_ends_rl_episodes_when_the_autopilot_flies_home():
    venv = PilotVecEnv("small", n_envs=2, seed=3, approach_shaping=0.0)
    obs = venv.reset()
    assert obs.shape == (6, FEATURES)
    done_seen = np.zeros(6, dtype=bool)
    for _ in range(200):
        obs, _, done, infos = venv.step(np.tile([0.0, 1.0], (6, 1)))
        for i in np.flatnonzero(done & ~done_seen):
            done_seen[i] = True
            term = infos[i]["terminal_observation"]
            if not infos[i].get("inactive"):
                # the RL episode ended while the UAV still flew: home-bound, not landed
                assert term[12] == 1.0  # flying
        if done_seen.all():
            break
    assert done_seen.all()


def test_approach_shaping_is_potential_based():
    gamma = 0.9
    plain = PilotVecEnv("paper_6_2", n_envs=1, seed=0)
    shaped = PilotVecEnv("paper_6_2", n_envs=1, seed=0, approach_shaping=0.5, gamma=gamma)
    plain.reset()
    shaped.reset()
    act = np.tile([0.0, 1.0], (6, 1))
    d_before = grid_distance(shaped.params, shaped.state.pos[0, :, :2]) / 1e3
    _, r0, *_ = plain.step(act)
    _, r1, *_ = shaped.step(act)
    d_after = grid_distance(shaped.params, shaped.state.pos[0, :, :2]) / 1e3
    np.testing.assert_allclose(r1 - r0, 0.5 * (-gamma * d_after + d_before), rtol=1e-5)
    assert np.all(r1 > r0)  # closing in on the grid pays


def test_ppo_policy_flies_a_pilot_checkpoint(tmp_path):
    from poc_env.agents.rl.args import TrainArgs
    from poc_env.agents.rl.policy import PPOPolicy
    from poc_env.agents.rl.train import make_env, make_model
    from poc_env.config import load_scenario

    args = TrainArgs(scenario="small", recipe="pilot", n_envs=1, n_steps=8, batch_size=8)
    env = make_env(args, load_scenario("small"))
    model = make_model(args, env, None)
    model.save(tmp_path / "m.zip")
    pol = PPOPolicy(tmp_path / "m.zip")
    penv, obs = _env("small")
    pol.reset(penv, 0)
    assert (pol.mode, pol.control) == ("compass", "heading")
    acts, _ = pol.predict(obs)
    assert set(acts) == set(penv.agents)
    assert all(a.shape == (3,) and np.all(np.abs(a) <= 1) for a in acts.values())
    # evaluation sees exactly the features training saw (same state, same observation)
    venv = PilotVecEnv("small", n_envs=1, seed=0)
    trained_on = venv.reset()
    live = penv.possible_agents
    seen = pol._features(
        np.stack([obs[a]["raster"] for a in live]),
        np.stack([obs[a]["vector"] for a in live]),
        np.arange(len(live)),
    )
    np.testing.assert_array_equal(seen, trained_on)


# the tolerance for a number recorded on another machine (a card, a golden episode): see
# docs/CONTRIBUTING.md, "Numbers recorded elsewhere"
CROSS_CPU_REL = 1e-3

SHIPPED = [
    "ppo_pilot_paper_6_2",
    "ppo_heading_paper_6_2",
    "ppo_heading_individual_paper_6_2",
    "ppo_increments_paper_6_2",
    "ppo_increments_individual_paper_6_2",  # BC at the increments level, then PPO (docs/rl.md)
    "rllib_heading_paper_6_2",
    "ppo_set_anysize",  # the set observation, one policy for 3 to 24 UAVs (docs/rl.md)
    "ppo_set_increments_anysize",  # the same at the eq. 19 level, BC on every task (docs/rl.md)
    "ppo_drift_small",
]


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_checkpoint_replays_its_card_and_flies_an_unseen_episode(name):
    """The card beside a shipped model (poc_env.agents.rl.card) records its held-out evaluation: the
    first of those episodes replays to the recorded POSC, and a further episode (a seed and
    prior neither training nor that evaluation used) lands every UAV and reaches the card's
    floor (the lowest POSC of the evaluation's episodes)."""
    import json
    from importlib.resources import as_file, files

    from poc_env.agents.experiments.evaluate import run_episode
    from poc_env.tasks import get_task

    folder = files("poc_env.agents") / "checkpoints"  # package data
    card = json.loads((folder / f"{name}.json").read_text())
    kind = "rllib" if card.get("engine") == "rllib" else "ppo"
    if kind == "rllib":
        pytest.importorskip("ray", reason="the rllib extra is not installed")
    with as_file(folder / (name if kind == "rllib" else f"{name}.zip")) as path:
        files_ = [f for f in path.rglob("*") if f.is_file()] if path.is_dir() else [path]
        assert sum(f.stat().st_size for f in files_) <= 5 * 2**20  # the 5 MB limit
    scenario = get_task(card["task"]).scenario if card.get("task") else "paper_6_2"
    random_priors = True
    if card.get("task") and get_task(card["task"]).motion != "static":  # its moving target
        scenario, random_priors = get_task(card["task"]).load_scenario(), False
    ev = card["evaluation"]
    first = run_episode(scenario, f"{kind}:{name}", ev["seeds"][0], random_priors=random_priors)
    # The card was recorded on another machine. torch picks CPU-specific kernels (AVX2,
    # AVX-512, ...), so the network's float32 outputs differ in their last bits between CPUs
    # and a replayed episode drifts from the recorded one (1.1e-6 relative seen on an AVX-512
    # EPYC). A number recorded elsewhere gets a cross-CPU tolerance (docs/CONTRIBUTING.md);
    # 1e-3 still fails on another model, another prior or a changed environment.
    assert first.posc == pytest.approx(ev["posc"][0], rel=CROSS_CPU_REL)
    unseen = run_episode(scenario, f"{kind}:{name}", 987_654, random_priors=random_priors)
    fleet = 6 if isinstance(scenario, str) else scenario.n_uavs
    assert unseen.landed == fleet and unseen.crashed == 0  # the autopilot brings all home
    assert unseen.posc >= ev["floor"] > 0.0


@pytest.mark.parametrize(
    ("name", "control"),
    [
        ("ppo_pilot_paper_6_2", "heading"),
        ("ppo_heading_paper_6_2", "heading"),
        ("ppo_heading_individual_paper_6_2", "heading"),
        ("ppo_increments_paper_6_2", "increments"),
        ("ppo_increments_individual_paper_6_2", "increments"),
    ],
)
def test_shipped_checkpoint_flies_at_its_level_within_limits(name, control):
    from poc_env.agents.rl.policy import PPOPolicy

    env = UAVSearchParallelEnv("paper_6_2")
    obs, _ = env.reset(seed=5)
    policy = PPOPolicy(name)
    policy.reset(env, 5)
    assert (policy.mode, policy.control) == ("compass", control)
    assert policy._return == (control == "increments")  # its card: --return-autopilot
    for _ in range(5):
        actions, _ = policy.predict(obs)
        assert all(np.all(np.abs(a) <= 1.0) for a in actions.values())
        obs, *_ = env.step(actions)


def test_shipped_checkpoint_by_name(tmp_path, monkeypatch):
    """``ppo:ppo_pilot_paper_6_2`` finds the package's file from any folder; unknown names
    list the shipped ones."""
    from importlib.resources import files

    from poc_env.agents.rl.checkpoint import model_path, shipped_checkpoints
    from poc_env.errors import ConfigError

    monkeypatch.chdir(tmp_path)
    assert "ppo_pilot_paper_6_2" in shipped_checkpoints()
    found = model_path("ppo_pilot_paper_6_2")
    assert found.samefile(str(files("poc_env.agents") / "checkpoints" / "ppo_pilot_paper_6_2.zip"))
    with pytest.raises(ConfigError, match="ppo_pilot_paper_6_2"):
        model_path("ppo_pilot_nowhere")
