"""Kill every writing ``poc-env`` command part-way and inspect what it leaves (cli-audit).

For each command: one uninterrupted run gives the reference output (the set of files and
folders it writes) and its wall time T. Then, for each kill, a fresh scratch folder (or one
holding the previous, complete output: the ``over`` variant), the command started, a seeded
uniform sleep in [0.05 T, 1.05 T], SIGINT or SIGKILL, and the folder inspected:

* ``out``: absent, or exactly the reference set (``complete``), or -- ``over`` variant --
  byte-identical to the previous output (``old``); anything else is ``PARTIAL`` (a defect);
* ``temp``: hidden temporary files or staging folders left (``.tmp-``, ``.partial-``, ``*.tmp``);
  allowed only if the rerun removes them (they are never read);
* ``rerun``: the same command again must exit 0, with the reference set and no temp left;
* SIGINT: exit status and whether stderr holds a Python traceback.

Usage (one thread, niced; writes a JSON line per kill to --log)::

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/cli/kill_harness.py \
        --kills 6 --seed 5000 --log results/audit/cli/kills.jsonl [--only plan,render]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

PY = sys.executable
EXE = [PY, "-m", "poc_env.cli"]

# name: (argv with {o}: the output root, {i}: the inputs folder; the output paths under {o})
COMMANDS: dict[str, list[str]] = {
    "plan": [
        "plan",
        "--scenario",
        "small",
        "--quiet",
        "--out",
        "{o}/p/plan.json",
        "--plot",
        "{o}/p/plan.png",
    ],
    "replan": ["replan", "--plan", "{i}/plan.json", "--out", "{o}/next.json"],
    "export_qgc": ["export", "{i}/plan.json", "--format", "qgc", "--out", "{o}/x"],
    "export_kml": ["export", "{i}/plan.json", "--format", "kml", "--out", "{o}/x"],
    "export_html": ["export", "{i}/plan.json", "--format", "html", "--out", "{o}/x"],
    "evaluate": [
        "evaluate",
        "--scenario",
        "small",
        "--policies",
        "lawnmower,random",
        "--episodes",
        "3",
        "--quiet",
        "--out",
        "{o}/e",
    ],
    "experiment": ["experiment", "table4", "--quick", "--out", "{o}/t"],
    "bench_baselines": [
        "bench",
        "baselines",
        "--quick",
        "--tasks",
        "poc_env/UAVSearch-Small-Heading-v1",
        "--policies",
        "lawnmower,random",
        "--out",
        "{o}/b",
    ],
    "figures": ["figures", "--out", "{o}/f"],
    "render": ["render", "--scenario", "small", "--max-steps", "40", "--out", "{o}/r/ep.gif"],
    "survey": ["survey", "--out", "{o}/s", "--plan-out", "{o}/s_plan.json"],
    "summarise": ["summarise", "{i}/eval", "--out", "{o}/sum"],
    "curve": ["curve", "{i}/run", "--out", "{o}/c/curve.png"],
    "train": [
        "train",
        "--scenario",
        "small",
        "--total-timesteps",
        "512",
        "--n-steps",
        "64",
        "--n-envs",
        "2",
        "--batch-size",
        "64",
        "--checkpoint-every",
        "128",
        "--no-progress",
        "--run-dir",
        "{o}/run",
    ],
    "scenario_import": [
        "scenario",
        "import",
        "{i}/area.geojson",
        "--prior",
        "{i}/sightings.csv",
        "--airfields",
        "{i}/fields.geojson",
        "--no-fly",
        "{i}/zones.geojson",
        "--out",
        "{o}/harbin.yaml",
    ],
    "record": [
        "record",
        "--task",
        "poc_env/UAVSearch-Small-Heading-v1",
        "--task",
        "poc_env/UAVSearch-Small-Waypoint-v0",
        "--dir",
        "{o}/rec",
    ],
    "demo": ["demo", "--episodes", "1", "--workers", "1", "--out", "{o}/d"],
}

TEMP_MARKS = (".tmp-", ".partial-", ".tmp")


def tree(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root`` (relative) with its bytes (None: a folder)."""
    out: dict[str, bytes | None] = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        out[rel] = None if p.is_dir() else p.read_bytes()
    return out


def temps(names) -> list[str]:
    """Hidden temporary files and staging folders, and everything inside a staging folder."""
    return [n for n in names if any(m in part for part in Path(n).parts for m in TEMP_MARKS)]


def visible(t: dict) -> set[str]:
    return {n for n in t if not temps([n])}


def run(argv, cwd, timeout=1800):
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)  # fmt: skip


def setup_inputs(inp: Path) -> None:
    """The inputs the commands read: a plan, an evaluation folder, a training run, the Harbin
    layers of docs/missions.md."""
    if (inp / "done").exists():
        return
    inp.mkdir(parents=True, exist_ok=True)
    steps = [
        [
            "plan",
            "--scenario",
            "small",
            "--quiet",
            "--origin",
            "45.5,126.6",
            "--out",
            f"{inp}/plan.json",
        ],
        [
            "evaluate",
            "--scenario",
            "small",
            "--policies",
            "lawnmower,random",
            "--episodes",
            "2",
            "--quiet",
            "--baseline",
            "random",
            "--out",
            f"{inp}/eval",
        ],
        [
            "train",
            "--scenario",
            "small",
            "--total-timesteps",
            "256",
            "--n-steps",
            "64",
            "--n-envs",
            "2",
            "--batch-size",
            "64",
            "--no-progress",
            "--run-dir",
            f"{inp}/run",
        ],
    ]
    for s in steps:
        r = run([*EXE, *s], inp)
        assert r.returncode == 0, (s, r.stderr[-2000:])
    page = Path(__file__).resolve().parents[3] / "docs" / "missions.md"
    text = page.read_text(encoding="utf-8")
    start = text.index("Songhua search area")  # the Harbin walkthrough's layers
    start = text.rindex("cat > area.geojson", 0, start)
    end = text.index("poc-env scenario import area.geojson --prior sightings", start)
    block = text[start:end]
    subprocess.run(["bash", "-e", "-c", block], cwd=inp, check=True)
    (inp / "done").write_text("")


