"""Every ``--help`` shows its options' defaults, and every example in it runs (issue 27 item 10:
``plan --help`` showed ``uav.count=3``, a key the scenario refuses; defaults were not shown).

The parsers are walked, not listed: a new subcommand or benchmark is covered by itself. Each
example command line is parsed as ``poc-env`` parses it, the names it gives (scenario and its
``KEY=VALUE`` overrides, policies, tasks, experiments, formats, origins) are checked by the
project's own loaders, and the cheap ones (listings, ``spec``, ``--version``) are run.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import shlex

import pytest

from poc_env.cli import BENCHMARKS, build_parser, main, parse_command_line
from poc_env.config import load_scenario, parse_overrides
from poc_env.helptext import help_examples, shown_default, walk

#: Commands whose examples are run, not only parsed (a second or less each).
CHEAP = ("scenarios", "policies", "tasks")


def _parsers():
    """(command path, parser) of every poc-env parser: subcommands and each benchmark's."""
    found = walk(build_parser())
    for module in BENCHMARKS.values():
        found += walk(importlib.import_module(module).build_parser())
    return found


def _train_help() -> str:
    """``poc-env train --help`` (tyro's, from TrainArgs)."""
    from poc_env.agents.rl.args import parse_train_args

    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        parse_train_args(["--help"])
    return out.getvalue()


def _examples() -> list[tuple[str, str]]:
    found = [(path, line) for path, p in _parsers() for line in help_examples(p.format_help())]
    return found + [("poc-env train", line) for line in help_examples(_train_help())]


EXAMPLES = _examples()


def test_every_option_shows_its_default():
    for path, p in _parsers():
        text = "".join(p.format_help().split())  # no whitespace: wrapping (of words too) undone
        for action in p._actions:
            value = shown_default(action)
            if value is not None:
                shown = "".join(f"(default: {value})".split())
                assert shown in text, f"{path} {action.option_strings}: {shown} not in its help"
                once = "".join(f"default: {value}".split())
                assert once + shown not in text, f"{path} {action.option_strings}: shown twice"
        assert "(default:None)" not in text and "==SUPPRESS==" not in text, path
    train = _train_help()
    assert "(default: None)" not in train and "(default: )" not in train
    assert "(default: paper_6_2)" in train and "(default: 1000000)" in train


def test_every_command_has_examples():
    leaves = [
        path
        for path, p in _parsers()
        if not any(a.__class__.__name__ == "_SubParsersAction" for a in p._actions)
        and path != "poc-env train"  # tyro's help, below
    ]
    with_examples = {path for path, _ in EXAMPLES}
    assert [p for p in leaves if p not in with_examples] == []
    assert "poc-env train" in with_examples and "poc-env" in with_examples
    assert len(EXAMPLES) >= 40


def _check_names(ns) -> None:
    """The names an example gives exist: each is handed to the loader that would read it."""
    from poc_env.agents.experiments.evaluate import check_policies
    from poc_env.tasks import get_task

    scenario = getattr(ns, "scenario", None)
    overrides = getattr(ns, "overrides", None) or getattr(ns, "set", None) or []
    if scenario is not None or overrides:
        load_scenario(scenario or "paper_6_2", parse_overrides(list(overrides)))
    policies = [p for p in (getattr(ns, "policies", None) or "").split(",") if p]
    policies += [ns.policy] if isinstance(getattr(ns, "policy", None), str) else []
    if policies:
        check_policies(policies)
    baseline = getattr(ns, "baseline", None)
    if baseline and policies:
        assert set(baseline.split(",")) <= set(policies), baseline
    task = getattr(ns, "task", None)
    tasks = list(getattr(ns, "tasks", None) or []) + (task if isinstance(task, list) else [task])
    for t in tasks:
        if t is not None:
            get_task(t)
    if getattr(ns, "command", None) == "experiment":
        from poc_env.agents.experiments.paper import EXPERIMENTS

        assert ns.name in (*EXPERIMENTS, "all"), ns.name
    if getattr(ns, "command", None) == "export":
        from poc_env.agents.mission.formats import FORMATS

        assert ns.format in FORMATS, ns.format
    if getattr(ns, "optimizer", None) is not None:
        from poc_env.agents.planning.optimizers import OPTIMIZERS

        assert ns.optimizer in OPTIMIZERS, ns.optimizer
    if getattr(ns, "origin", None) is not None:
        from poc_env.agents.mission.crs import make_crs

        make_crs(getattr(ns, "projection", "aeqd"), ns.origin, zone=getattr(ns, "utm_zone", None))


@pytest.mark.parametrize(("path", "line"), EXAMPLES, ids=[line for _, line in EXAMPLES])
def test_every_help_example_parses_and_names_what_exists(path, line, capsys):
    argv = shlex.split(line)[1:]
    assert (line + " ").startswith(path + " "), f"an example of {path} runs another command: {line}"
    if argv == ["--version"]:
        with pytest.raises(SystemExit) as done:
            main(argv)
        assert done.value.code == 0
        return
    try:
        ns = parse_command_line(argv)
    except SystemExit:  # argparse printed why
        pytest.fail(f"{line}: {capsys.readouterr().err}")
    if ns.command == "train":
        from poc_env.agents.rl.args import parse_train_args

        _check_names(parse_train_args(ns.train_options))
        return
    _check_names(ns)
    if ns.command == "bench":
        module = importlib.import_module(BENCHMARKS[ns.what])
        bench = module.build_parser().parse_args(ns.rest)
        if ns.what == "suite":  # its --scenario is a task-id part (Small, Paper62, Paper61)
            bench.scenario = None
        _check_names(bench)
    if ns.command in CHEAP or (ns.command == "spec" and not ns.write):
        assert main(argv) == 0, line
