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
    names = ["episodes.csv", "evaluate.csv", "evaluate.txt", "paired.csv"]
    assert sorted(p.name for p in out.iterdir()) == names


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


def test_env_checkers_pass_without_the_plot_extra():
    """Issue 27: on an ``[rl]`` install (no matplotlib) SB3's ``check_env`` on the Gymnasium
    view and PettingZoo's ``parallel_api_test`` pass when ``render_mode`` is None; asking for a
    render mode names the ``plot`` extra when the env is made, and ``render()`` without one
    warns and returns None (Gymnasium's convention), never a ModuleNotFoundError."""
    code = HIDE.format(mods=["matplotlib", "PIL"]) + (
        "import warnings\n"
        "import poc_env\n"
        "from pettingzoo.test import parallel_api_test\n"
        "from stable_baselines3.common.env_checker import check_env\n"
        "from poc_env.envs.gymnasium_env import UAVSearchGym\n"
        "from poc_env.errors import MissingExtraError\n"
        "check_env(UAVSearchGym(scenario='small', obs_type='flat'))\n"
        "parallel_api_test(poc_env.parallel_env('small'), num_cycles=3)\n"
        "for make in (poc_env.parallel_env, poc_env.env):\n"
        "    try:\n"
        "        make('small', render_mode='rgb_array')\n"
        "    except MissingExtraError as err:\n"
        "        assert err.extra == 'plot', err\n"
        "    else:\n"
        "        raise AssertionError('render_mode without matplotlib was accepted')\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        "    assert UAVSearchGym(scenario='small').render() is None\n"
        "assert any('render_mode=None' in str(w.message) for w in caught), caught\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().endswith("ok")