def _sigint_default() -> None:
    """In the child: SIGINT back to its default. A background job of a non-interactive shell
    (this harness under ``... &``) inherits SIGINT ignored, and Python then keeps it ignored:
    every SIGINT kill would be a no-op (the first round of this harness measured exactly that)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def one(name, argv_t, inp, work, sleep_s, sig, over, ref_tree):
    work.mkdir(parents=True)
    out = work / "o"
    out.mkdir()
    argv = [a.format(o=out, i=inp) for a in argv_t]
    if over:  # the previous complete output in place
        for rel, data in ref_tree.items():
            p = out / rel
            if data is None:
                p.mkdir(parents=True, exist_ok=True)
            else:
                p.parent.mkdir(parents=True, exist_ok=True)
                p.write_bytes(data)
    before = tree(out)
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([*EXE, *argv], cwd=work, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=_sigint_default)  # fmt: skip
    time.sleep(sleep_s)
    finished_first = proc.poll() is not None
    if not finished_first:
        proc.send_signal(sig)
    try:
        _, se = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:  # SIGINT ignored for 2 min: a defect of its own
        proc.kill()
        _, se = proc.communicate()
        se += "\n[harness: did not stop within 120 s of SIGINT; killed]"
    after = tree(out)
    vis = visible(after)
    ref = set(ref_tree)
    if vis == set():
        state = "absent"
    elif vis == ref and all(after[k] is None or k in after for k in ref):
        state = "complete"
        if over and all(after.get(k) == before.get(k) for k in before):
            state = "old"
    elif over and {k: after[k] for k in vis} == before:
        state = "old"
    else:
        state = "PARTIAL"
    left = temps(after)
    if name == "train":  # a run folder grows (checkpoints, TensorBoard files named by time):
        run_dir = out / "run"  # killed, it is absent or resumable, and --resume finishes it
        state = "absent" if not run_dir.exists() else (
            "resumable" if (run_dir / "config.json").is_file() else "PARTIAL")  # fmt: skip
        again = ["train", "--resume", str(run_dir)] if state == "resumable" else argv
        r = run([*EXE, *again], work)
        after2 = tree(out)
        rerun_ok = r.returncode == 0 and (run_dir / "model.zip").is_file() and not temps(after2)
    else:
        r = run([*EXE, *argv], work)
        after2 = tree(out)
        rerun_ok = r.returncode == 0 and visible(after2) == ref and not temps(after2)
    rec = {
        "command": name, "signal": sig.name, "sleep_s": round(sleep_s, 3), "over": over,
        "finished_first": finished_first, "exit": proc.returncode, "state": state,
        "missing": sorted(ref - vis)[:8], "extra": sorted(vis - ref)[:8], "temp_left": left[:8],
        "traceback": "Traceback" in se, "stderr_tail": se.strip().splitlines()[-1:] if se else [],
        "rerun_exit": r.returncode, "rerun_ok": rerun_ok,
        "rerun_err": r.stderr.strip().splitlines()[-1:] if not rerun_ok else [],
    }  # fmt: skip
    return rec


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--kills", type=int, default=4, help="kills per command and variant")
    ap.add_argument("--seed", type=int, default=5000)
    ap.add_argument("--root", default="/tmp/cli-audit/kill")
    ap.add_argument("--log", required=True)
    ap.add_argument("--only", default=None)
    ap.add_argument("--skip", default="")
    a = ap.parse_args()
    root = Path(a.root)
    inp = root / "inputs"
    setup_inputs(inp)
    names = a.only.split(",") if a.only else [n for n in COMMANDS if n not in a.skip.split(",")]
    rng = np.random.default_rng(a.seed)
    with open(a.log, "a", encoding="utf-8") as log:
        for name in names:
            argv_t = COMMANDS[name]
            ref_dir = root / name / "ref"
            shutil.rmtree(root / name, ignore_errors=True)
            (ref_dir / "o").mkdir(parents=True)
            ref_argv = [*EXE, *[s.format(o=ref_dir / "o", i=inp) for s in argv_t]]
            r = run(ref_argv, ref_dir)  # the first run fills numba's caches
            if r.returncode == 0:  # the second, timed, is what a kill interrupts
                shutil.rmtree(ref_dir / "o")
                (ref_dir / "o").mkdir()
                t0 = time.perf_counter()
                r = run(ref_argv, ref_dir)
            wall = time.perf_counter() - t0 if r.returncode == 0 else 0.0
            ref_tree = tree(ref_dir / "o")
            head = {"command": name, "reference": True, "exit": r.returncode,
                    "wall_s": round(wall, 2), "load1": os.getloadavg()[0],
                    "files": sorted(ref_tree)[:30],
                    "err": r.stderr.strip().splitlines()[-1:] if r.returncode else []}  # fmt: skip
            print(json.dumps(head), file=log, flush=True)
            if r.returncode != 0:
                continue
            k = 0
            for over in (False,) if name == "train" else (False, True):
                for sig in (signal.SIGINT, signal.SIGKILL):
                    for _ in range(a.kills):
                        sleep_s = float(rng.uniform(0.05, 1.05)) * wall
                        rec = one(name, argv_t, inp, root / name / f"k{k}", sleep_s, sig,
                                  over, ref_tree)  # fmt: skip
                        k += 1
                        print(json.dumps(rec), file=log, flush=True)
            shutil.rmtree(root / name, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
