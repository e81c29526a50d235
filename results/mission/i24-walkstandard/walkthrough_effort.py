"""The SAR walkthrough (docs/missions.md) at the default effort and at ``--effort standard``,
three sorties each: the page's blocks run as written (``tests/e2e/test_sar_walkthrough.py``
reads them from the page; its synthetic DEM), with ``plan`` and ``replan`` given the effort,
a third sortie (``replan --plan p1.json --plan p2.json``) and every export format for every
sortie. One JSON line per sortie: planned POS (sortie 1: plan.json's ``posc``; sorties 2-3:
``sortie_posc``, the routes swept over the belief the earlier sorties' routes left, point by
point, and the planner's own ``posc`` on cells), the cumulative POS replan prints, flown POS
(one episode, seed 0, of the plan flown by the plan policies' follower, as
``agents/testing/flights.fly`` flies it; sorties 2-3 on the environment's belief at the end of
the previous sortie's flight, so the flown sorties chain as the aircraft would: eq. 14 over
every flight), no-fly / out-of-bounds / collision steps, the
command's CPU seconds (its process and children: Python start-up, terrain, planning, writing)
and the planner's printed seconds, and the 1-minute load. Run from the repository root:
``OMP_NUM_THREADS=1 .venv/bin/python results/mission/i24-walkstandard/walkthrough_effort.py
[--variants default,standard,standard/default]``."""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(ROOT / "tests" / "e2e"), str(ROOT / "tests" / "planning")]

import test_sar_walkthrough as W  # noqa: E402
import zone_ab  # noqa: E402

from poc_env.agents.mission.plan import load_plan  # noqa: E402
from poc_env.agents.planning.replan import _swept, plan_paths  # noqa: E402
from poc_env.config import load_scenario  # noqa: E402
from poc_env.theory.probability_map import build_prior  # noqa: E402

OVR = "--overrides uav.max_altitude_m=6000"
FORMATS = ("qgc", "kml", "geojson", "html")


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _cmd(line: str, cwd: Path) -> tuple[str, float]:
    """Run one shell line with the venv's poc-env first on PATH: (stdout, CPU seconds)."""
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    before = _cpu_children()
    done = subprocess.run(["bash", "-e", "-c", line], cwd=cwd, env=env, capture_output=True,
                          text=True, check=False)  # fmt: skip
    cpu = _cpu_children() - before
    if done.returncode != 0:
        raise SystemExit(f"{line}\n{done.stderr[-2000:]}")
    return done.stdout + done.stderr, cpu


def _with_effort(line: str, effort: str) -> str:
    """``line`` (one command of the page's block) with ``--effort`` set to ``effort`` on
    ``plan`` and ``replan`` (replaced where the page gives one, added where it does not)."""
    line = re.sub(r"\s--effort \S+", "", line)
    if effort == "default" or not re.match(r"poc-env (plan|replan) ", line):
        return line
    return line.replace(" --out ", f" --effort {effort} --out ", 1)


def _fly_after(sc, plan: dict, prior: np.ndarray, left: np.ndarray | None):
    """Fly ``plan`` for one episode (seed 0) on what the flights before it left: ``left``, the
    environment's fine belief at the previous flight's end in the prior's units (None: sortie
    1, the prior). Returns (a :class:`Flight` whose ``posc`` is this flight's POS in the prior's
    units, the fine belief it leaves, likewise)."""
    from poc_env.agents.testing.flights import Flight
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario=sc)
    g = env.params.grid
    s = env.params.s
    mass = 1.0 if left is None else float(left.sum())
    cells = np.asarray(prior, dtype=float) if left is None else g.coarsen(left, s)
    obs, _ = env.reset(seed=0, options={"prior": cells / cells.sum()})
    st = env.sim_state
    if left is not None:  # the flights before left the belief uneven within cells: keep it
        st.belief[0] = left / mass * st.initial_mass[0]
    policy = zone_ab._Fly(plan)
    policy.reset(env, 0)
    counts = [0, 0, 0]
    while env.agents:
        actions, _ = policy.predict(obs)
        obs, _, _, _, infos = env.step(actions)
        for i, key in enumerate(("violation_no_fly", "violation_out_of_bounds",
                                 "violation_collision")):  # fmt: skip
            counts[i] += sum(int(v[key]) for v in infos.values())
    st = env.sim_state
    flight = Flight(counts[0], counts[1], int(st.landed[0].sum()), float(st.posc[0]) * mass,
                    counts[2])  # fmt: skip
    out = st.belief[0] / st.initial_mass[0] * mass
    env.close()
    return flight, out


