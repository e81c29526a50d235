"""The walkthrough's ``plan`` (sortie 1) and ``replan`` (sortie 2, after the default sortie 1)
commands at the default effort and at ``--effort standard``, timed in interleaved pairs (the
order alternating) in one prepared folder: the command's CPU seconds (its process and
children, one thread) and the planner's printed seconds, with the 1-minute load. One JSON line
per command. Run from the repository root: ``OMP_NUM_THREADS=1 .venv/bin/python
results/mission/i24-walkstandard/timing.py [--pairs 3]``."""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent)]

import walkthrough_effort as E  # noqa: E402

PLAN = (f"poc-env plan --scenario alps.yaml --planner allocation {E.OVR} --quiet "
        "{effort}--out t_{tag}.json")  # fmt: skip
REPLAN = (
    f"poc-env replan --scenario alps.yaml --plan p1.json {E.OVR} {{effort}}--out t_{{tag}}.json"
)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--pairs", type=int, default=3)
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="walkstandard_t_"))
    setup, flight = E.W._blocks()
    E.W._run(setup, tmp)
    E.W._terrain_test()._dem(tmp / "dem.tif")
    imp = flight.replace("\\\n", " ").splitlines()[0]
    E._cmd(imp, tmp)
    E._cmd(PLAN.format(effort="", tag="warm").replace("t_warm", "p1"), tmp)  # warm caches
    for i in range(a.pairs):
        order = ("default", "standard") if i % 2 == 0 else ("standard", "default")
        for cmd_name, template in (("plan", PLAN), ("replan", REPLAN)):
            for effort in order:
                flag = "" if effort == "default" else f"--effort {effort} "
                out, cpu = E._cmd(template.format(effort=flag, tag=f"{cmd_name}{effort}{i}"), tmp)
                secs = re.search(r"\(allocation, seed \d+, ([\d.]+) s\)", out)
                print(json.dumps({"command": cmd_name, "effort": effort, "pair": i,
                                  "cmd_cpu_s": round(cpu, 2),
                                  "printed_s": float(secs.group(1)) if secs else None,
                                  "load": round(os.getloadavg()[0], 2)}), flush=True)  # fmt: skip
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
