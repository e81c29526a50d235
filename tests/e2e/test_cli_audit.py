"""Defects the command-line audit found (cli-audit, results/audit/cli/README.md): each test
failed before its fix. Bad input ends in ``error: <field>: got ...; allowed: ...`` with exit
status 2 and nothing written; a command's outputs are complete or absent."""

from __future__ import annotations

import os
import sys

import pytest

from poc_env import recorded, spec, tasks
from poc_env.cli import main


def _tree(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def _refused(capsys, argv, field) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"error: {field}: got " in err and "allowed:" in err, err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize("what", ["missing", "folder", "no markers", "not utf-8"])
def test_spec_doc_that_cannot_be_read_is_a_clear_error(tmp_path, capsys, what):
    """``spec --doc`` a missing file, a folder, a page without the generated sections' markers
    or one that is not UTF-8: a traceback (FileNotFoundError, IsADirectoryError, KeyError,
    UnicodeDecodeError) before; now an error naming ``doc`` -- as from a wheel install, where
    the default docs/environment.md does not exist."""
    page = tmp_path / "ENV.md"
    if what == "folder":
        page.mkdir()
    elif what == "no markers":
        page.write_text("no markers", encoding="utf-8")
    elif what == "not utf-8":
        page.write_bytes(b"\xff\xfe<!-- spec:tasks -->")
    before = _tree(tmp_path)
    err = _refused(capsys, ["spec", "--write", "--doc", str(page)], "doc")
    if what == "no markers":
        assert "spec:tasks" in err
    assert _tree(tmp_path) == before


def test_spec_write_replaces_the_page_atomically(tmp_path, capsys, monkeypatch):
    """``spec --write`` rewrote the page in place (``Path.write_text``): a failure part-way
    left it truncated. It is now written through :func:`poc_env.io.write_text_atomic`: a
    failing write leaves the old page whole."""
    page = tmp_path / "ENV.md"
    stale = "".join(f"<!-- spec:{n} -->\nSTALE\n<!-- /spec:{n} -->\n" for n in spec.SECTIONS)
    page.write_text(stale, encoding="utf-8")

    def broken_fsync(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("os.fsync", broken_fsync)
    with pytest.raises(OSError):
        main(["spec", "--write", "--doc", str(page)])
    assert page.read_text(encoding="utf-8") == stale
    assert _tree(tmp_path) == ["ENV.md"]  # no temporary file left either
    capsys.readouterr()


def test_record_dir_that_is_a_file_is_refused_before_flying(tmp_path, capsys, monkeypatch):
    """``record --dir FILE``: a traceback (FileExistsError) after flying the episode; now
    refused up front, naming ``dir``."""
    f = tmp_path / "f"
    f.write_text("a file")
    flown = []
    monkeypatch.setattr(recorded, "run", lambda tid, *a: flown.append(tid))
    tid = f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}"
    _refused(capsys, ["record", "--task", tid, "--dir", str(f)], "dir")
    _refused(capsys, ["record", "--task", tid, "--dir", str(f / "sub")], "dir")
    assert flown == [] and f.read_text() == "a file"


def test_record_writes_all_its_files_or_none(tmp_path, capsys, monkeypatch):
    """``record --task A --task B`` failing on B left A's new recording in the folder (a set
    of outputs part-written); now the recordings are staged and put in place together."""
    tids = [f"poc_env/UAVSearch-Small-{c}-v{tasks.VERSION}" for c in ("Heading", "Waypoint")]
    real = recorded.run

    def fails_on_the_second(tid, *a):
        if tid == tids[1]:
            raise RuntimeError("killed")
        return real(tid, *a)

    monkeypatch.setattr(recorded, "run", fails_on_the_second)
    out = tmp_path / "rec"
    with pytest.raises(RuntimeError):
        main(["record", "--task", tids[0], "--task", tids[1], "--dir", str(out)])
    assert _tree(tmp_path) == []
    capsys.readouterr()


def test_record_without_dir_outside_a_checkout_is_refused(tmp_path, capsys, monkeypatch):
    """From a wheel install ``record`` without ``--dir`` wrote into
    ``site-packages/tests/recorded`` (the source tree's folder, computed from the package's
    location); with no such folder it is now refused, naming ``dir``."""
    monkeypatch.setattr(recorded, "DEFAULT_DIR", tmp_path / "site-packages" / "tests" / "rec")
    tid = f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}"
    err = _refused(capsys, ["record", "--task", tid], "dir")
    assert "--dir" in err
    assert _tree(tmp_path) == []