def run(variant: str) -> list[dict]:
    """The walkthrough's three sorties with ``variant``: one effort for ``plan`` and
    ``replan``, or ``PLAN/REPLAN`` (e.g. ``standard/default``: the replans at the default)."""
    first, _, later = variant.partition("/")
    later = later or first
    tmp = Path(tempfile.mkdtemp(prefix="walkstandard_"))
    setup, flight = W._blocks()
    W._run(setup, tmp)
    W._terrain_test()._dem(tmp / "dem.tif")
    # the flight block, one command a line (continuations joined)
    lines = [ln.split("  #")[0].strip() for ln in flight.replace("\\\n", " ").splitlines()]
    lines = [re.sub(r"\s+", " ", ln) for ln in lines if ln]
    rows: list[dict] = []
    printed: dict[str, tuple[str, float]] = {}
    for ln in lines:
        effort = first if ln.startswith("poc-env plan ") else later
        out, cpu = _cmd(_with_effort(ln, effort), tmp)
        if ln.startswith("poc-env plan ") or ln.startswith("poc-env replan "):
            printed[re.search(r"--out (\S+)", ln).group(1)] = (out, cpu)
    third = f"poc-env replan --scenario alps.yaml --plan p1.json --plan p2.json {OVR} --out p3.json"
    printed["p3.json"] = _cmd(_with_effort(third, later), tmp)
    # every format for every sortie
    exported = {}
    for k in (1, 2, 3):
        for fmt in FORMATS:
            _cmd(f"poc-env export p{k}.json --format {fmt} --out x_sortie{k}", tmp)
        exported[k] = sorted(p.name for p in (tmp / f"x_sortie{k}").iterdir())
    sc = load_scenario(tmp / "alps.yaml", {"uav.max_altitude_m": 6000})
    prior = build_prior(sc.map)
    plans = [dict(load_plan(tmp / f"p{k}.json")) for k in (1, 2, 3)]
    flown_cum, left = 0.0, None
    for k, plan in enumerate(plans, start=1):
        paths = [p for q in plans[: k - 1] for p in plan_paths(q)]
        searched = _swept(sc, prior, paths)[3] if paths else 0.0
        f, left = _fly_after(sc, plan, prior, left)
        flown = f.posc
        flown_cum += flown
        out, cpu = printed[f"p{k}.json"]
        secs = re.search(r"\(allocation, seed \d+, ([\d.]+) s\)", out)
        rows.append({
            "variant": variant, "effort": first if k == 1 else later, "sortie": k,
            "planned": round(float(plan.get("sortie_posc", plan["posc"])), 4),
            "planner_posc": round(float(plan["posc"]), 4),
            "cumulative": round(float(plan.get("cumulative_posc", plan["posc"])), 4),
            "searched_before": round(float(searched), 4),
            "flown": round(flown, 4), "flown_cumulative": round(flown_cum, 4),
            "nofly": f.nofly_steps, "oob": f.oob_steps, "collision": f.collision_steps,
            "landed": f.landed,
            "cmd_cpu_s": round(cpu, 2), "printed_s": float(secs.group(1)) if secs else None,
            "polish": (plan.get("optimizer", {}).get("settings", {}).get("polish") or {}),
            "exports": len(exported[k]), "html": f"p{k}.html" in exported[k],
            "load": round(os.getloadavg()[0], 2),
        })  # fmt: skip
        print(json.dumps(rows[-1], default=str), flush=True)
    shutil.rmtree(tmp, ignore_errors=True)
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--variants", default="default,standard,standard/default")
    a = ap.parse_args()
    for v in a.variants.split(","):
        run(v)
