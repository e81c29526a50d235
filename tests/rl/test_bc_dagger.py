"""DAgger after the BC warm start (poc_env.agents.rl.bc, ``poc-env train --bc-dagger N``):
N=0 changes nothing, the learner's states carry the teacher's labels, aggregation, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.rl.args import TrainArgs, parse_train_args
from poc_env.agents.rl.bc import (
    DAGGER_KEY,
    DEMO_KEY,
    FIT_KEY,
    collect_demos,
    dagger_rollouts,
    pretrain,
    warm_start,
)
from poc_env.agents.rl.checkpoint import load_policy
from poc_env.agents.rl.train import make_env, make_model, seed_everything, train
from poc_env.config import load_scenario
from poc_env.errors import ConfigError

INC = "UAVSearch-Small-Random-Increments-v0"
HEAD = "UAVSearch-Small-Random-Heading-v0"


def _args(run_dir: Path, **kw) -> TrainArgs:
    base = dict(
        task=INC,
        bc_teacher="lawnmower",
        bc_episodes=2,
        bc_epochs=3,
        total_timesteps=0,
        n_envs=2,
        return_autopilot=True,
        progress=False,
        run_dir=str(run_dir),
    )
    base.update(kw)
    return TrainArgs(**base)


def test_no_dagger_leaves_the_warm_start_unchanged(tmp_path, same_weights):
    """--bc-dagger 0 (the default) is the warm start as before: the first fit alone (the same
    weights as collect_demos + pretrain on the demo and fit streams), no ``dagger`` record, no
    iteration files."""
    sc = load_scenario("small")
    args = _args(tmp_path / "run")
    assert args.bc_dagger == 0
    seed_everything(args.seed)
    model = make_model(args, make_env(args, sc), None)
    out = warm_start(args, sc, model, tmp_path / "run")
    seed_everything(args.seed)
    ref = make_model(args, make_env(args, sc), None)
    demos = collect_demos(
        sc, INC, "lawnmower", 2, np.random.SeedSequence(args.seed, spawn_key=DEMO_KEY)
    )
    fit_rng = np.random.default_rng(np.random.SeedSequence(args.seed, spawn_key=FIT_KEY))
    pretrain(ref, demos, epochs=3, batch_size=64, seed=fit_rng, log_std=args.bc_log_std)
    assert same_weights(model, ref)
    assert "dagger" not in out and "dagger" not in json.loads(
        (tmp_path / "run/bc.json").read_text()
    )
    assert not (tmp_path / "run" / "bc_dagger").exists()


def test_a_dagger_iteration_labels_the_learners_states_with_the_teachers_actions():
    """The rows are the states the learner flew into (its own actions, the return autopilot
    taking home the UAVs eq. 18 sends home) and each label is what a fresh teacher, planned on
    the same prior and asked along the same flight, answers there; the autopilot's rows have no
    label. Checked by replaying the first episode independently."""
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.sim.autopilot import returning
    from poc_env.sim.control import return_home
    from poc_env.sim.engine import RandomPrior
    from poc_env.sim.observations import CompassFeatures, decode_vector, split_observation

    sc = load_scenario("small")
    args = _args(Path("unused"))
    seed_everything(0)
    model = make_model(args, make_env(args, sc), None)  # an untrained learner: far off route
    ss = np.random.SeedSequence(5, spawn_key=(*DAGGER_KEY, 1))
    demos, counts = dagger_rollouts(sc, INC, "lawnmower", model, 1, ss, return_autopilot=True)
    assert counts["labelled"] == demos.samples > 0
    assert counts["rows"] == counts["labelled"] + counts["autopilot"] and counts["autopilot"] > 0
    # the replay: same seed and prior, the learner's mean and the autopilot fly, a second
    # teacher is asked at every state
    env = UAVSearchParallelEnv(scenario=sc)
    p = env.params
    rng = np.random.default_rng(np.random.SeedSequence(5, spawn_key=(*DAGGER_KEY, 1)))
    seed = int(rng.integers(0, 2**31))
    prior = RandomPrior().draw(p.grid, rng)
    assert demos.seeds == (seed,)
    obs, _ = env.reset(seed=seed, options={"prior": prior})
    teacher = make_policy("lawnmower")
    teacher.reset(env, seed)
    feats_fn = CompassFeatures(p, True)
    agents = list(env.possible_agents)
    rows: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {k: [] for k in range(len(agents))}
    own: list[np.ndarray] = []
    while env.agents:
        live = list(env.agents)
        k = np.array([agents.index(a) for a in live])
        ras, vec = zip(*(split_observation(obs[a], p.grid.shape) for a in live), strict=True)
        feats = feats_fn(np.stack(ras), np.stack(vec), k)
        act, _ = model.predict(feats, deterministic=True)
        q = decode_vector(p, np.stack(vec))
        home = returning(p, q["xy"], q["usable"], k)
        inc = return_home(p, q, np.asarray(act, float), k)
        labels, _ = teacher.predict(obs)
        for j, a in enumerate(live):
            if not home[j]:
                rows[int(k[j])].append((feats[j], np.clip(labels[a], -1, 1)))
                own.append(np.asarray(act[j], float))
        obs, *_ = env.step({a: inc[j].astype(np.float32) for j, a in enumerate(live)})
    flat = [r for k in sorted(rows) for r in rows[k]]  # the demos' order: UAV by UAV
    assert demos.samples == len(flat)
    np.testing.assert_array_equal(demos.obs, np.stack([f for f, _ in flat]).astype(np.float32))
    np.testing.assert_allclose(demos.labels, np.stack([lab for _, lab in flat]), atol=1e-6)
    # the labels are the teacher's, not the learner's own actions
    order = np.argsort([k for k in sorted(rows) for _ in rows[k]], kind="stable")
    assert len(order) == len(own)
    assert np.mean(np.abs(demos.labels - np.stack(own)[order]).max(axis=1) > 0.1) > 0.3
    # and the states are not the teacher's own: its demonstration of the same episode differs
    t_demos = collect_demos(
        sc, INC, "lawnmower", 1, np.random.SeedSequence(5, spawn_key=(*DAGGER_KEY, 1))
    )
    assert t_demos.seeds == demos.seeds
    n = min(t_demos.samples, demos.samples)
    assert not np.allclose(t_demos.obs[:n], demos.obs[:n])


def test_dagger_aggregates_refits_and_records_every_iteration(tmp_path, same_weights):
    """Each iteration adds exactly its labelled rows to all the data so far, refits from the
    current weights, and is recorded in bc.json; the run's model is the last iteration's; the
    same seed gives the same run."""
    run = train(_args(tmp_path / "run", bc_dagger=2, bc_dagger_episodes=1, bc_dagger_epochs=2))
    bc = json.loads((run / "bc.json").read_text())
    recs = bc["dagger"]
    assert [r["iteration"] for r in recs] == [1, 2]
    total = bc["samples"]
    for r in recs:
        assert r["samples_new"] == r["labelled"] == r["rows"] - r["autopilot"] > 0
        total += r["samples_new"]
        assert r["samples_total"] == total
        assert r["episodes"] == len(r["rollout_posc"]) == 1
        assert 0.0 <= r["rollout_posc_mean"] <= 1.0 and r["beta"] == 0.0
        assert len(r["epochs_actor_mse"]) == 2
    assert recs[0]["seeds"] != recs[1]["seeds"]  # a fresh stream per iteration
    files = sorted(p.name for p in (run / "bc_dagger").iterdir())
    assert files == ["iter_0.zip", "iter_1.zip", "iter_2.zip"]
    assert same_weights(run / "model.zip", run / "bc_dagger" / "iter_2.zip")
    assert not same_weights(run / "bc_dagger" / "iter_0.zip", run / "bc_dagger" / "iter_1.zip")
    assert load_policy(run / "model.zip").num_timesteps == 0
    again = train(_args(tmp_path / "again", bc_dagger=2, bc_dagger_episodes=1, bc_dagger_epochs=2))
    assert same_weights(again / "model.zip", run / "model.zip")


def test_dagger_streams_are_new():
    """DAgger's seeds and priors come from none of the demonstration, fit, training or
    evaluation streams of the run's seed."""
    import poc_env.limits as limits
    from poc_env.agents.experiments.evaluate import EVAL_PRIOR_STREAM

    seed = 3
    dag = [np.random.SeedSequence(seed, spawn_key=(*DAGGER_KEY, i)).generate_state(4)
           for i in range(1, 9)]  # fmt: skip
    others = [np.random.SeedSequence(seed, spawn_key=k) for k in (DEMO_KEY, FIT_KEY)]
    others += [*np.random.SeedSequence(seed).spawn(limits.N_ENVS_MAX)]
    others += [np.random.SeedSequence([seed, EVAL_PRIOR_STREAM])]
    for d in dag:
        for o in others:
            assert not np.array_equal(d, o.generate_state(4))
    assert len({tuple(d) for d in dag}) == len(dag)


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"bc_dagger": -1}, "bc_dagger"),
        ({"bc_dagger": 1, "bc_dagger_episodes": 0}, "bc_dagger_episodes"),
        ({"bc_dagger": 1, "bc_dagger_epochs": 0}, "bc_dagger_epochs"),
        ({"bc_dagger": 1, "bc_dagger_beta": 1.5}, "bc_dagger_beta"),
        ({"bc_dagger": 1, "bc_dagger_beta": float("nan")}, "bc_dagger_beta"),
        ({"bc_dagger": 1, "task": HEAD}, "bc_dagger"),  # labels at the increments level only
    ],
)
def test_bad_dagger_options_name_the_field(kw, field):
    with pytest.raises(ConfigError) as err:
        TrainArgs(**{"task": INC, "bc_teacher": "lawnmower", **kw})
    assert err.value.field == field
    if kw.get("task") == HEAD:
        assert "increments" in str(err.value) and HEAD in str(err.value)


