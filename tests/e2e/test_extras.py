"""A command whose optional dependency group is missing names the extra to install."""

from __future__ import annotations

import subprocess
import sys

import pytest

HIDE = "import sys\nfor m in {mods!r}:\n    sys.modules[m] = None  # import m raises\n"
RUN = "from poc_env.cli import main\nsys.exit(main({argv!r}))\n"


@pytest.mark.parametrize(
    "mods,argv,extra",
    [
        (["torch", "stable_baselines3"], ["train", "--scenario", "small"], "rl"),
        (["matplotlib", "PIL"], ["figures", "--out", "{tmp}"], "plot"),
    ],
)
def test_missing_extra_is_named(tmp_path, mods, argv, extra):
    argv = [a.format(tmp=tmp_path) for a in argv]
    code = HIDE.format(mods=mods) + RUN.format(argv=argv)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 2, out.stderr
    assert f"pip install 'poc-env[{extra}]'" in out.stderr
    assert "Traceback" not in out.stderr


def test_environment_needs_no_extra():
    """parallel_env, reset and step with torch, SB3 and matplotlib unavailable."""
    code = HIDE.format(mods=["torch", "stable_baselines3", "matplotlib", "PIL"]) + (
        "import poc_env\n"
        "env = poc_env.parallel_env('small')\n"
        "env.reset(seed=0)\n"
        "env.step({a: env.action_space(a).sample() for a in env.agents})\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