def test_ctrl_c_is_one_line_and_status_130(tmp_path, capsys, monkeypatch):
    """Ctrl-C (SIGINT) during a command printed a Python traceback (KeyboardInterrupt, from
    wherever the run was: scipy, numba, a worker's wait) and the process died by the signal;
    now one line on stderr, exit status 130 (128 + SIGINT, as ``train`` already returned), and
    nothing written: the staged output never reaches its place."""
    import poc_env.agents.planning.survey as survey

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(survey, "run_survey", interrupted)
    monkeypatch.chdir(tmp_path)
    assert main(["survey", "--out", str(tmp_path / "s")]) == 130
    err = capsys.readouterr().err
    assert err.startswith("interrupted") and err.count("\n") == 1, err
    assert _tree(tmp_path) == []


def test_the_command_line_starts_without_the_compiled_kernels():
    """Ctrl-C in the first moments of a command, while the package imported, printed Python's
    traceback (cli-audit: 42 of 99 SIGINTs; ``poc_env`` imported its configuration and with
    it numba and the compiled kernels before ``main`` could catch anything). The package and
    its command line now import without them; ``poc_env.load_scenario`` loads them on use."""
    import subprocess

    code = (
        "import sys, poc_env.cli; assert 'numba' not in sys.modules, 'numba'; "
        "assert 'poc_env.config' not in sys.modules, 'config'; "
        "print(poc_env.load_scenario('small').name, 'numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["small", "True"]


def test_ctrl_c_while_the_command_line_is_parsed_is_one_line_too(capsys, monkeypatch):
    """The parser reads the configuration (and so loads the compiled kernels the first time):
    a Ctrl-C there ends as one inside a command does, one line and status 130."""
    from poc_env import cli

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "parse_command_line", interrupted)
    assert main(["tasks"]) == 130
    err = capsys.readouterr().err
    assert err.startswith("interrupted") and err.count("\n") == 1, err


LONG = "y" * 300  # one name longer than any file system's limit (255 bytes): ENAMETOOLONG


TOO_LONG = [
    (["export", "{L}.json", "--format", "kml", "--out", "x"], "plan"),
    (["plan", "--scenario", "{L}.yaml", "--out", "p.json"], "scenario"),
    (["plan", "--scenario", "small", "--map", "{L}.npy", "--out", "p.json"], "map_file"),
    (["replan", "--plan", "{L}.json", "--out", "n.json"], "plan"),
    (["survey", "--regions", "{L}.yaml"], "regions"),
    (["summarise", "{L}"], "results_dir"),
    (["curve", "{L}", "--out", "c.png"], "run_dir"),
    (["train", "--resume", "{L}"], "resume"),
    (["evaluate", "--policies", "ppo:{L},random", "--episodes", "1"], "policies"),
    (["scenario", "import", "{L}.geojson", "--airfields", "f.geojson", "--out", "h.yaml"],
     "area"),
    (["plan", "--scenario", "small", "--overrides", "map.prior.kind=file",
     "map.prior.file={L}.npy", "--out", "p.json"], "overrides"),
]  # fmt: skip


@pytest.mark.parametrize("argv, field", TOO_LONG, ids=[" ".join(a)[:40] for a, _ in TOO_LONG])
def test_a_path_too_long_for_the_file_system_is_a_clear_error(
    tmp_path, capsys, monkeypatch, argv, field
):
    """An input path with a name over the file system's limit: ``Path.is_file()`` and its kin
    raise OSError (ENAMETOOLONG) instead of answering False, and every command with an input
    file ended in that traceback. Now one error naming the option the path came from."""
    monkeypatch.chdir(tmp_path)
    err = _refused(capsys, [a.replace("{L}", str(tmp_path / LONG)) for a in argv], field)
    assert "File name too long" in err
    assert _tree(tmp_path) == []


