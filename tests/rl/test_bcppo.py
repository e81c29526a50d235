"""The BC term during PPO (poc_env.agents.rl.bcppo, ``poc-env train --bc-coef C``): 0 is
today's training, the term pulls the policy toward the demonstrations, the decay schedule,
bad options, and resume with the same demonstrations."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from poc_env.agents.rl import bcppo
from poc_env.agents.rl.args import TrainArgs, parse_train_args
from poc_env.agents.rl.bc import DEMOS_FILE, bc_losses, load_demos, save_demos
from poc_env.agents.rl.checkpoint import checkpoint_steps, load_policy
from poc_env.agents.rl.train import train
from poc_env.errors import ConfigError

INC = "UAVSearch-Small-Random-Increments-v0"
# SB3_LOGS: SB3 writes the train/ scalars of the update after rollout k with rollout k + 1's
# (at its step); the last update's are not written: 3 updates -> 2 points
# small: 3 UAVs; 2 envs x 3 UAVs = 6 slots, 128 steps per slot: rollouts of 768 transitions
ROLLOUT = 768


#: The BC term's coefficient of the tiny runs: strong, so that a few updates show its pull.
BC_COEF = 100.0


def _args(run_dir: Path, **kw) -> TrainArgs:
    base = dict(
        task=INC,
        bc_teacher="greedy_bayes",
        bc_episodes=2,
        bc_epochs=3,
        total_timesteps=2048,  # 3 rollouts
        n_envs=2,
        n_steps=128,
        batch_size=128,
        n_epochs=4,  # 24 minibatch updates a rollout
        checkpoint_every=1,  # one checkpoint per rollout
        keep_checkpoints=0,
        progress=False,
        run_dir=str(run_dir),
    )
    base.update(kw)
    return TrainArgs(**base)


def _scalars(run: Path, tag: str) -> list[tuple[int, float]]:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    out: list[tuple[int, float]] = []
    for log in sorted((run / "tb").glob("ppo_*")):
        acc = EventAccumulator(str(log), size_guidance={"scalars": 0})
        acc.Reload()
        if tag in acc.Tags()["scalars"]:
            out += [(e.step, e.value) for e in acc.Scalars(tag)]
    return out


@pytest.fixture(scope="module")
def plain_run(tmp_path_factory) -> Path:
    """A tiny BC + PPO run with the default --bc-coef 0."""
    return train(_args(tmp_path_factory.mktemp("bcppo") / "plain"))


@pytest.fixture(scope="module")
def bc_run(tmp_path_factory) -> Path:
    """The same run with a strong BC term (constant)."""
    return train(_args(tmp_path_factory.mktemp("bcppo") / "bc", bc_coef=BC_COEF))


# -- C = 0 -------------------------------------------------------------------------------------
def test_bc_coef_zero_is_todays_training(plain_run, tmp_path, monkeypatch, same_weights):
    """--bc-coef 0 is plain PPO (no demos file, no BC scalars); and the BC machinery with
    C_t = 0 (demos loaded, a minibatch drawn and its loss logged at every update) trains the
    same weights bit for bit: it draws from no global generator and adds no gradient."""
    assert not (plain_run / DEMOS_FILE).exists()
    assert _scalars(plain_run, "train/bc_coef") == []
    monkeypatch.setattr(bcppo, "bc_coef_at", lambda *a: 0.0)
    run = train(_args(tmp_path / "zero", bc_coef=1.0))
    assert same_weights(run / "model.zip", plain_run / "model.zip")
    assert [v for _, v in _scalars(run, "train/bc_coef")] == [0.0, 0.0]  # SB3_LOGS
    assert len(_scalars(run, "train/bc_loss")) == 2


# -- C > 0 -------------------------------------------------------------------------------------
def test_the_bc_term_pulls_the_policy_toward_the_demonstrations(plain_run, bc_run):
    """After the same warm start and PPO budget, the run with the BC term is nearer the
    teacher's labels than its start, which plain PPO leaves, and its logged BC loss falls."""
    demos = load_demos(bc_run / DEMOS_FILE)
    a = json.loads((plain_run / "bc.json").read_text())
    b = json.loads((bc_run / "bc.json").read_text())
    assert a["after"] == b["after"]  # the same start
    mse_plain = bc_losses(load_policy(plain_run / "model.zip"), demos)["actor_mse"]
    mse_bc = bc_losses(load_policy(bc_run / "model.zip"), demos)["actor_mse"]
    print(f"demo actor MSE: start {b['after']['actor_mse']:.5f}, plain PPO {mse_plain:.5f}, "
          f"with the BC term {mse_bc:.5f}")  # fmt: skip
    # PPO alone moves away from the labels; with the term the policy ends nearer than it began
    assert mse_bc < b["after"]["actor_mse"] < mse_plain
    losses = [v for _, v in _scalars(bc_run, "train/bc_loss")]
    assert len(losses) == 2 and losses[-1] < losses[0]
    assert [v for _, v in _scalars(bc_run, "train/bc_coef")] == [BC_COEF] * 2


