"""The option groups of ``poc-env train`` (poc_env.agents.rl.args.GROUPS): one help box per
group, the same flags, defaults and help as the flat option list they replaced, and one flat
TrainArgs record (config.json) behind them."""

from __future__ import annotations

import dataclasses
import json
import re
from importlib import resources

import pytest

from poc_env.agents.rl.args import GROUPS, TrainArgs, field_help, parse_train_args

#: Every flag of `poc-env train --help` since the grouping (issue 23): none renamed or lost.
FLAGS = {
    "-h", "--help", "--address", "--agent-index", "--no-agent-index", "--algo",
    "--approach-shaping", "--batch-size", "--bc-batch-size", "--bc-episodes", "--bc-epochs",
    "--bc-log-std", "--bc-teacher", "--checkpoint-every", "--engine", "--ent-coef",
    "--gae-lambda", "--gamma", "--keep-checkpoints", "--learning-rate", "--n-envs",
    "--n-epochs", "--n-steps", "--net-arch", "--num-env-runners", "--overrides", "--progress",
    "--no-progress", "--random-priors", "--no-random-priors", "--recipe", "--resume",
    "--return-autopilot", "--no-return-autopilot", "--rllib-policies", "--run-dir",
    "--scenario", "--seed", "--task", "--torch-threads", "--total-timesteps",
    "--net", "--also-task",  # issue 28: the set network and fleet sizes trained together
    "--residual-teacher", "--residual-pool", "--residual-log-std",  # issue 28: residual policy
    "--bc-dagger", "--bc-dagger-episodes", "--bc-dagger-epochs", "--bc-dagger-beta",  # DAgger
    "--bc-all-tasks", "--no-bc-all-tasks",  # issue 28: BC on every task of a mixed run
    "--from-card",  # issue 28: a shipped checkpoint's recipe, one command
    "--bc-coef", "--bc-coef-half-life",  # issue 28: the BC term during PPO
    "--bc-coef-filter", "--no-bc-coef-filter",
}  # fmt: skip


def _help(capsys, monkeypatch) -> str:
    monkeypatch.setenv("COLUMNS", "80")  # one column of boxes
    with pytest.raises(SystemExit) as stop:
        parse_train_args(["--help"])
    assert stop.value.code == 0
    return capsys.readouterr().out


def _boxes(text: str) -> dict[str, list[str]]:
    """Box title -> the flags listed in it, in order (boxes on a terminal, plain text in a pipe)."""
    out: dict[str, list[str]] = {}
    title = None
    for line in text.splitlines():
        if m := re.match(r"(?:╭─ | )((?:\w+ )?options)(?: ─+╮| *)$", line):
            title = m.group(1)
            out[title] = []
        elif m := re.match(r"(?:│ |  )(--?[a-z][\w-]*)(?:, (--[\w-]+))?(?: |$)", line):
            assert title is not None
            out[title] += [f for f in m.groups() if f]
    return out


def test_groups_partition_the_fields():
    names = [n for _, group in GROUPS.values() for n in group]
    fields = {f.name for f in dataclasses.fields(TrainArgs)}
    assert len(names) == len(set(names)) and set(names) < fields
    assert set(GROUPS) & fields == set()  # a group's name is no option


def test_help_has_a_box_per_group_and_the_same_flags(capsys, monkeypatch):
    boxes = _boxes(_help(capsys, monkeypatch))
    assert list(boxes) == ["options", *(f"{g} options" for g in GROUPS)]
    assert {f for flags in boxes.values() for f in flags} == FLAGS
    for group, (_, names) in GROUPS.items():
        assert boxes[f"{group} options"] == [
            flag
            for n in names
            for flag in ("--" + n.replace("_", "-"), "--no-" + n.replace("_", "-"))
            if flag in FLAGS
        ]


def test_each_option_keeps_its_docstring_as_help(capsys, monkeypatch):
    text = " ".join(_help(capsys, monkeypatch).replace("│", " ").split())
    for name, doc in field_help().items():
        assert " ".join(doc.split()) in text, name


def test_options_of_every_group_parse_into_one_flat_record():
    task = "poc_env/UAVSearch-Small-Heading-v0"
    argv = ["--seed", "3", "--n-steps", "8", "--task", task, "--no-agent-index"]
    argv += ["--bc-teacher", "lawnmower", "--bc-epochs", "4", "--net-arch", "16", "16"]
    assert parse_train_args(argv) == TrainArgs(
        seed=3,
        n_steps=8,
        task=task,
        agent_index=False,
        bc_teacher="lawnmower",
        bc_epochs=4,
        net_arch=[16, 16],
    )
    argv = ["--engine", "rllib", "--rllib-policies", "per_uav", "--num-env-runners", "1"]
    assert parse_train_args(argv) == TrainArgs(
        engine="rllib", rllib_policies="per_uav", num_env_runners=1
    )


def test_stored_configs_still_load():
    """config.json stays the flat TrainArgs: the shipped RLlib run's (written before the
    grouping, without the fields added since) and one written now round-trip."""
    shipped = resources.files("poc_env.agents") / "checkpoints/rllib_heading_paper_6_2"
    data = json.loads((shipped / "config.json").read_text())
    args = TrainArgs.from_dict(data, "config.json")
    assert (args.engine, args.task, args.n_steps) == ("rllib", data["task"], 2048)
    assert args.bc_teacher is None and args.agent_index  # absent keys take their defaults
    now = TrainArgs(engine="rllib", task=data["task"], num_env_runners=1)
    assert TrainArgs.from_dict(json.loads(json.dumps(dataclasses.asdict(now)))) == now
