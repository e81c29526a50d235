"""A command's output folder is complete or absent: a failed run leaves the old one intact."""

import subprocess
import sys

import pytest

from poc_env.cli import main
from poc_env.io import atomic_dir


def _leftovers(root):
    return [p.name for p in root.rglob(".*partial-*")]


def test_atomic_dir_new_folder_appears_complete_or_not_at_all(tmp_path):
    dest = tmp_path / "out"
    with pytest.raises(RuntimeError), atomic_dir(dest) as stage:
        (stage / "a.txt").write_text("first")
        raise RuntimeError("killed")
    assert not dest.exists() and not _leftovers(tmp_path)
    with atomic_dir(dest) as stage:
        (stage / "a.txt").write_text("first")
        (stage / "sub").mkdir()
        (stage / "sub" / "b.txt").write_text("second")
        assert not dest.exists()
    assert (dest / "a.txt").read_text() == "first"
    assert (dest / "sub" / "b.txt").read_text() == "second"
    assert not _leftovers(tmp_path)


def test_atomic_dir_existing_folder_keeps_other_files(tmp_path):
    dest = tmp_path / "mine"
    dest.mkdir()
    (dest / "notes.txt").write_text("the user's")
    (dest / "a.txt").write_text("old")
    with pytest.raises(RuntimeError), atomic_dir(dest) as stage:
        (stage / "a.txt").write_text("new")
        raise RuntimeError("killed")
    assert (dest / "a.txt").read_text() == "old"
    with atomic_dir(dest) as stage:
        (stage / "a.txt").write_text("new")
        (stage / "b.txt").write_text("new too")
        assert (dest / "a.txt").read_text() == "old"
    assert (dest / "a.txt").read_text() == "new"
    assert (dest / "b.txt").read_text() == "new too"
    assert (dest / "notes.txt").read_text() == "the user's"
    assert not _leftovers(tmp_path)


def _old_folder(dest):
    """A folder of a previous run plus a file of the user's."""
    dest.mkdir()
    for name in ("a.txt", "b.txt"):
        (dest / name).write_text("old")
    (dest / "notes.txt").write_text("the user's")
    return {"a.txt": "old", "b.txt": "old", "notes.txt": "the user's"}


def _stage_new_run(stage):
    for name in ("a.txt", "b.txt", "c.txt", "d.txt"):
        (stage / name).write_text("new")
    (stage / "sub").mkdir()
    (stage / "sub" / "e.txt").write_text("new")


