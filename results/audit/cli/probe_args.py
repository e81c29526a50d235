"""Bad arguments and hostile names for every ``poc-env`` command, in-process (cli-audit).

Each probe runs :func:`poc_env.cli.main` in a fresh scratch folder (inputs from the kill
harness's ``inputs`` folder: a plan, an evaluation, a training run, the Harbin layers) and
records the exit status, the last stderr line, whether a traceback escaped, and every path
written outside the scratch folder's ``out`` area (a write anywhere else -- the inputs, the
parent -- is a defect). One JSON line per probe to --log.

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/cli/probe_args.py \
        --inputs /tmp/cli-audit/kill/inputs --log results/audit/cli/probes.jsonl
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import traceback
from pathlib import Path

LONG = "x" * 300
NAMES = ["../x", "/abs-x", "a/b", "con", "", LONG, "a\nb", "*?", "ümlaut-名"]

# (probe id, argv; {i}: inputs, {o}: the scratch out folder)
P = [
    # global
    ("mem -1", ["--max-memory-gb", "-1", "scenarios"]),
    ("mem 0", ["--max-memory-gb", "0", "scenarios"]),
    ("mem nan", ["--max-memory-gb", "nan", "scenarios"]),
    ("mem inf", ["--max-memory-gb", "inf", "scenarios"]),
    # plan
    ("plan uavs 0", ["plan", "--scenario", "small", "--uavs", "0", "--out", "{o}/p.json"]),
    ("plan uavs -1", ["plan", "--scenario", "small", "--uavs", "-1", "--out", "{o}/p.json"]),
    ("plan seed nan", ["plan", "--scenario", "small", "--seed", "nan", "--out", "{o}/p.json"]),
    ("plan seed 2^70", ["plan", "--scenario", "small", "--seed", str(2**70), "--out",
                        "{o}/p.json"]),
    ("plan refine -1", ["plan", "--scenario", "small", "--planner", "allocation", "--refine",
                        "-1", "--out", "{o}/p.json"]),
    ("plan refine 1e9", ["plan", "--scenario", "small", "--planner", "allocation", "--refine",
                         "1000000000", "--out", "{o}/p.json"]),
    ("plan effort bogus", ["plan", "--scenario", "small", "--planner", "allocation",
                           "--effort", "bogus", "--out", "{o}/p.json"]),
    ("plan speed bogus", ["plan", "--scenario", "small", "--planner", "allocation", "--speed",
                          "bogus", "--out", "{o}/p.json"]),
    ("plan effort with de", ["plan", "--scenario", "small", "--effort", "thorough", "--out",
                             "{o}/p.json"]),
    ("plan refine with de", ["plan", "--scenario", "small", "--refine", "2", "--out",
                             "{o}/p.json"]),
    ("plan preset bogus", ["plan", "--scenario", "small", "--preset", "bogus", "--out",
                           "{o}/p.json"]),
    ("plan optimizer bogus", ["plan", "--scenario", "small", "--optimizer", "bogus", "--out",
                              "{o}/p.json"]),
    ("plan planner bogus", ["plan", "--scenario", "small", "--planner", "bogus", "--out",
                            "{o}/p.json"]),
    ("plan projection bogus", ["plan", "--scenario", "small", "--projection", "bogus",
                               "--origin", "45,7", "--out", "{o}/p.json"]),
    ("plan utm-zone 0", ["plan", "--scenario", "small", "--projection", "utm", "--utm-zone",
                         "0", "--origin", "45,7", "--out", "{o}/p.json"]),
    ("plan utm-zone 61", ["plan", "--scenario", "small", "--projection", "utm", "--utm-zone",
                          "61", "--origin", "45,7", "--out", "{o}/p.json"]),
    ("plan utm without origin", ["plan", "--scenario", "small", "--utm-zone", "32", "--out",
                                 "{o}/p.json"]),
    ("plan origin nan", ["plan", "--scenario", "small", "--origin", "nan,nan", "--out",
                         "{o}/p.json"]),
    ("plan origin 91", ["plan", "--scenario", "small", "--origin", "91,0", "--out",
                        "{o}/p.json"]),
    ("plan origin abc", ["plan", "--scenario", "small", "--origin", "abc", "--out",
                         "{o}/p.json"]),
    ("plan origin inf", ["plan", "--scenario", "small", "--origin", "45,inf", "--out",
                         "{o}/p.json"]),
    ("plan scenario missing", ["plan", "--scenario", "{o}/nope.yaml", "--out", "{o}/p.json"]),
    ("plan scenario dir", ["plan", "--scenario", "{i}", "--out", "{o}/p.json"]),
    ("plan scenario empty", ["plan", "--scenario", "", "--out", "{o}/p.json"]),
    ("plan map missing", ["plan", "--scenario", "small", "--map", "{o}/nope.npy", "--out",
                          "{o}/p.json"]),
    ("plan map dir", ["plan", "--scenario", "small", "--map", "{i}", "--out", "{o}/p.json"]),
    ("plan map plan.json", ["plan", "--scenario", "small", "--map", "{i}/plan.json", "--out",
                            "{o}/p.json"]),
    ("plan overrides nan", ["plan", "--scenario", "small", "--overrides",
                            "sensor.sweep_width_km=nan", "--out", "{o}/p.json"]),
    ("plan overrides junk", ["plan", "--scenario", "small", "--overrides", "junk", "--out",
                             "{o}/p.json"]),
    ("plan overrides unknown", ["plan", "--scenario", "small", "--overrides", "no.such=1",
                                "--out", "{o}/p.json"]),
    ("plan out same as plot", ["plan", "--scenario", "small", "--out", "{o}/p.png", "--plot",
                               "{o}/p.png"]),
    ("plan out empty", ["plan", "--scenario", "small", "--out", ""]),
    ("plan out NUL", ["plan", "--scenario", "small", "--out", "{o}/a\0b.json"]),
    ("plan out 300", ["plan", "--scenario", "small", "--out", "{o}/" + LONG + ".json"]),
    ("plan out newline", ["plan", "--scenario", "small", "--quiet", "--out", "{o}/a\nb.json"]),
    # replan
    ("replan plan missing", ["replan", "--plan", "{o}/nope.json", "--out", "{o}/n.json"]),
    ("replan plan dir", ["replan", "--plan", "{i}", "--out", "{o}/n.json"]),
    ("replan tracks missing", ["replan", "--plan", "{i}/plan.json", "--tracks",
                               "{o}/nope.geojson", "--out", "{o}/n.json"]),
    ("replan seed -1", ["replan", "--plan", "{i}/plan.json", "--seed", "-1", "--out",
                        "{o}/n.json"]),
    ("replan out = plan", ["replan", "--plan", "{o}/plan_copy.json", "--out",
                           "{o}/plan_copy.json"]),
    # export
    ("export alt nan", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-m", "nan",
                        "--out", "{o}/x"]),
    ("export alt inf", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-m", "inf",
                        "--out", "{o}/x"]),
    ("export alt -1", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-m", "-1",
                       "--out", "{o}/x"]),
    ("export alt 0", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-m", "0",
                      "--out", "{o}/x"]),
    ("export field nan", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-ref",
                          "amsl", "--field-elevation-m", "nan", "--out", "{o}/x"]),
    ("export field inf", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-ref",
                          "amsl", "--field-elevation-m", "inf", "--out", "{o}/x"]),
    ("export ref bogus", ["export", "{i}/plan.json", "--format", "qgc", "--altitude-ref",
                          "bogus", "--out", "{o}/x"]),
    ("export format bogus", ["export", "{i}/plan.json", "--format", "bogus", "--out", "{o}/x"]),
    ("export plan missing", ["export", "{o}/nope.json", "--format", "kml", "--out", "{o}/x"]),
    ("export plan dir", ["export", "{i}", "--format", "kml", "--out", "{o}/x"]),
    ("export plan not json", ["export", "{i}/sightings.csv", "--format", "kml", "--out",
                              "{o}/x"]),
    ("export utm-zone 99", ["export", "{i}/plan.json", "--format", "kml", "--projection",
                            "utm", "--utm-zone", "99", "--out", "{o}/x"]),
    # evaluate
    ("eval episodes -1", ["evaluate", "--episodes", "-1"]),
    ("eval workers 0", ["evaluate", "--workers", "0", "--episodes", "1"]),
    ("eval workers 1e6", ["evaluate", "--workers", "1000000", "--episodes", "1"]),
    ("eval seed 2^70", ["evaluate", "--seed", str(2**70), "--episodes", "1"]),
    ("eval task bogus", ["evaluate", "--task", "bogus", "--episodes", "1"]),
    ("eval task+scenario", ["evaluate", "--task", "poc_env/UAVSearch-Small-Heading-v1",
                            "--scenario", "small", "--episodes", "1"]),
    ("eval policy bogus", ["evaluate", "--policies", "bogus,random", "--episodes", "1"]),
    ("eval ppo missing", ["evaluate", "--policies", "ppo:{o}/nope,random", "--episodes", "1"]),
    ("eval ppo ../x", ["evaluate", "--policies", "ppo:../x,random", "--episodes", "1"]),
    ("eval ppo dir", ["evaluate", "--policies", "ppo:{i},random", "--episodes", "1"]),
    ("eval ppo empty", ["evaluate", "--policies", "ppo:,random", "--episodes", "1"]),
    ("eval alloc@bogus", ["evaluate", "--policies", "allocation_plan@bogus,random",
                          "--episodes", "1"]),
    ("eval baseline bogus", ["evaluate", "--policies", "lawnmower,random", "--baseline",
                             "bogus", "--episodes", "1"]),
    ("eval map dir", ["evaluate", "--scenario", "small", "--map", "{i}", "--episodes", "1"]),
    ("eval out = file", ["evaluate", "--episodes", "1", "--out", "{i}/plan.json"]),
    # render
    ("render max-steps -1", ["render", "--max-steps", "-1", "--out", "{o}/e.gif"]),
    ("render every -1", ["render", "--every", "-1", "--out", "{o}/e.gif"]),
    ("render policy bogus", ["render", "--policy", "bogus", "--out", "{o}/e.gif"]),
    ("render out no ext", ["render", "--max-steps", "2", "--out", "{o}/episode"]),
    ("render out .png", ["render", "--max-steps", "2", "--out", "{o}/episode.png"]),
    # survey
    ("survey regions missing", ["survey", "--regions", "{o}/nope.yaml"]),
    ("survey regions ../", ["survey", "--regions", "../scenarios/small"]),
    ("survey plan-out dir", ["survey", "--plan-out", "{i}"]),
    ("survey origin bad", ["survey", "--plan-out", "{o}/s.json", "--origin", "1,2,3"]),
    ("survey origin without plan-out", ["survey", "--origin", "45,7"]),
    ("survey utm-zone -1", ["survey", "--plan-out", "{o}/s.json", "--origin", "45,7",
                            "--projection", "utm", "--utm-zone", "-1"]),
    # summarise
    ("summarise missing", ["summarise", "{o}/nope"]),
    ("summarise file", ["summarise", "{i}/plan.json"]),
    ("summarise baseline bogus", ["summarise", "{i}/eval", "--baseline", "bogus", "--out",
                                  "{o}/s"]),
    # curve
    ("curve missing", ["curve", "{o}/nope", "--out", "{o}/c.png"]),
    ("curve until 0", ["curve", "{i}/run", "--until", "0", "--out", "{o}/c.png"]),
    ("curve until -1", ["curve", "{i}/run", "--until", "-1", "--out", "{o}/c.png"]),
    ("curve not a run", ["curve", "{i}", "--out", "{o}/c.png"]),
    ("curve file", ["curve", "{i}/plan.json", "--out", "{o}/c.png"]),
    # train
    *[
        (f"train {opt} {v}", ["train", "--scenario", "small", opt, v, "--run-dir", "{o}/run"])
        for opt, vals in {
            "--total-timesteps": ["-1"],
            "--learning-rate": ["nan", "inf", "-1", "0"],
            "--gamma": ["2", "nan", "-0.5"],
            "--gae-lambda": ["nan", "1.5"],
            "--ent-coef": ["nan", "-1", "inf"],
            "--n-envs": ["0", "-1"],
            "--seed": ["-1"],
            "--checkpoint-every": ["0"],
            "--batch-size": ["0"],
            "--n-steps": ["0", "1"],
            "--n-epochs": ["0"],
            "--keep-checkpoints": ["-1"],
            "--torch-threads": ["0"],
            "--recipe": ["bogus"],
            "--algo": ["bogus"],
            "--engine": ["bogus"],
            "--net-arch": ["0", "-5"],
            "--approach-shaping": ["nan"],
            "--from-card": ["bogus", "../x", ""],
            "--bc-teacher": ["bogus"],
        }.items()
        for v in vals
    ],
    ("train resume missing", ["train", "--resume", "{o}/nope"]),
    ("train resume file", ["train", "--resume", "{i}/plan.json"]),
    ("train resume + seed", ["train", "--resume", "{i}/run", "--seed", "3"]),
    ("train scenario missing", ["train", "--scenario", "{o}/nope.yaml", "--run-dir",
                                "{o}/run"]),
    ("train task bogus", ["train", "--task", "bogus", "--run-dir", "{o}/run"]),
    ("train run-dir existing run", ["train", "--scenario", "small", "--seed", "9", "--run-dir",
                                    "{i}/run"]),
    # experiment
    ("experiment bogus", ["experiment", "bogus", "--quick", "--out", "{o}/t"]),
    ("experiment workers 0", ["experiment", "table4", "--quick", "--workers", "0", "--out",
                              "{o}/t"]),
    ("experiment seed -1", ["experiment", "table4", "--quick", "--seed", "-1", "--out",
                            "{o}/t"]),
    ("experiment preset bogus", ["experiment", "table4", "--quick", "--preset", "bogus",
                                 "--out", "{o}/t"]),
    # scenario import
    *[
        (f"import cell-km {v}", ["scenario", "import", "{i}/area.geojson", "--prior",
                                 "{i}/sightings.csv", "--airfields", "{i}/fields.geojson",
                                 "--cell-km", v, "--out", "{o}/h.yaml"])
        for v in ("0", "-1", "nan", "inf", "1e-9")
    ],
    ("import area missing", ["scenario", "import", "{o}/nope.geojson", "--airfields",
                             "{i}/fields.geojson", "--out", "{o}/h.yaml"]),
    ("import area dir", ["scenario", "import", "{i}", "--airfields", "{i}/fields.geojson",
                         "--out", "{o}/h.yaml"]),
    ("import base bogus", ["scenario", "import", "{i}/area.geojson", "--airfields",
                           "{i}/fields.geojson", "--base", "bogus", "--out", "{o}/h.yaml"]),
    ("import projection bogus", ["scenario", "import", "{i}/area.geojson", "--airfields",
                                 "{i}/fields.geojson", "--projection", "bogus", "--out",
                                 "{o}/h.yaml"]),
    ("import out dir", ["scenario", "import", "{i}/area.geojson", "--airfields",
                        "{i}/fields.geojson", "--out", "{o}"]),
    ("import out .json", ["scenario", "import", "{i}/area.geojson", "--airfields",
                          "{i}/fields.geojson", "--out", "{o}/h.json"]),
    # record
    ("record task bogus", ["record", "--task", "bogus", "--dir", "{o}/rec"]),
    ("record dir file", ["record", "--task", "poc_env/UAVSearch-Small-Heading-v1", "--dir",
                         "{i}/plan.json"]),
    # spec
    ("spec doc missing", ["spec", "--doc", "{o}/nope.md"]),
    ("spec doc dir", ["spec", "--doc", "{i}"]),
    # demo
    ("demo episodes 0", ["demo", "--episodes", "0", "--out", "{o}/d"]),
    ("demo workers -1", ["demo", "--workers", "-1", "--out", "{o}/d"]),
    # names reaching file names
    *[(f"import out name {n!r}", ["scenario", "import", "{i}/area.geojson", "--airfields",
                                   "{i}/fields.geojson", "--out", "{o}/" + n + ".yaml"])
      for n in NAMES],
    *[(f"train task name {n!r}", ["train", "--task", n, "--total-timesteps", "1"])
      for n in NAMES],
    *[(f"eval task name {n!r}", ["evaluate", "--task", n, "--episodes", "1"]) for n in NAMES],
    *[(f"record task name {n!r}", ["record", "--task", n, "--dir", "{o}/rec"]) for n in NAMES],
    *[(f"experiment name {n!r}", ["experiment", n, "--quick", "--out", "{o}/t"])
      for n in NAMES],
    *[(f"from-card {n!r}", ["train", "--from-card", n, "--run-dir", "{o}/run"])
      for n in NAMES],
    *[(f"export plan name {n!r}", ["export", "{o}/" + n + ".json", "--format", "geojson",
                                   "--out", "{o}/x"]) for n in NAMES],
]  # fmt: skip


def snapshot(root: Path) -> dict[str, int]:
    return {str(p): p.stat().st_mtime_ns for p in root.rglob("*")}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--inputs", required=True)
    ap.add_argument("--log", required=True)
    ap.add_argument("--root", default="/tmp/cli-audit/probe")
    ap.add_argument("--only", default=None, help="probe ids containing this text")
    a = ap.parse_args()
    from poc_env.cli import main as cli

    inp = Path(a.inputs)
    root = Path(a.root)
    root.mkdir(parents=True, exist_ok=True)
    with open(a.log, "a", encoding="utf-8") as log:
        for k, (pid, argv_t) in enumerate(P):
            if a.only and a.only not in pid:
                continue
            work = root / f"p{k}"
            out = work / "o"
            out.mkdir(parents=True, exist_ok=True)
            import shutil

            shutil.copy(inp / "plan.json", out / "plan_copy.json")
            for n in NAMES:  # the export plan-name probes read a plan under that name
                with contextlib.suppress(OSError, ValueError):
                    shutil.copy(inp / "plan.json", out / f"{n}.json")
            before = {w: snapshot(w) for w in (inp,)}
            top_before = set(os.listdir(root.parent)) | set(os.listdir(work.parent))
            argv = [s.format(i=inp, o=out) for s in argv_t]
            err, sout = io.StringIO(), io.StringIO()
            cwd = os.getcwd()
            os.chdir(work)
            code: object
            tb = ""
            try:
                with contextlib.redirect_stderr(err), contextlib.redirect_stdout(sout):
                    code = cli(argv)
            except SystemExit as e:
                code = e.code
            except BaseException as e:  # a traceback the user would see
                code = f"TRACEBACK {type(e).__name__}"
                tb = "".join(traceback.format_exception_only(type(e), e)).strip()
            finally:
                os.chdir(cwd)
            after = {w: snapshot(w) for w in (inp,)}
            stray = sorted(set(after[inp]) - set(before[inp]))
            # anything new beside the probe folders, or in the folder above them
            outside = sorted(
                (set(os.listdir(root.parent)) | set(os.listdir(work.parent)))
                - top_before
                - {work.name}
            )
            e = err.getvalue().strip().splitlines()
            rec = {"probe": pid, "exit": code, "err": e[-1][:300] if e else "",
                   "traceback": tb[:300], "stray_in_inputs": stray[:5],
                   "outside": outside[:5]}  # fmt: skip
            print(json.dumps(rec, ensure_ascii=False), file=log, flush=True)
            print(pid, code, (e[-1][:160] if e else ""), tb[:160], file=sys.__stdout__)
            shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
