"""poc-env bench peers: our envs against MPE2, VMAS and DSSE (agents/benchmarks/peers.py)."""

from __future__ import annotations

import csv
import statistics

import pytest

from poc_env.agents.benchmarks import peers
from poc_env.cli import build_parser
from poc_env.errors import ConfigError


def _rows(out):
    with open(out / "peers.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_smoke_run_writes_the_table_and_reports_missing_peers(tmp_path, monkeypatch):
    """Every contender gets a row and every target whose sides were asked for a ratio row;
    a peer that does not import is 'not installed' (its row and its ratios), not a traceback.
    MPE2 is made missing here so the path runs whatever the venv holds."""
    gone = peers.Contender(
        "mpe2", "MPE2 (hidden)", 6, lambda s: 1, peers._mpe, "mpe2", "no_such_peer_xyz"
    )
    monkeypatch.setitem(peers.CONTENDERS, "mpe2", gone)
    out = tmp_path / "peers"
    keys = ["single", "make_vec_small", "core_small_reset", "mpe2", "vmas", "dsse"]
    rows = peers.main(["--smoke", "--rounds", "1", "--only", *keys, "--out", str(out)])
    table = _rows(out)
    assert [r["key"] for r in table] == [str(r["key"]) for r in rows]
    speed = {r["key"]: r for r in table if r["kind"] == "speed"}
    assert list(speed) == keys
    for k, r in speed.items():
        if peers.installed(peers.CONTENDERS[k]):
            assert r["status"] == "ok"
            assert float(r["env_steps_per_s"]) > 0
            agents = peers.CONTENDERS[k].agents
            assert float(r["agent_steps_per_s"]) == pytest.approx(
                agents * float(r["env_steps_per_s"]), rel=1e-3
            )
        else:
            assert r["status"] == peers.NOT_INSTALLED
            assert r["env_steps_per_s"] == ""
    assert speed["mpe2"]["status"] == peers.NOT_INSTALLED
    ratios = {r["key"]: r for r in table if r["kind"] == "ratio"}
    # the targets with both sides among the keys (make_vec_paper62 and core_small_area left out)
    assert list(ratios) == ["single/dsse", "single/mpe2", "make_vec_small/core_small_reset"]
    assert ratios["single/mpe2"]["status"] == f"{peers.NOT_INSTALLED}: mpe2"
    assert ratios["make_vec_small/core_small_reset"]["status"] == "ok"
    assert float(ratios["make_vec_small/core_small_reset"]["ratio"]) > 0
    for r in table:
        assert float(r["load_before"]) >= 0 and float(r["load_after"]) >= 0
    md = (out / "peers.md").read_text()
    assert "not installed" in md and "pip install -e .[peers]" in md
    assert "load average" in md
    assert md.count("\n| MPE2 (hidden) |") == 1


def test_ratio_is_the_ratio_of_median_env_steps(tmp_path, monkeypatch):
    """A stand-in peer and a stand-in of ours, registered in the same table: the ratio is
    median(ours env-steps/s) / median(peer env-steps/s) (agent-steps / agents), not the
    median of the per-round ratios; the rounds are interleaved, each contender once a round."""
    ours = [100.0, 300.0, 200.0]  # agent-steps/s per round, 1 agent: env medians 200
    theirs = [40.0, 20.0, 60.0]  # 2 agents: env-steps 20, 10, 30, median 20
    calls: list[str] = []

    def run(rates, key):
        def f(s, seed):
            calls.append(key)
            return rates[seed]

        return f

    monkeypatch.setitem(
        peers.CONTENDERS,
        "ours_fake",
        peers.Contender("ours_fake", "ours", 1, lambda s: 4, run(ours, "o")),
    )
    monkeypatch.setitem(
        peers.CONTENDERS,
        "peer_fake",
        peers.Contender("peer_fake", "peer", 2, lambda s: 1, run(theirs, "p"), "none", "math"),
    )

    def broken(s, seed):
        calls.append("b")
        raise ImportError("a dependency of the peer is missing")

    # found by importlib but failing on import: 'not installed' too, tried once
    monkeypatch.setitem(
        peers.CONTENDERS,
        "broken_fake",
        peers.Contender("broken_fake", "broken", 1, lambda s: 1, broken, "none", "math"),
    )
    targets = [("ours_fake", "peer_fake", 9.0), ("ours_fake", "x", 1.0)]
    monkeypatch.setattr(peers, "TARGETS", [*targets, ("ours_fake", "broken_fake", 1.0)])
    out = tmp_path / "o"
    keys = ["ours_fake", "peer_fake", "broken_fake"]
    rows = peers.main(["--rounds", "3", "--only", *keys, "--out", str(out)])
    assert calls == ["o", "p", "b", "p", "o", "o", "p"]  # interleaved, order rotating
    status = {r["key"]: r["status"] for r in rows}
    assert status["broken_fake"] == peers.NOT_INSTALLED
    assert status["ours_fake/broken_fake"] == f"{peers.NOT_INSTALLED}: broken_fake"
    ratio = [r for r in rows if r["kind"] == "ratio" and r["key"] == "ours_fake/peer_fake"]
    assert len(ratio) == 1
    assert ratio[0]["ratio"] == pytest.approx(10.0)
    assert ratio[0]["ratio"] != pytest.approx(statistics.median([5.0, 30.0, 200 / 30]))
    assert ratio[0]["per_round"] == "5.00 30.00 6.67"
    assert ratio[0]["met"] == "yes"
    speed = {r["key"]: r for r in rows if r["kind"] == "speed"}
    assert speed["peer_fake"]["env_steps_per_s"] == 20.0
    assert speed["ours_fake"]["envs"] == 4
    assert (
        "| ours / peer | 10.00 | 5.00 30.00 6.67 | >= 9.0 | yes |" in (out / "peers.md").read_text()
    )


def test_bad_input_names_the_field_and_writes_nothing(tmp_path):
    out = tmp_path / "o"
    with pytest.raises(ConfigError, match="only"):
        peers.main(["--only", "nosuch", "--out", str(out)])
    with pytest.raises(ConfigError, match="rounds"):
        peers.main(["--rounds", "0", "--out", str(out)])
    assert not out.exists()


def test_sb3_cpu_time_option_reaches_the_pair_and_picks_the_cpu_clock(tmp_path, monkeypatch):
    """``--sb3-cpu-time`` times the SB3 pair by the process's CPU time: the flag reaches
    ``_sb3_rate`` of the task side (not set: wall time), and ``_sb3_rate`` reads the clock it
    names (a fake model whose learning takes 2 s of CPU and 10 s of wall time)."""
    import types

    seen: list[bool] = []
    monkeypatch.setattr(peers, "_sb3_rate", lambda a, e, s, i, cpu=False: seen.append(cpu) or 1.0)
    for flag in ([], ["--sb3-cpu-time"]):
        out = tmp_path / f"cpu{len(flag)}"
        peers.main(["--smoke", "--rounds", "1", "--only", "sb3_task", *flag, "--out", str(out)])
    assert seen == [False, True]
    monkeypatch.undo()

    clocks = {"process_time": 0.0, "perf_counter": 0.0}

    class Model:
        def learn(self, steps, reset_num_timesteps=True):
            clocks["process_time"] += 2.0
            clocks["perf_counter"] += 10.0

    import poc_env.agents.rl.train as train

    monkeypatch.setattr(train, "make_model", lambda args, env, log: Model())
    monkeypatch.setattr(train, "seed_everything", lambda seed: None)
    fake_time = types.SimpleNamespace(**{k: (lambda k=k: clocks[k]) for k in clocks})
    monkeypatch.setattr(peers, "time", fake_time)
    env = types.SimpleNamespace(num_envs=3, close=lambda: None)
    args = types.SimpleNamespace(n_steps=4)
    assert peers._sb3_rate(args, env, 0, 2, cpu_time=True) == 2 * 12 / 2.0
    assert peers._sb3_rate(args, env, 0, 2, cpu_time=False) == 2 * 12 / 10.0


def test_sb3_pair_smoke_run(tmp_path):
    """The SB3 PPO pair (``--sb3``): PPO through ``train --task`` against PPO with the same
    settings on MPE2; each side runs where its packages import (SB3, and MPE2 with SuperSuit,
    the ``peers`` extra) and is 'not installed' otherwise, and the ratio row says which."""
    out = tmp_path / "sb3"
    keys = list(peers.SB3_KEYS)
    peers.main(["--smoke", "--rounds", "1", "--only", *keys, "--out", str(out)])
    table = _rows(out)
    speed = {r["key"]: r for r in table if r["kind"] == "speed"}
    assert list(speed) == keys
    ran = []
    for k, r in speed.items():
        if r["status"] == "ok":
            ran.append(k)
            assert float(r["agent_steps_per_s"]) > 0
            assert r["envs"] == "1"  # --smoke: one swarm (one MPE2 world)
        else:
            assert r["status"] == peers.NOT_INSTALLED
    (ratio,) = [r for r in table if r["kind"] == "ratio"]
    assert ratio["key"] == "sb3_task/sb3_mpe2" and float(ratio["target"]) == 3.0
    if len(ran) == 2:
        assert ratio["status"] == "ok" and float(ratio["ratio"]) > 0
    else:
        assert ratio["status"].startswith(peers.NOT_INSTALLED)


def test_sb3_pair_only_on_request():
    """The slow PPO pair is left out of a default run and added by ``--sb3`` (or ``--only``)."""
    default = peers.chosen_keys(None, False)
    assert not set(peers.SB3_KEYS) & set(default)
    assert peers.chosen_keys(None, True) == default + list(peers.SB3_KEYS)
    assert peers.chosen_keys(["sb3_task"], False) == ["sb3_task"]
    args = peers.build_parser().parse_args(["--sb3"])
    assert args.sb3 and peers.chosen_keys(args.only, args.sb3)[-2:] == list(peers.SB3_KEYS)


def test_bench_peers_is_a_bench_subcommand():
    args = build_parser().parse_args(["bench", "peers", "--smoke"])
    assert args.what == "peers" and args.rest == ["--smoke"]


def test_declared_agents_are_the_scenarios():
    """Env-steps/s = agent-steps/s / the contender's agents: each of ours declares its task's
    UAV count (a scenario that changed it would skew every ratio)."""
    assert peers.CONTENDERS["single"].agents == peers._core_params("paper_6_2").n_agents
    for key, family in (
        ("make_vec_paper62", "Paper62"),
        ("make_vec_small", "Small"),
        ("core_small_reset", "Small"),
        ("core_small_area", "Small"),
    ):
        assert peers.CONTENDERS[key].agents == peers._task_agents(family), key


def test_breakdown_times_the_parts_and_restores_them(tmp_path):
    """``--breakdown``: a row per part of the contender's step, the whole first at 100 %, the
    whole-batch step's parts inside it (nested parts never exceed what contains them), written
    as a table set; the timed functions are the original ones afterwards. A bad key names it."""
    from poc_env._kernels import observations as obs_kernels
    from poc_env.agents.benchmarks import breakdown
    from poc_env.envs.gym_vector import SwarmGymVectorEnv
    from poc_env.sim import engine, single

    before = (SwarmGymVectorEnv.step, engine.Engine.step, single.SingleStep.step,
              single.swarm_increments, obs_kernels.compass)  # fmt: skip
    out = tmp_path / "bd"
    rows = peers.main(["--breakdown", "make_vec_small", "--smoke", "--out", str(out)])
    by = {r["part"]: r for r in rows}
    assert [r["part"] for r in rows] == [p[2] for p in breakdown.PARTS["make_vec_small"]]
    whole, batch = rows[0], by["whole-batch step"]
    fast = by["- single step (sim.single.SingleStep.step)"]
    assert whole["share"] == 100.0 and whole["ms_per_step"] > 0
    assert 0 < batch["ms_per_step"] <= whole["ms_per_step"]
    assert 0 < fast["ms_per_step"] <= batch["ms_per_step"]
    assert 0 < by["  - core step (SingleStep._core_step)"]["ms_per_step"] <= fast["ms_per_step"]
    assert 0 < by["    - compass kernel"]["ms_per_step"] <= fast["ms_per_step"]
    assert (out / "breakdown_make_vec_small.csv").exists()
    after = (SwarmGymVectorEnv.step, engine.Engine.step, single.SingleStep.step,
             single.swarm_increments, obs_kernels.compass)  # fmt: skip
    assert after == before
    with pytest.raises(ConfigError, match="breakdown"):
        breakdown.breakdown("vmas")


def test_single_breakdown_times_the_single_step_and_its_kernels():
    """``--breakdown single`` wraps the single env's step (:mod:`poc_env.sim.single`) and the
    kernels it calls: each part resolves, the step and its core and kernels are timed, and the
    kernels are the original dispatchers afterwards."""
    from poc_env._kernels import sensing, swarm
    from poc_env.agents.benchmarks import breakdown

    before = (sensing.fly_sense, swarm.step_end)
    rows = breakdown.breakdown("single", steps=5)
    by = {r["part"]: r["ms_per_step"] for r in rows}
    assert [r["part"] for r in rows] == [p[2] for p in breakdown.PARTS["single"]]
    whole = rows[0]["ms_per_step"]
    step = by["single step (sim.single.SingleStep.step)"]
    assert 0 < step <= whole
    assert 0 < by["- core step and its end (SingleStep._core_step)"] <= step
    assert by["  - kinematics, sensing and hidden target kernel (eq. 19, 12-14)"] > 0
    assert by["  - bookkeeping, topology, rewards, episode end, infos kernel"] > 0
    assert (sensing.fly_sense, swarm.step_end) == before
