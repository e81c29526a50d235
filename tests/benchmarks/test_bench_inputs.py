"""``poc-env bench NAME`` with bad values: a clear ``error: FIELD: ...`` (exit status 2), never
a traceback nor a table of ``nan`` / ``0 in 0.0 s`` from a count below one."""

import importlib
import subprocess
import sys

import pytest

from poc_env.cli import BENCHMARKS
from poc_env.errors import ConfigError


@pytest.mark.parametrize(
    "module, argv, field",
    [
        ("env", ["--envs", "1", "--runs", "0", "--no-mpe", "--no-memory"], "runs"),
        ("env", ["--envs", "0", "--runs", "1", "--no-mpe", "--no-memory"], "envs"),
        ("plan", ["--runs", "0"], "runs"),
        ("plan", ["--quality", "--seeds", "0"], "seeds"),
        ("moving_bound", ["--scenario", "small", "--runs", "0", "--steps", "5"], "runs"),
        ("moving_bound", ["--scenario", "small", "--runs", "1", "--steps", "0"], "steps"),
        ("suite", ["--runs", "0", "--skip-sb3", "--skip-rllib"], "runs"),
        ("train", ["--iterations", "0"], "iterations"),
    ],
)
def test_a_count_below_one_is_refused_naming_it(module, argv, field):
    """A count of runs, seeds, envs, steps or iterations below one: refused before any work
    (it ended in ``no median for empty data``, a ``KeyError``, or a table of ``nan``)."""
    main = importlib.import_module(f"poc_env.agents.benchmarks.{module}").main
    with pytest.raises(ConfigError, match=rf"^{field}: got [-0-9]+; allowed: an integer >= 1"):
        main(argv)


