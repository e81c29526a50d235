"""Everyday command-line conventions (issue 27 item 10): ``--version`` and ``policies``."""

from __future__ import annotations

import importlib.metadata

import pytest

from poc_env.agents.policies.registry import registered, spec
from poc_env.cli import main


def test_version_prints_the_installed_version(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.strip() == f"poc-env {importlib.metadata.version('poc-env')}"


def test_policies_lists_every_registered_policy_with_what_it_does(capsys):
    assert main(["policies"]) == 0
    out = capsys.readouterr().out
    lines = {line.split()[0]: line for line in out.splitlines() if line and line[0] != " "}
    for spelling in registered():  # each spelling evaluate accepts, with its summary
        assert spelling in lines, spelling
        assert spec(spelling).summary and spec(spelling).summary in lines[spelling]
    from poc_env.agents.policies import plan_choice, replan_choice
    from poc_env.agents.rl.checkpoint import shipped_checkpoints

    for name in shipped_checkpoints():  # the shipped checkpoints, spelled as evaluate takes them
        assert f"  ppo:{name}" in out
    # i24-leftovers, item 2: and the shipped chooser models (they were missing)
    choosers = {"plan_choice": plan_choice, "receding_choice": replan_choice}
    for policy, module in choosers.items():
        assert module.shipped_choosers(), policy  # else the loop below checks nothing
        for name in module.shipped_choosers():
            assert f"  {policy}:{name}" in out
