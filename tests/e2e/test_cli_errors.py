"""Bad command-line arguments end in ``error: <field>: ...`` with exit 2, before any output.

Every case checks the exit status, the message naming the field, the absence of a traceback,
and that the working folder holds exactly what it held before (no partial result).
"""

import os
import sys

import pytest

from poc_env.cli import main


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


# (argv with {d}: a folder, {f}: a file, {p}: a stand-in plan.json; the field in the error)
CASES = [
    (["survey", "--out", "{f}"], "out"),
    (["survey", "--out", "{f}/sub"], "out"),
    (["evaluate", "--episodes", "1", "--out", "{f}"], "out"),
    (["evaluate", "--episodes", "1", "--out", "{f}/sub/deeper"], "out"),
    (["render", "--max-steps", "2", "--out", "{d}"], "out"),
    (["render", "--max-steps", "2", "--out", "{f}/ep.gif"], "out"),
    (["plan", "--scenario", "small", "--out", "{d}"], "out"),
    (["plan", "--scenario", "small", "--out", "{f}/plan.json"], "out"),
    (["plan", "--scenario", "small", "--out", "{d}/plan.json", "--plot", "{d}"], "plot"),
    (["plan", "--scenario", "small", "--out", "{d}/plan.json", "--plot", "{f}/p.png"], "plot"),
    (["figures", "--out", "{f}"], "out"),
    (["demo", "--out", "{f}/demo"], "out"),
    (["experiment", "table4", "--quick", "--out", "{f}"], "out"),
    (["export", "{p}", "--format", "geojson", "--origin", "45,7", "--out", "{f}"], "out"),
    (["curve", "{d}", "--out", "{d}"], "out"),
    (["train", "--scenario", "small", "--run-dir", "{f}"], "run_dir"),
    (["train", "--scenario", "small", "--run-dir", "{f}/run"], "run_dir"),
    (["train", "--scenario", "small", "--n-envs", "1000000000"], "n_envs"),
    (["render", "--seed", "-1", "--out", "{d}/ep.gif"], "seed"),
    (["evaluate", "--seed", "-1", "--episodes", "1"], "seed"),
    (["plan", "--scenario", "small", "--seed", "-1", "--out", "{d}/plan.json"], "seed"),
    (["evaluate", "--policies", "", "--episodes", "1"], "policies"),
    (["evaluate", "--policies", " , ", "--episodes", "1"], "policies"),
    # audit (i28-audit): a repeated policy flew twice, and with --baseline the paired table
    # crashed (IndexError) after every episode had flown
    (["evaluate", "--policies", "random,random", "--episodes", "1"], "policies"),
    (["evaluate", "--policies", "random, lawnmower,random", "--baseline", "random"], "policies"),
    # audit (i28-audit): random priors flown and printed under a fixed-prior task's id
    (["evaluate", "--task", "UAVSearch-Small-Heading-v1", "--random-priors"], "random_priors"),
    (
        ["evaluate", "--task", "UAVSearch-Small-Drift-Heading-v1", "--random-priors"],
        "random_priors",
    ),
    (["plan", "--scenario", "small", "--popsize", "0", "--out", "{d}/plan.json"], "popsize"),
    (["plan", "--popsize", str(10**12), "--out", "{d}/plan.json"], "popsize"),
    (["plan", "--scenario", "small", "--maxiter", "0", "--out", "{d}/plan.json"], "maxiter"),
    (["evaluate", "--episodes", "0"], "episodes"),
    (["render", "--every", "0", "--out", "{d}/ep.gif"], "every"),
]
if sys.platform.startswith("linux") and os.path.isdir("/proc/1"):
    # a folder nobody can create entries in, even root
    CASES.append((["survey", "--out", "/proc/1/poc-env-out"], "out"))


