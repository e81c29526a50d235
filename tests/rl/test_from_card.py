"""``poc-env train --from-card NAME``: a shipped checkpoint's recipe as one command."""

from __future__ import annotations

import dataclasses
import json

import pytest

from poc_env.agents.rl.args import (
    TrainArgs,
    card_names,
    card_options,
    changed_fields,
    check_used,
    parse_train_args,
)
from poc_env.errors import ConfigError

CARD = "ppo_set_increments_anysize"


def test_every_card_is_a_recipe_train_accepts() -> None:
    # a card whose options no longer build a TrainArgs (a field renamed, a value now refused)
    # would make its recipe unreproducible: every shipped card must parse
    assert CARD in card_names() and "rllib_heading_paper_6_2" in card_names()
    for name in card_names():
        args = parse_train_args(["--from-card", name, "--run-dir", "runs/x"])
        assert args.from_card == name
        assert args.task == card_options(name).get("task")
        # and train() takes it: no field the run would ignore (a card records the task's own
        # scenario, which the Python-side check of train() once refused for ppo_drift_small)
        check_used(args, changed_fields(args))


def test_card_options_are_the_defaults_and_given_options_replace_them() -> None:
    card = card_options(CARD)
    args = parse_train_args(
        ["--from-card", CARD, "--seed", "2", "--overrides", "reward.alpha=1", "--run-dir", "r"]
    )
    assert (args.seed, args.overrides, args.run_dir) == (2, ["reward.alpha=1"], "r")
    # everything not given is the card's, not TrainArgs' default
    for name in ("task", "also_task", "net", "bc_teacher", "bc_log_std", "bc_all_tasks",
                 "n_envs", "batch_size", "total_timesteps", "return_autopilot"):  # fmt: skip
        assert getattr(args, name) == card[name], name
    assert args.bc_log_std != TrainArgs.bc_log_std and args.net != TrainArgs.net
    # the run folder's own options never come from a card
    assert not {"run_dir", "resume", "progress"} & set(card)


def test_config_json_records_the_card(tmp_path) -> None:
    # config.json is dataclasses.asdict(args) (agents/rl/train.py), read back by --resume
    args = parse_train_args(["--from-card", CARD, "--run-dir", str(tmp_path)])
    assert json.loads(json.dumps(dataclasses.asdict(args)))["from_card"] == CARD
    again = TrainArgs.from_dict(json.loads(json.dumps(dataclasses.asdict(args))))
    assert again == args and again.from_card == CARD


def test_bad_card_names_the_field_and_the_cards() -> None:
    with pytest.raises(ConfigError, match=r"from_card: got 'nope'.*ppo_set_anysize"):
        parse_train_args(["--from-card", "nope"])
    with pytest.raises(ConfigError, match="from_card"):
        TrainArgs(from_card="../scenario")
    with pytest.raises(ConfigError, match="resume"):
        parse_train_args(["--resume", "runs/x", "--from-card", CARD])


def test_dagger_with_every_task_is_refused() -> None:
    # DAgger relabels --task's episodes only: with --bc-all-tasks it would leave the others'
    # demonstrations unlabelled by the learner's states, so the pair is refused
    argv = ["--task", "UAVSearch-Paper62-Random-Increments-v0", "--also-task",
            "UAVSearch-Paper62-Increments-v0", "--bc-teacher", "allocation_plan"]  # fmt: skip
    assert parse_train_args([*argv, "--bc-dagger", "2"]).bc_dagger == 2
    assert parse_train_args([*argv, "--bc-all-tasks"]).bc_all_tasks
    with pytest.raises(ConfigError, match=r"bc_dagger: got 2.*--bc-all-tasks"):
        parse_train_args([*argv, "--bc-all-tasks", "--bc-dagger", "2"])


def test_docs_table_lists_every_card() -> None:
    # docs/rl.md opens with the table of shipped policies: one row and the count per card
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "rl.md").read_text(encoding="utf-8")
    table = text.split("\n\n| name |", 1)[1].split("\n\n", 1)[0]
    rows = [line.split("`")[1] for line in table.splitlines()[2:]]
    assert sorted(rows) == card_names()
    words = ["One", "Two", "Three", "Four", "Five", "Six", "Seven", "Eight", "Nine", "Ten"]
    assert f"{words[len(rows) - 1]} policies are shipped" in text