def test_the_demos_file_holds_the_warm_starts_demonstrations(bc_run, tmp_path):
    demos = load_demos(bc_run / DEMOS_FILE)
    bc = json.loads((bc_run / "bc.json").read_text())
    assert demos.samples == bc["samples"] and list(demos.seeds) == bc["seeds"]
    assert demos.teacher == "greedy_bayes" and demos.control == "increments"
    again = load_demos(save_demos(demos, tmp_path / "again.npz"))
    for k in ("obs", "labels", "rewards", "returns", "episode", "uav"):
        np.testing.assert_array_equal(getattr(again, k), getattr(demos, k))
    assert (again.posc, again.seeds, again.gamma) == (demos.posc, demos.seeds, demos.gamma)


def test_actor_loss_weights_select_rows():
    import torch as th

    from poc_env.agents.rl.bc import actor_loss

    class Mean:  # a policy whose Gaussian mean is its observation
        def get_distribution(self, obs):
            class D:
                def mode(self):
                    return obs

            return D()

    obs = th.tensor([[0.0, 0.0], [1.0, 1.0], [0.0, 2.0]], requires_grad=True)
    lab = th.zeros(3, 2)
    assert float(actor_loss(Mean(), obs, lab)) == pytest.approx((0 + 2 + 4) / 6)
    assert float(actor_loss(Mean(), obs, lab, th.ones(3))) == pytest.approx((0 + 2 + 4) / 6)
    assert float(actor_loss(Mean(), obs, lab, th.tensor([0.0, 1.0, 0.0]))) == pytest.approx(1.0)
    none = actor_loss(Mean(), obs, lab, th.zeros(3))
    none.backward()
    assert float(none) == 0.0 and float(obs.grad.abs().sum()) == 0.0


def test_a_filtered_run_imitates_only_the_rows_where_the_teacher_did_better(tmp_path):
    """--bc-coef-filter: the kept share (rows whose demo return beats the critic) is logged,
    strictly between none and all after the warm start's value fit."""
    run = train(_args(tmp_path / "filtered", bc_coef=BC_COEF, bc_coef_filter=True))
    kept = [v for _, v in _scalars(run, "train/bc_filter_kept")]
    print("kept", kept)
    assert len(kept) == 2 and all(0.0 < k < 1.0 for k in kept)
    assert len(_scalars(run, "train/bc_loss")) == 2


# -- the schedule ------------------------------------------------------------------------------
def test_the_half_life_schedule():
    assert bcppo.bc_coef_at(2.0, 0, 10**9) == 2.0  # constant
    assert bcppo.bc_coef_at(2.0, 1000, 0) == 2.0
    assert bcppo.bc_coef_at(2.0, 1000, 1000) == pytest.approx(1.0)
    assert bcppo.bc_coef_at(2.0, 1000, 3000) == pytest.approx(0.25)