@pytest.mark.parametrize("what", ["env", "plan", "train", "moving-bound"])
def test_bench_bad_input_ends_as_an_error_line_not_a_traceback(what):
    """An unknown scenario to ``poc-env bench NAME``: ``error: scenario: ...`` and status 2, as
    the other benchmarks (their ``__main__`` is ``run_main``)."""
    r = subprocess.run(
        [sys.executable, "-m", BENCHMARKS[what], "--scenario", "nosuch"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("error: scenario: got 'nosuch'")
    assert "Traceback" not in r.stderr


@pytest.mark.parametrize("module", ["baselines", "generalise", "learning", "peers"])
def test_an_unwritable_out_is_refused_before_any_work(tmp_path, monkeypatch, module):
    """``--out`` that is a file: ``out: ...`` before the benchmark runs (it was found after the
    whole run, minutes at full budget, as ``output: got 'FILE/NAME.csv'``)."""
    mod = importlib.import_module(f"poc_env.agents.benchmarks.{module}")

    def no_work(*args, **kwargs):
        raise AssertionError("the benchmark ran before its --out was checked")

    for name in ("run", "measure"):
        if hasattr(mod, name):
            monkeypatch.setattr(mod, name, no_work)
    (tmp_path / "a_file").write_text("x")
    argv = ["--out", str(tmp_path / "a_file")]
    if module == "learning":
        argv += ["--recipe", f"r={tmp_path}"]
    with pytest.raises(ConfigError, match=r"^out: got '.*a_file'; allowed: a folder path"):
        mod.main(argv)


def test_bench_plan_scale_out_and_seeds_checked_before_the_run(tmp_path, monkeypatch):
    """``bench plan --scale --scale-out FOLDER`` (or a negative ``--seed0``, ``--zones``): refused
    naming the option before the scale run, not found after it."""
    from poc_env.agents.benchmarks import plan, plan_scale

    def no_work(*args, **kwargs):
        raise AssertionError("the scale run started before its options were checked")

    monkeypatch.setattr(plan_scale, "main", no_work)
    with pytest.raises(ConfigError, match=r"^scale_out: got .*; allowed: a file path"):
        plan.main(["--scale", "--scale-out", str(tmp_path)])
    with pytest.raises(ConfigError, match=r"^seed0: got -1; allowed: an integer >= 0"):
        plan.main(["--sweep", "100,300,0.2,0.1", "--seed0", "-1"])
    with pytest.raises(ConfigError, match=r"^zones: got -1; allowed: an integer >= 0"):
        plan.main(["--scale", "--zones", "-1"])


@pytest.mark.parametrize("option, value", [("--frame-min", "0"), ("--swirl", "nan")])
def test_bench_moving_bound_bad_frame_interval_or_swirl_refused(option, value):
    """``--frame-min 0`` ended in ``ZeroDivisionError``; a NaN swirl drifted the belief by NaN."""
    from poc_env.agents.benchmarks import moving_bound

    field = option[2:].replace("-", "_")
    with pytest.raises(ConfigError, match=rf"^{field}: got {value}"):
        moving_bound.main(["--scenario", "small", "--runs", "1", "--steps", "3", option, value])


def test_bench_baselines_random_column_is_each_tasks_own_floor():
    """``bench baselines --policies random,random_heading,...``: the ``random`` column is the
    floor of each task's control level (it showed whichever floor came last: Increments'
    ``random`` cell held ``random_heading``'s 0.036 where its own was 0.085)."""
    from poc_env.agents.benchmarks.baselines import to_markdown

    def row(task, policy, posc):
        return {"task": f"poc_env/UAVSearch-Small-{task}-v0", "policy": policy, "label": policy,
                "episodes": 20, "posc_mean": posc, "posc_ci95": 0.01, "normalised": posc,
                "violation_steps": 1.0}  # fmt: skip

    md = to_markdown(
        [row("Increments", "random", 0.085), row("Increments", "random_heading", 0.036),
         row("Heading", "random", 0.085), row("Heading", "random_heading", 0.036)],
        "cmd",
    )  # fmt: skip
    lines = md.splitlines()
    assert lines[0] == "| task | random | random_heading (heading) | random (increments) |"
    cell = "{:.3f} ± 0.010 ({:.3f}; 1)".format
    inc, head = cell(0.085, 0.085), cell(0.036, 0.036)
    assert lines[2] == f"| UAVSearch-Small-Increments-v0 | {inc} | {head} | - |"
    assert lines[3] == f"| UAVSearch-Small-Heading-v0 | {head} | - | {inc} |"


def test_bench_env_flies_the_fleet_size_asked(monkeypatch, capsys):
    """``bench env --uavs N`` (scale-audit): the core, the PettingZoo env and the memory figure
    fly N UAVs spread over the scenario's airfields (as ``Scenario.with_uavs``), the lines say
    N and not a YAML fleet; a size outside 1-64 is refused naming ``uavs``."""
    from poc_env.agents.benchmarks import env as bench

    seen = {}
    monkeypatch.setattr(bench, "bench_core", lambda p, e, r: seen.setdefault("core", p.n_agents))
    monkeypatch.setattr(
        bench, "bench_pettingzoo", lambda s, o, r: seen.setdefault("pz", o["fleet"]) and 1.0
    )
    monkeypatch.setattr(
        bench, "peak_memory", lambda s, o, e, t: seen.setdefault("mem", o) and (1, 1)
    )
    bench.main(["--scenario", "wide_400", "--uavs", "24", "--envs", "1", "16", "--runs", "1",
                "--no-mpe"])  # fmt: skip
    assert seen["core"] == 24
    assert seen["pz"] == [{"takeoff": a, "count": 8} for a in "ABC"]
    assert seen["mem"]["fleet"] == seen["pz"]
    out = capsys.readouterr().out
    assert "N=24" in out and "fleet" not in out
    with pytest.raises(ConfigError, match=r"^uavs: got 65; allowed: an integer in \[1, 64\]"):
        bench.main(["--scenario", "wide_400", "--uavs", "65", "--no-mpe", "--no-memory"])