@pytest.mark.parametrize(
    "argv, field",
    [
        (
            ["plan", "--scenario", "small", "--quiet", "--out", "{d}/p.png", "--plot", "{d}/p.png"],
            "plot",
        ),
        (["plan", "--scenario", "{d}/sc.yaml", "--quiet", "--out", "{d}/sc.yaml"], "out"),
        (["replan", "--plan", "{d}/p1.json", "--out", "{d}/p1.json"], "out"),
        (["replan", "--plan", "{d}/p1.json", "--out", "{d}/../d/p1.json"], "out"),
        (["survey", "--plan-out", "{d}/sc.yaml", "--scenario", "{d}/sc.yaml"], "plan_out"),
        (["survey", "--out", "{d}/s", "--plan-out", "{d}/s/survey.csv"], "plan_out"),
    ],
    ids=[
        "plan out=plot",
        "plan out=scenario",
        "replan out=plan",
        "replan out=plan (path)",
        "survey plan-out=scenario",
        "survey plan-out=its survey.csv",
    ],
)
def test_an_output_over_an_input_or_another_output_is_refused(tmp_path, capsys, argv, field):
    """``plan --out P --plot P`` wrote the PNG and then plan.json over it (one output lost,
    exit 0), as ``survey --out S --plan-out S/survey.csv`` did the CSV; ``--out`` naming the
    command's own input (the scenario YAML, the previous sortie's plan.json that the next
    replan needs again) replaced the user's file. Refused before any work, naming the output
    option; the inputs are untouched."""
    import shutil

    from poc_env.config import CONFIG_DIR

    d = tmp_path / "d"
    d.mkdir()
    shutil.copy(CONFIG_DIR / "paper_6_1.yaml", d / "sc.yaml")
    assert main(["plan", "--scenario", "small", "--quiet", "--maxiter", "1", "--popsize", "8",
                 "--out", str(d / "p1.json")]) == 0  # fmt: skip
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in d.iterdir()}
    _refused(capsys, [a.replace("{d}", str(d)) for a in argv], field)
    assert {p.name: p.read_bytes() for p in d.iterdir()} == before


def test_a_refused_plan_leaves_no_empty_folders(tmp_path, capsys):
    """``plan --plot new/sub/p.png`` refused after its checks (here --uavs with --overrides
    fleet...): the plot's temporary file had created ``new/sub/`` first, and the error left
    those empty folders (a SIGKILL left them holding only the temporary file). The temporary
    file now waits in the nearest existing folder and the folders are made when it is
    published."""
    argv = ["plan", "--scenario", "small", "--uavs", "2", "--overrides", "fleet.uavs=1",
            "--quiet", "--out", str(tmp_path / "new" / "p.json"),
            "--plot", str(tmp_path / "new" / "sub" / "p.png")]  # fmt: skip
    _refused(capsys, argv, "uavs")
    assert _tree(tmp_path) == []