def test_a_run_logs_the_decayed_coefficient_at_each_update(tmp_path):
    run = train(_args(tmp_path / "decay", bc_coef=4.0, bc_coef_half_life=ROLLOUT))
    logged = _scalars(run, "train/bc_coef")
    # one update after each rollout, at t = 1, 2, 3 rollouts: C_t = 4 x 0.5, 0.25, 0.125;
    # SB3 writes an update's train/ scalars with the next rollout's (SB3_LOGS)
    assert [s for s, _ in logged] == [2 * ROLLOUT, 3 * ROLLOUT]
    np.testing.assert_allclose([v for _, v in logged], [2.0, 1.0], rtol=1e-6)


# -- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"bc_coef": -1.0}, "bc_coef"),
        ({"bc_coef": float("nan")}, "bc_coef"),
        ({"bc_coef": 1.0, "bc_coef_half_life": -5}, "bc_coef_half_life"),
        ({"bc_coef": 1.0, "bc_teacher": None}, "bc_coef"),
    ],
)
def test_bad_bc_coef_options_name_the_field(kw, field, tmp_path):
    with pytest.raises(ConfigError) as err:
        _args(tmp_path, **kw)
    assert err.value.field == field


def test_bc_coef_options_on_the_command_line():
    argv = ["--task", INC, "--bc-teacher", "lawnmower"]
    args = parse_train_args([*argv, "--bc-coef", "0.5", "--bc-coef-half-life", "1000000"])
    assert (args.bc_coef, args.bc_coef_half_life) == (0.5, 1_000_000)
    with pytest.raises(ConfigError) as err:  # a half-life without the term does nothing
        parse_train_args([*argv, "--bc-coef-half-life", "1000"])
    assert err.value.field == "bc_coef_half_life"
    with pytest.raises(ConfigError) as err:
        parse_train_args([*argv, "--bc-coef-filter"])
    assert err.value.field == "bc_coef_filter"
    assert parse_train_args([*argv, "--bc-coef", "1", "--bc-coef-filter"]).bc_coef_filter
    with pytest.raises(ConfigError) as err:
        parse_train_args(["--task", INC, "--bc-coef", "1"])
    assert err.value.field == "bc_coef"


# -- resume ------------------------------------------------------------------------------------
def test_a_resumed_run_continues_with_the_same_demonstrations(
    bc_run, tmp_path, monkeypatch, same_weights
):
    """Killed in its second rollout and resumed: no warm start again, the demonstrations read
    from the run folder, and the weights of the uninterrupted run, bit for bit. Without the
    demos file the resume is refused, naming the field."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Interrupt(Exception):
        pass

    class Kill(BaseCallback):
        def _on_step(self) -> bool:
            if self.model.num_timesteps >= ROLLOUT + 300:
                raise Interrupt
            return True

    run = tmp_path / "killed"
    with pytest.raises(Interrupt):
        train(_args(run, bc_coef=BC_COEF), callback=Kill())
    assert checkpoint_steps(run) == [ROLLOUT]
    demos_before = (run / DEMOS_FILE).read_bytes()

    def no_bc(*a, **k):
        raise AssertionError("BC repeated on resume")

    monkeypatch.setattr("poc_env.agents.rl.bc.warm_start", no_bc)
    (run / "moved.npz").write_bytes(demos_before)
    (run / DEMOS_FILE).unlink()
    with pytest.raises(ConfigError) as err:
        train(TrainArgs(resume=str(run), progress=False))
    assert err.value.field == "bc_coef" and DEMOS_FILE in str(err.value)
    (run / "moved.npz").rename(run / DEMOS_FILE)
    train(TrainArgs(resume=str(run), progress=False))
    assert same_weights(run / "model.zip", bc_run / "model.zip")
    assert (run / DEMOS_FILE).read_bytes() == demos_before
