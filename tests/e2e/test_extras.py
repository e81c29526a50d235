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


def test_evaluate_without_the_plot_extra_writes_its_tables_and_says_so(tmp_path):
    """Issue 27 item 7: the tables are written, the figure is left out with a note (it used
    to print the table, then fail for the figure and write no CSV)."""
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "small", "--episodes", "1", "--policies", "lawnmower",
            "--quiet", "--out", str(out)]  # fmt: skip
    code = HIDE.format(mods=["matplotlib", "PIL"]) + RUN.format(argv=argv)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "no posc_over_time.png: it needs the 'plot' extra" in done.stdout
    assert sorted(p.name for p in out.iterdir()) == ["episodes.csv", "evaluate.csv", "evaluate.txt"]


def test_plan_plot_without_the_plot_extra_fails_before_planning(tmp_path):
    """A figure asked for explicitly is checked before the work, and nothing is written."""
    argv = ["plan", "--scenario", "paper_6_2", "--out", str(tmp_path / "plan.json"),
            "--plot", str(tmp_path / "plan.png")]  # fmt: skip
    code = (
        HIDE.format(mods=["matplotlib", "PIL"])
        + "import poc_env.agents.planning.planner as planner\n"
        + "planner.make_plan = None  # planning now would be a TypeError\n"
        + RUN.format(argv=argv)
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 2, done.stderr
    assert "pip install 'poc-env[plot]'" in done.stderr and "Traceback" not in done.stderr
    assert list(tmp_path.iterdir()) == []