def test_dagger_options_on_the_command_line():
    base = ["--task", INC, "--bc-teacher", "lawnmower", "--total-timesteps", "0"]
    args = parse_train_args([*base, "--bc-dagger", "3", "--bc-dagger-episodes", "5",
                             "--bc-dagger-epochs", "7", "--bc-dagger-beta", "0.5"])  # fmt: skip
    assert (args.bc_dagger, args.bc_dagger_episodes, args.bc_dagger_epochs) == (3, 5, 7)
    assert args.bc_dagger_beta == 0.5
    with pytest.raises(ConfigError) as err:  # ignored without --bc-dagger: an error
        parse_train_args([*base, "--bc-dagger-episodes", "5"])
    assert err.value.field == "bc_dagger_episodes"
    with pytest.raises(ConfigError) as err:
        parse_train_args(["--task", INC, "--total-timesteps", "10", "--bc-dagger", "2"])
    assert err.value.field == "bc_dagger"


def test_beta_one_flies_the_teacher():
    """With the mixture at 1 every UAV flies the teacher's action: the labelled states are the
    teacher's own demonstration of the same episode (less the rows the autopilot flies home);
    at 0 they are not."""
    sc = load_scenario("small")
    seed_everything(0)
    args = _args(Path("unused"))
    model = make_model(args, make_env(args, sc), None)
    ss = np.random.SeedSequence(9, spawn_key=(*DAGGER_KEY, 1))
    mixed, counts = dagger_rollouts(
        sc, INC, "lawnmower", model, 1, ss, return_autopilot=True, beta=1.0
    )
    assert counts["teacher_flown"] == counts["labelled"] > 0
    own = collect_demos(
        sc, INC, "lawnmower", 1, np.random.SeedSequence(9, spawn_key=(*DAGGER_KEY, 1))
    )
    assert mixed.posc == pytest.approx(own.posc)
    rows = {(int(u), tuple(o)) for u, o in zip(own.uav, own.obs.round(5), strict=True)}
    assert all(
        (int(u), tuple(o)) in rows for u, o in zip(mixed.uav, mixed.obs.round(5), strict=True)
    )
    pure, _ = dagger_rollouts(sc, INC, "lawnmower", model, 1, ss, return_autopilot=True, beta=0.0)
    assert pure.posc != pytest.approx(own.posc)