@pytest.mark.parametrize("argv, field", CASES, ids=[" ".join(c[0]) for c in CASES])
def test_bad_argument_is_a_clear_error(tmp_path, monkeypatch, capsys, argv, field):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d").mkdir()
    (tmp_path / "f").write_text("a file")
    (tmp_path / "plan.json").write_text("{}")
    names = {"d": str(tmp_path / "d"), "f": str(tmp_path / "f"), "p": str(tmp_path / "plan.json")}
    before = _tree(tmp_path)
    code = main([a.format(**names) for a in argv])
    err = capsys.readouterr().err
    assert code == 2
    assert f"error: {field}: got " in err and "allowed:" in err
    assert "Traceback" not in err
    assert _tree(tmp_path) == before
    assert (tmp_path / "f").read_text() == "a file"


def test_origin_may_start_with_a_minus(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    args = ["--scenario", "small", "--popsize", "8", "--maxiter", "1", "--quiet"]
    assert main(["plan", *args, "--out", str(plan)]) == 0
    out = tmp_path / "export"
    assert (
        main(["export", str(plan), "--format", "geojson", "--origin", "-45,7", "--out", str(out)])
        == 0
    )
    text = (out / "plan.geojson").read_text()
    assert '"type"' in text
    assert (
        main(["export", str(plan), "--format", "kml", "--origin=-45.5,-7", "--out", str(out)]) == 0
    )
    assert "error" not in capsys.readouterr().err


def test_readme_rl_evaluation_finishes_without_omp_settings(tmp_path):
    """Issue 15 item 14: the README's RL evaluation on two workers, in the environment a new
    user has (no OMP_NUM_THREADS): torch's thread pool is running in the parent, and the
    workers must still finish (they are started by a fork server, and every wait times out)."""
    import subprocess

    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    cmd = [sys.executable, "-m", "poc_env.cli", "evaluate", "--workers", "2", "--episodes", "2",
           "--policies", "ppo:ppo_pilot_paper_6_2,lawnmower", "--quiet"]  # fmt: skip
    done = subprocess.run(
        cmd, env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600, check=False
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "ppo:ppo_pilot_paper_6_2" in done.stdout and "lawnmower" in done.stdout


def test_overrides_on_every_scenario_command(tmp_path, capsys):
    """--overrides KEY=VALUE on plan, evaluate, survey and render changes the scenario (issue
    14 ergonomics) and a bad key or value is a clear error naming it."""
    out = tmp_path / "p.json"
    base = ["plan", "--scenario", "small", "--maxiter", "2", "--popsize", "8", "--quiet"]
    import json

    def feasible(*extra: str) -> list[bool]:
        assert main([*base, "--out", str(out), *extra]) == 0
        return [u["feasible"] for u in json.loads(out.read_text())["uavs"]]

    # the same seed's plan, judged against a shorter endurance: some UAV no longer fits 0.85 T
    assert all(feasible())
    assert not all(feasible("--overrides", "uav.endurance_h=0.5"))
    assert main([*base, "--out", str(out), "--overrides", "reward.alpha='5'"]) == 2
    assert "reward.alpha: got '5'" in capsys.readouterr().err
    ev = [
        "evaluate",
        "--scenario",
        "small",
        "--episodes",
        "1",
        "--policies",
        "lawnmower",
        "--quiet",
    ]
    assert main([*ev, "--overrides", "episode.horizon_steps=3"]) == 0
    assert main([*ev, "--overrides", "nope.key=1"]) == 2
    assert "nope" in capsys.readouterr().err
    assert main(["render", "--out", str(tmp_path / "e.gif"), "--overrides", "episode.dt_s=-1"]) == 2
    assert main(["survey", "--overrides", "sensor.sweep_width_km=abc"]) == 2
    assert "sensor.sweep_width_km" in capsys.readouterr().err


def test_a_merge_refused_at_the_end_names_the_out_option(tmp_path, capsys):
    """``--out DIR`` where DIR holds a file named as a folder the command writes (here
    ``figures``' ``survey_paper_6_1``): the merge is refused, nothing written, and the error
    named a field ``output`` no command has; it names ``out``, the option the user gave."""
    out = tmp_path / "figs"
    out.mkdir()
    (out / "survey_paper_6_1").write_text("mine")
    assert main(["figures", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "error: out: " in err and "survey_paper_6_1" in err, err
    assert sorted(p.name for p in out.iterdir()) == ["survey_paper_6_1"]
    assert (out / "survey_paper_6_1").read_text() == "mine"
