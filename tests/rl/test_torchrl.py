"""TorchRL on the registered tasks: :func:`poc_env.agents.rl.frameworks.torchrl_env`.

TorchRL's spec check, rollout shapes per control level, a transition-by-transition replay of a
wrapped episode on the bare PettingZoo env (UAVs finishing at different times: masks, zeros,
no reset before the last UAV finishes), and a ``SyncDataCollector`` run across episodes.
"""

from __future__ import annotations

import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("torchrl")

import torch
from torchrl.envs.utils import check_env_specs

from poc_env import tasks
from poc_env.agents.rl.frameworks import GROUP, torchrl_env
from poc_env.errors import MissingExtraError

SHORT = {"episode.horizon_steps": 20}
DIMS = {"Increments": 3, "Heading": 2, "Waypoint": 2}


@pytest.fixture(autouse=True)
def _quiet():
    # TorchRL warns that it tests PettingZoo 1.24.3 only (we run 1.27)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="PettingZoo in TorchRL", category=UserWarning)
        yield


def random_policy(seed: int, dim: int):
    """A uniform random policy drawing from its own seeded generator."""
    gen = torch.Generator().manual_seed(seed)

    def policy(td):
        n = td[GROUP, "observation"].shape[-2]
        td.set((GROUP, "action"), torch.rand(n, dim, generator=gen) * 2 - 1)
        return td

    return policy


@pytest.mark.parametrize("control", list(DIMS))
def test_specs_and_rollout_shapes(control):
    tid = f"UAVSearch-Small-{control}-v0"
    env = torchrl_env(tid, seed=0, overrides=SHORT)
    assert env.group_map == {GROUP: ["uav_0", "uav_1", "uav_2"]}
    check_env_specs(env)
    td = env.rollout(50, random_policy(0, DIMS[control]), break_when_any_done=False)
    assert td.batch_size == (50,)
    assert td[GROUP, "observation"].shape == (50, 3, 63)
    assert td[GROUP, "action"].shape == (50, 3, DIMS[control])
    assert td["next", GROUP, "reward"].shape == (50, 3, 1)
    assert td["next", GROUP, "done"].shape == (50, 3, 1)
    assert td[GROUP, "mask"].shape == (50, 3)
    assert td["next", "done"].shape == (50, 1)
    # the horizon of 20 steps ends every episode: 50 steps span at least two
    assert td["next", "done"].sum() >= 2
    # infos are numeric and keyed per agent
    assert td["next", GROUP, "info", "posc"].shape == (50, 3)


def test_state_for_centralised_critics():
    env = torchrl_env("UAVSearch-Small-Heading-v0", seed=0, return_state=True, overrides=SHORT)
    check_env_specs(env)
    td = env.reset()
    np.testing.assert_allclose(td["state"].numpy(), env._env.state(), rtol=1e-6)


def test_replay_matches_pettingzoo_env_with_staggered_finishes():
    """A wrapped episode, replayed action by action on the bare env, gives the same
    transitions; agents that finished are masked with zero observation and reward, and the
    episode runs on until the last UAV finishes (no reset when the first lands)."""
    tid = "UAVSearch-Small-Heading-v0"
    env = torchrl_env(tid, seed=3)
    td = env.rollout(400, random_policy(1, 2), break_when_any_done=True)
    T = td.batch_size[0]
    nxt = td["next", GROUP]
    mask = nxt["mask"].numpy()  # (T, 3): agent still flying after the step
    finish = [int(np.argmin(mask[:, i])) for i in range(3)]
    assert not mask[-1].any() and td["next", "done"][-1].item()
    assert not td["next", "done"][:-1].any()  # one episode: never done before the last step
    assert len(set(finish)) > 1, f"UAVs finished together {finish}: the case is not staggered"

    pz = tasks.make_parallel(tid)
    obs, _ = pz.reset(seed=3)
    for i, agent in enumerate(pz.possible_agents):
        np.testing.assert_allclose(td[GROUP, "observation"][0, i].numpy(), obs[agent], rtol=1e-6)
    for t in range(T):
        live = list(pz.agents)
        assert td[GROUP, "mask"][t].tolist() == [a in live for a in pz.possible_agents]
        actions = {a: td[GROUP, "action"][t, pz.possible_agents.index(a)].numpy() for a in live}
        obs, rew, term, trunc, _ = pz.step(actions)
        for i, agent in enumerate(pz.possible_agents):
            if agent in live:  # includes the agent's final transition
                np.testing.assert_allclose(nxt["observation"][t, i].numpy(), obs[agent], rtol=1e-6)
                assert nxt["reward"][t, i, 0].item() == pytest.approx(rew[agent], rel=1e-6)
                assert nxt["terminated"][t, i, 0].item() == term[agent]
                assert nxt["truncated"][t, i, 0].item() == trunc[agent]
            else:  # finished before this step: masked, zeros, done
                assert not nxt["mask"][t, i]
                assert not nxt["observation"][t, i].any()
                assert nxt["reward"][t, i, 0].item() == 0.0
                assert nxt["done"][t, i, 0].item()
    assert not pz.agents


def test_collector_across_episodes():
    from torchrl.collectors import Collector  # SyncDataCollector before torchrl 0.11

    env = torchrl_env("UAVSearch-Small-Increments-v0", seed=0, overrides=SHORT)
    collector = Collector(env, random_policy(2, 3), frames_per_batch=100, total_frames=200)
    batches = list(collector)
    collector.shutdown()
    assert len(batches) == 2
    for b in batches:
        assert b.batch_size == (100,)
        assert b[GROUP, "observation"].shape == (100, 3, 63)
        assert b["next", GROUP, "reward"].shape == (100, 3, 1)
        assert torch.isfinite(b["next", GROUP, "reward"]).all()
    traj = torch.cat([b["collector", "traj_ids"] for b in batches])
    assert traj.unique().numel() >= 200 // 20  # the collector reset the env at every episode end


def test_missing_torchrl_is_a_missing_extra_error(monkeypatch):
    for name in ("torchrl", "torchrl.envs", "torchrl.envs.libs", "torchrl.envs.libs.pettingzoo"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(MissingExtraError) as err:
        torchrl_env("UAVSearch-Small-Heading-v0")
    assert err.value.extra == "torchrl"
    assert "pip install 'poc-env[torchrl]'" in str(err.value)


def test_docs_example_runs(capsys):
    """The TorchRL example of docs/FRAMEWORKS.md runs as written."""
    doc = (Path(__file__).resolve().parents[2] / "docs" / "FRAMEWORKS.md").read_text("utf-8")
    blocks = [b for b in re.findall(r"```python\n(.*?)```", doc, flags=re.S) if "torchrl" in b]
    assert len(blocks) == 1
    exec(compile(blocks[0], "docs/FRAMEWORKS.md", "exec"), {})
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2 and all(line.startswith("torch.Size([2, 100, 3, 63])") for line in lines)