def test_atomic_path_makes_its_folders_only_when_it_publishes(tmp_path):
    from poc_env.io import atomic_path

    dest = tmp_path / "a" / "b" / "f.txt"
    with pytest.raises(RuntimeError), atomic_path(dest) as tmp:
        tmp.write_text("half")
        assert _tree(tmp_path) == [tmp.name]  # staged beside the nearest existing folder
        raise RuntimeError("killed")
    assert _tree(tmp_path) == []
    with atomic_path(dest) as tmp:
        tmp.write_text("whole")
    assert dest.read_text() == "whole" and _tree(tmp_path) == ["a", "a/b", "a/b/f.txt"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_a_killed_bench_takes_its_benchmark_with_it(tmp_path):
    """``poc-env bench`` runs the benchmark in a child interpreter; SIGKILL (or SIGTERM) of
    ``poc-env`` -- a scheduler ending the job -- left that child running on, orphaned, and it
    wrote its --out folder after the kill (the kill harness saw a "complete" output from a run
    killed 1.3 s in). The child now dies with its parent."""
    import os
    import signal
    import subprocess
    import time

    argv = [sys.executable, "-m", "poc_env.cli", "bench", "baselines", "--tasks",
            f"poc_env/UAVSearch-Small-Heading-v{tasks.VERSION}", "--policies", "lawnmower",
            "--episodes", "10000", "--out", str(tmp_path / "b")]  # fmt: skip
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    children: list[int] = []
    try:
        for _ in range(600):  # until the benchmark's interpreter is started
            task = f"/proc/{proc.pid}/task/{proc.pid}/children"
            with open(task) as fh:
                children = [int(c) for c in fh.read().split()]
            if children:
                break
            time.sleep(0.05)
        assert children, "the benchmark's child process never started"
    finally:
        proc.kill()
        proc.wait()
    for _ in range(200):  # the child goes within moments of its parent
        if not os.path.exists(f"/proc/{children[0]}") or _zombie(children[0]):
            break
        time.sleep(0.05)
    else:
        os.kill(children[0], signal.SIGKILL)
        pytest.fail("the benchmark outlived the killed poc-env bench")
    assert not (tmp_path / "b").exists()


def _zombie(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


@pytest.mark.parametrize(
    "argv, field",
    [
        (["export", "{p}", "--format", "geojson", "--projection", "utm", "--out", "{d}/x"],
         "projection"),
        (["export", "{p}", "--format", "geojson", "--utm-zone", "32", "--out", "{d}/x"],
         "utm_zone"),
        (["plan", "--scenario", "small", "--quiet", "--projection", "utm", "--out", "{d}/q.json"],
         "projection"),
        (["plan", "--scenario", "small", "--quiet", "--utm-zone", "32", "--out", "{d}/q.json"],
         "utm_zone"),
        (["survey", "--origin", "45,7"], "origin"),
        (["survey", "--projection", "utm", "--plan-out", "{d}/s.json"], "projection"),
    ],
    ids=["export utm over an aeqd plan", "export zone over an aeqd plan", "plan utm, no origin",
         "plan zone, no origin", "survey origin, no plan-out", "survey utm, no origin"],
)  # fmt: skip
def test_a_projection_option_that_would_be_ignored_is_refused(tmp_path, capsys, argv, field):
    """``export --projection utm`` (or ``--utm-zone``) of a plan that records its crs wrote the
    plan's own projection and said nothing (only ``--origin`` was compared with the plan's);
    ``plan``/``survey`` with ``--projection``/``--utm-zone`` but no ``--origin``, and
    ``survey --origin`` without ``--plan-out``, ignored them. Now each is an error naming the
    option, as ``plan --effort`` with the de planner is."""
    d = tmp_path / "d"
    d.mkdir()
    plan = d / "p.json"
    assert main(["plan", "--scenario", "small", "--quiet", "--maxiter", "1", "--popsize", "8",
                 "--origin", "45.5,126.6", "--out", str(plan)]) == 0  # fmt: skip
    capsys.readouterr()
    before = _tree(tmp_path)
    _refused(capsys, [a.replace("{p}", str(plan)).replace("{d}", str(d)) for a in argv], field)
    assert _tree(tmp_path) == before


@pytest.mark.parametrize(
    "argv, field",
    [
        (["plan", "--scenario", "small", "--quiet", "--out", "{d}/p.json", "--plot", "{d}/p.jpg"],
         "plot"),
        (["curve", "{d}", "--out", "{d}/curve.txt"], "out"),
    ],
    ids=["plan --plot p.jpg", "curve --out c.txt"],
)  # fmt: skip
def test_a_png_under_another_name_is_refused(tmp_path, capsys, argv, field):
    """``plan --plot p.jpg`` and ``curve --out curve.txt`` wrote PNG data under those names
    (exit 0; a viewer then refuses the file), where ``render --out ep.png`` is refused for not
    ending in .gif. Refused before any work now, naming the option."""
    d = tmp_path / "d"
    d.mkdir()
    err = _refused(capsys, [a.replace("{d}", str(d)) for a in argv], field)
    assert ".png" in err
    assert _tree(tmp_path) == ["d"]


def test_a_run_in_progress_shows_no_output_folder_yet(tmp_path, capsys, monkeypatch):
    """``experiment table4 --out t`` killed (SIGKILL) part-way left ``t/`` holding only a
    hidden staging folder (the kill harness's one PARTIAL state after the fixes): the staging
    folder's parents were made before the run. Now the staging folder waits in the nearest
    existing folder and the destination's folders are made when it is put in place, so at any
    moment of the run nothing but hidden staging is visible."""
    import poc_env.agents.planning.survey as survey

    seen: list[list[str]] = []
    real = survey.run_survey

    def watched(*a, **k):
        seen.append([p for p in _tree(tmp_path) if ".partial-" not in p])  # a kill now
        return real(*a, **k)

    monkeypatch.setattr(survey, "run_survey", watched)
    out = tmp_path / "new" / "s"
    assert main(["survey", "--out", str(out)]) == 0
    capsys.readouterr()
    assert seen == [[]]
    assert sorted(p.name for p in out.iterdir()) == ["survey.csv", "survey.png", "survey.txt"]
    assert _tree(tmp_path) == ["new", "new/s", *(f"new/s/survey.{e}" for e in ("csv", "png",
                                                                             "txt"))]  # fmt: skip


@pytest.mark.skipif(not os.path.exists("/proc/self/mem"), reason="needs Linux's /proc/self/mem")
@pytest.mark.parametrize(
    "argv, field",
    [
        (["plan", "--scenario", "/proc/self/mem", "--out", "{d}/p.json"], "scenario"),
        (["survey", "--regions", "/proc/self/mem"], "regions"),
    ],
    ids=["plan --scenario", "survey --regions"],
)
def test_a_yaml_file_that_cannot_be_read_is_a_clear_error(tmp_path, capsys, argv, field):
    """A scenario or region file that exists but cannot be read (``/proc/self/mem``: EIO; an
    unreadable file, a failing disk) ended in an ``OSError`` traceback: the read's error names
    no file, so no handler could say which option it was. The YAML reader now reads through
    :func:`poc_env.io.read_text`, naming the option (``regions``, not ``scenario``, for a
    region file)."""
    err = _refused(capsys, [a.replace("{d}", str(tmp_path)) for a in argv], field)
    assert "Input/output error" in err
    assert _tree(tmp_path) == []


# ---------------------------------------------------------------- leftovers #5 (cli-audit's)
def _layers(tmp_path):
    """A minimal area and airfield for ``scenario import``."""
    import json

    ring = [[126.0, 45.3], [127.2, 45.3], [127.2, 46.1], [126.0, 46.1], [126.0, 45.3]]
    area = {
        "type": "Feature",
        "properties": {},
        "geometry": {"type": "Polygon", "coordinates": [ring]},
    }
    field = {"type": "Feature", "properties": {"name": "A"},
             "geometry": {"type": "Point", "coordinates": [126.5, 45.2]}}  # fmt: skip
    (tmp_path / "area.geojson").write_text(json.dumps(area))
    (tmp_path / "fields.geojson").write_text(json.dumps(field))
    return ["scenario", "import", str(tmp_path / "area.geojson"), "--airfields",
            str(tmp_path / "fields.geojson"), "--out", str(tmp_path / "s.yaml")]  # fmt: skip


@pytest.mark.parametrize("option", ["area", "airfields", "no_fly", "prior"])
def test_scenario_import_names_the_option_of_a_bad_file(tmp_path, capsys, option):
    """A missing layer is named by its option (``no_fly``), the path given as the value; before,
    the error's field was the path itself (``error: /x/nope.geojson: got 'missing or not a
    regular file'``)."""
    argv = _layers(tmp_path)
    nope = str(tmp_path / ("nope.csv" if option == "prior" else "nope.geojson"))
    if option == "area":
        argv[2] = nope
    elif option == "airfields":
        argv[4] = nope
    else:
        argv += [f"--{option.replace('_', '-')}", nope]
    err = _refused(capsys, argv, option)
    assert nope in err and "it does not exist" in err
    assert not (tmp_path / "s.yaml").exists()


def test_an_unreadable_empty_layer_is_called_unreadable(tmp_path, capsys, monkeypatch):
    """A zero-size file poc-env may not read (EACCES on open; the sessions run as root, so the
    refusal is injected) is unreadable, not 'an empty file'; an empty readable one is empty."""
    argv = _layers(tmp_path)
    empty = tmp_path / "zones.geojson"
    empty.write_text("")
    argv += ["--no-fly", str(empty)]
    real_open = os.open

    def no_permission(path, flags, *args, **kwargs):
        if os.fspath(path) == str(empty):
            raise PermissionError(13, "Permission denied", os.fspath(path))
        return real_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", no_permission)
    err = _refused(capsys, argv, "no_fly")
    assert "unreadable (Permission denied)" in err and "an empty file" not in err
    from poc_env.agents.mission.geoimport import import_scenario
    from poc_env.errors import ConfigError

    with pytest.raises(ConfigError, match=r"^no_fly: .*unreadable \(Permission denied\)$"):
        import_scenario(argv[2], airfields=argv[4], no_fly=empty)  # the library call too
    monkeypatch.undo()
    err = _refused(capsys, argv, "no_fly")
    assert "it is an empty file" in err


def _unblock_readers_of(fifo, seconds: float = 20.0) -> None:
    """A daemon thread that, for ``seconds``, opens ``fifo`` for writing whenever a reader is
    blocked on it and closes it at once (the reader gets end of file)."""
    import contextlib
    import threading
    import time

    def run():
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            with contextlib.suppress(OSError):  # ENXIO: no reader yet
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            time.sleep(0.05)

    threading.Thread(target=run, daemon=True).start()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs are POSIX")
def test_a_fifo_given_as_an_input_is_refused_not_read(tmp_path, capsys, monkeypatch):
    """``replan --tracks`` on a FIFO blocked forever (a read that never ends); every input file
    option that is not a regular file is refused before the command runs, naming the option. A
    folder named like a built-in scenario in the working directory is no file: still the name."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "small").mkdir()
    plan = tmp_path / "p1.json"
    argv = ["plan", "--scenario", "small", "--planner", "allocation", "--origin", "46.5,7.9"]
    assert main([*argv, "--quiet", "--out", str(plan)]) == 0
    fifo = tmp_path / "t.geojson"
    os.mkfifo(fifo)
    _unblock_readers_of(fifo)  # were the FIFO read, the test would end in an error, not hang
    argv = ["replan", "--plan", str(plan), "--tracks", str(fifo), "--out", str(tmp_path / "n.json")]
    err = _refused(capsys, argv, "tracks")
    assert "it is a FIFO, not a regular file" in err
    argv = _layers(tmp_path)
    argv += ["--dem", str(fifo)]
    assert "a FIFO" in _refused(capsys, argv, "dem")


def test_max_memory_gb_is_each_call_s_own(tmp_path, capsys, monkeypatch):
    """``main()`` called twice in one process: the second call without ``--max-memory-gb`` gets
    the default limit, not the first call's (it stayed in os.environ)."""
    from poc_env import limits

    monkeypatch.delenv("POC_ENV_MAX_MEMORY_GB", raising=False)
    seen = []
    real = limits.memory_limit_bytes

    def spy(*args, **kwargs):
        seen.append(real())
        return real()

    monkeypatch.setattr(limits, "memory_limit_bytes", spy)
    plan = tmp_path / "p.json"
    base = ["plan", "--scenario", "small", "--planner", "allocation", "--quiet"]
    assert main(["--max-memory-gb", "3", *base, "--out", str(plan)]) == 0
    during = list(seen)
    seen.clear()
    assert main([*base, "--out", str(plan)]) == 0
    assert during and set(during) == {3 * 2**30}
    assert seen and set(seen) == {limits.DEFAULT_MEMORY_GB * 2**30}
    assert "POC_ENV_MAX_MEMORY_GB" not in os.environ


#: A ``poc-env`` process (``sys.argv[0]`` its script) sent SIGINT when it starts importing
#: gymnasium, inside ``import poc_env`` (results/audit/leftovers/probes.py runs it too).
KICK_WHILE_IMPORTING = (
    "import os, signal, sys\n"
    "class Kick:\n"
    "    def find_spec(self, name, path, target=None):\n"
    "        if name == 'gymnasium':\n"
    "            os.kill(os.getpid(), signal.SIGINT)\n"
    "sys.meta_path.insert(0, Kick())\n"
    "sys.argv[0] = os.path.join(os.path.dirname(sys.executable), 'poc-env')\n"
    "from poc_env.cli import main\n"
    "sys.exit(main(['--version']))\n"
)


def test_ctrl_c_while_the_command_imports_its_packages_is_one_line(tmp_path):
    """A Ctrl-C in the first fraction of a second, while ``poc-env`` imports numpy and
    Gymnasium (before main() runs), printed Python's KeyboardInterrupt traceback; now one line
    and status 130. The SIGINT is sent when the import of gymnasium starts (an import hook)."""
    import subprocess

    argv = [sys.executable, "-c", KICK_WHILE_IMPORTING]
    proc = subprocess.run(argv, capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 130, proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip() == "interrupted: poc-env stopped while starting; nothing was written"