def _contents(folder):
    return {
        str(p.relative_to(folder)): p.read_text() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def test_a_merge_that_fails_half_way_leaves_the_old_folder(tmp_path, monkeypatch):
    """A merge into an existing folder is all or nothing: a rename failing after some new files
    are in place (here the third, ``c.txt``) puts the old ones back and removes the new ones
    (leftovers #1: the merge renamed the files one at a time, so a failure left old and new
    side by side)."""
    import os

    dest = tmp_path / "out"
    before = _old_folder(dest)
    real_replace = os.replace

    def failing(src, dst, *args, **kwargs):
        if os.fspath(dst).endswith("c.txt"):
            raise OSError(28, "No space left on device")
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(OSError, match="No space"), atomic_dir(dest) as stage:
        _stage_new_run(stage)
    assert _contents(dest) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staging, nothing set aside
    monkeypatch.undo()
    with atomic_dir(dest) as stage:
        _stage_new_run(stage)
    assert _contents(dest) == {
        **{n: "new" for n in ("a.txt", "b.txt", "c.txt", "d.txt", "sub/e.txt")},
        "notes.txt": "the user's",
    }
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_merge_killed_half_way_is_rolled_back_by_the_next_run(tmp_path):
    """A run killed (``os._exit``, no clean-up) after two of its files replaced their namesakes:
    the next run into the folder puts the old files back and removes the killed run's new ones
    before its own merge."""
    dest = tmp_path / "out"
    before = _old_folder(dest)
    script = f"""
import os
from pathlib import Path
from poc_env.io import atomic_dir
real = os.replace
def kill(src, dst, *a, **k):
    if os.fspath(dst).endswith("c.txt"):
        os._exit(9)
    return real(src, dst, *a, **k)
os.replace = kill
with atomic_dir(Path({str(dest)!r})) as stage:
    for name in ("a.txt", "b.txt", "c.txt", "d.txt"):
        (stage / name).write_text("new")
"""
    proc = subprocess.run([sys.executable, "-c", script], check=False)
    assert proc.returncode == 9
    assert (dest / "a.txt").read_text() == "new"  # the killed run got this far
    with atomic_dir(dest) as stage:
        (stage / "x.txt").write_text("next run")
    assert _contents(dest) == {**before, "x.txt": "next run"}
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def _dead_pid() -> int:
    """The PID of a process that has exited (a killed writer's, as far as files can tell)."""
    proc = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(proc.stdout)


def test_staging_of_a_killed_run_is_removed(tmp_path):
    dead = _dead_pid()
    stale = tmp_path / f".out.partial-{dead}-abc"
    stale.mkdir()
    (stale / "half.csv").write_text("x")
    with atomic_dir(tmp_path / "out") as stage:
        (stage / "a.txt").write_text("a")
    assert not stale.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_failed_survey_leaves_the_previous_output(tmp_path, monkeypatch):
    import poc_env.viz.plots as plots

    out = tmp_path / "s"
    assert main(["survey", "--scenario", "paper_6_1", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == ["survey.csv", "survey.png", "survey.txt"]
    (out / "survey.csv").write_text("previous run")
    before["survey.csv"] = b"previous run"

    def broken(*args, **kwargs):
        raise KeyboardInterrupt  # a kill while the figure is drawn, after the CSV was written

    monkeypatch.setattr(plots, "plot_survey", broken)
    assert main(["survey", "--scenario", "paper_6_1", "--out", str(out)]) == 130  # Ctrl-C
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert not _leftovers(tmp_path)


def test_failed_evaluate_writes_nothing(tmp_path, monkeypatch):
    import poc_env.agents.experiments.evaluate as evaluate

    def broken(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(evaluate, "plot_curves", broken)
    out = tmp_path / "ev"
    argv = ["evaluate", "--scenario", "small", "--episodes", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 130  # Ctrl-C's status
    assert list(tmp_path.iterdir()) == []


def test_plan_and_its_plot_are_written_together(tmp_path, monkeypatch):
    import poc_env.agents.planning.planner as planner

    def broken(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(planner, "plot_plan", broken)
    plan, plot = tmp_path / "plan.json", tmp_path / "plan.png"
    argv = ["plan", "--scenario", "small", "--popsize", "8", "--maxiter", "1", "--quiet"]
    assert main([*argv, "--out", str(plan), "--plot", str(plot)]) == 130  # Ctrl-C's status
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    assert main([*argv, "--out", str(plan), "--plot", str(plot)]) == 0
    assert plan.stat().st_size > 0 and plot.stat().st_size > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json", "plan.png"]


def test_kill_during_writing_leaves_old_or_new_output(tmp_path):
    """SIGKILL once a new run has started writing: the folder is the old run's or the new one's."""
    import os
    import signal
    import time

    out = tmp_path / "s"
    out.mkdir()
    old = {"survey.csv": b"old csv", "survey.txt": b"old txt", "survey.png": b"old png"}
    for name, data in old.items():
        (out / name).write_bytes(data)
    argv = [sys.executable, "-m", "poc_env.cli", "survey", "--scenario", "paper_6_1"]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen([*argv, "--out", str(out)], env=env, stdout=subprocess.DEVNULL)
    try:
        while proc.poll() is None and not (
            list(tmp_path.glob(".s.partial-*/survey.csv"))
            or (out / "survey.csv").read_bytes() != old["survey.csv"]
        ):
            time.sleep(0.01)  # until the new run has written its first file
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    files = {p.name: p.read_bytes() for p in out.iterdir()}
    killed_before_the_end = files == old
    if not killed_before_the_end:  # the run finished first: the new output, complete
        assert sorted(files) == sorted(old) and all(files[n] != old[n] for n in old)
    # the next run cleans the killed run's staging folder
    subprocess.run([*argv, "--out", str(out)], env=env, check=True, stdout=subprocess.DEVNULL)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s"]
    assert (out / "survey.csv").read_bytes() != old["survey.csv"]


def test_temp_files_of_killed_writers_are_cleaned(tmp_path):
    import os

    from poc_env.io import write_text_atomic

    dead_pid = _dead_pid()
    stale = tmp_path / f".step_8.zip.tmp-{dead_pid}-abcd1234.zip"
    live = tmp_path / f".other.json.tmp-{os.getpid()}-abcd1234"
    stale.write_bytes(b"half a model")
    live.write_bytes(b"being written by a live process")
    write_text_atomic(tmp_path / "latest.json", "{}")
    assert not stale.exists()  # its writer is gone
    assert live.exists()  # its writer (this process) is alive: never touched
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, "latest.json"])


def test_atomic_dir_never_replaces_a_folder_by_a_file(tmp_path):
    """A folder of the user's where the command writes a file of the same name is refused with
    a clear error naming it, and kept with its contents (audit i24: ``export --out o`` with a
    folder ``o/plan.geojson`` deleted that folder and everything in it)."""
    from poc_env.errors import ConfigError

    dest = tmp_path / "o"
    (dest / "plan.geojson").mkdir(parents=True)
    (dest / "plan.geojson" / "keep.txt").write_text("the user's")
    (dest / "plan.kml").write_text("old")
    with (
        pytest.raises(ConfigError, match=r"plan\.geojson.*it is a folder"),
        atomic_dir(dest) as stage,
    ):
        (stage / "plan.kml").write_text("new")
        (stage / "plan.geojson").write_text("{}")
    assert (dest / "plan.geojson" / "keep.txt").read_text() == "the user's"
    assert (dest / "plan.kml").read_text() == "old"  # nothing moved: the merge is whole or none
    assert not _leftovers(tmp_path)
    # and a folder the command writes where the user has a file: refused the same way
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "sub").write_text("a file")
    with pytest.raises(ConfigError, match="sub"), atomic_dir(tmp_path / "p") as stage:
        (stage / "sub").mkdir()
        (stage / "sub" / "a.txt").write_text("x")
    assert (tmp_path / "p" / "sub").read_text() == "a file"


def test_export_over_a_folder_in_the_way_says_nothing_written(tmp_path, capsys):
    """``poc-env export`` whose output name is taken by a folder: a clear error, the folder and
    its contents kept, and no ``wrote`` line for a file that was not written."""
    plan = tmp_path / "plan.json"
    argv = ["plan", "--scenario", "small", "--popsize", "8", "--maxiter", "1", "--quiet"]
    assert main([*argv, "--origin", "45.75,126.65", "--out", str(plan)]) == 0
    (tmp_path / "o" / "plan.geojson").mkdir(parents=True)
    (tmp_path / "o" / "plan.geojson" / "keep.txt").write_text("the user's")
    capsys.readouterr()
    assert main(["export", str(plan), "--format", "geojson", "--out", str(tmp_path / "o")]) == 2
    printed = capsys.readouterr()
    assert "plan.geojson'; allowed: a new path or a regular file to replace; it is a folder" in (
        printed.err
    )
    assert "wrote" not in printed.out
    assert (tmp_path / "o" / "plan.geojson" / "keep.txt").read_text() == "the user's"
    assert main(["export", str(plan), "--format", "geojson", "--out", str(tmp_path / "p")]) == 0
    assert f"wrote {tmp_path / 'p' / 'plan.geojson'}" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, taken",
    [
        (["survey", "--scenario", "paper_6_1"], "survey.csv"),
        (["evaluate", "--policies", "random", "--episodes", "1", "--quiet"], "episodes.csv"),
        (["figures"], "survey_paper_6_1/survey.csv"),
    ],
    ids=["survey", "evaluate", "figures"],
)
def test_a_refused_output_folder_prints_no_wrote_line(tmp_path, capsys, argv, taken):
    """``survey``, ``evaluate`` and ``figures`` whose output name is taken by a folder: the
    merge is refused at the end, nothing is written, and no ``wrote`` line claims otherwise
    (they printed ``wrote PATH`` while still staging); into a fresh folder they say it."""
    out = tmp_path / "o"
    (out / taken).mkdir(parents=True)
    (out / taken / "keep.txt").write_text("the user's")
    capsys.readouterr()
    assert main([*argv, "--out", str(out)]) == 2
    printed = capsys.readouterr()
    assert "it is a folder" in printed.err
    assert "wrote" not in printed.out
    assert (out / taken / "keep.txt").read_text() == "the user's"
    assert main([*argv, "--out", str(tmp_path / "p")]) == 0
    assert f"wrote {tmp_path / 'p' / taken}" in capsys.readouterr().out


def test_survey_plan_out_absent_when_its_out_folder_is_refused(tmp_path, capsys):
    """``survey --out DIR --plan-out FILE`` is one set of outputs: a refused ``DIR`` leaves no
    ``FILE`` either (it was written before the folder's merge was refused)."""
    out, plan = tmp_path / "o", tmp_path / "survey_plan.json"
    (out / "survey.csv").mkdir(parents=True)
    argv = ["survey", "--scenario", "paper_6_1", "--plan-out", str(plan)]
    assert main([*argv, "--out", str(out)]) == 2
    assert not plan.exists() and "wrote" not in capsys.readouterr().out
    assert main([*argv, "--out", str(tmp_path / "p")]) == 0
    assert plan.is_file() and f"wrote {plan}" in capsys.readouterr().out
