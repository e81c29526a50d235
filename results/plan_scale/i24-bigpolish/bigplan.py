"""i24-bigpolish: plans of the 500 km scenario by effort variants, CPU time and planned POS_C,
with the polish's own counters per stage and pass (a script, not a test).

``python bigplan.py OUT.jsonl SCENARIO.yaml [SCENARIO.yaml ...] -- VARIANT [VARIANT ...]``
    (from the checkout, one thread) each scenario's own prior planned by each variant in turn
    (interleaved: the variants of one scenario one after the other in one process), one JSON
    line per plan: CPU seconds (``time.process_time``), wall seconds, the 1-minute load,
    planned POS_C, the polish's settings record and, per polish stage call and pass, the CPU
    seconds, the candidate sets scored, the candidates, the kept moves and their gain (from
    ``polish_routes``' ``trace``). VARIANT as tests/planning/effort_ab.py's
    (``standard+polish_max_cells=0``).
"""

import json
import os
import sys
import time
from collections import defaultdict

sys.path.insert(0, "tests/planning")
from effort_ab import _options

from poc_env.agents.planning import allocation
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior

_real = allocation.polish_for
calls: list[dict] = []


def traced(*a, **kw):
    """allocation.polish_for with a trace counting per pass (polish_routes only)."""
    if kw.get("routine") is not None:
        t0 = time.process_time()
        out = _real(*a, **kw)
        calls.append({"stage": "regrade", "cpu": time.process_time() - t0})
        return out
    passes = defaultdict(lambda: defaultdict(float))
    rec = {"stage": ",".join(kw.get("moves", ())), "passes": passes}
    last = [time.process_time()]

    def trace(kind, p, k, i, window, n, kept, gain):
        now = time.process_time()
        d = rec["passes"][p]
        d["cpu"] += now - last[0]
        d[f"cpu_{kind}"] += now - last[0]
        last[0] = now
        d["sets"] += 1
        d["cands"] += n
        if kept >= 0:
            d["kept"] += 1
            d["gain"] += gain
            d[f"gain_{kind}"] += gain

    t0 = time.process_time()
    out = _real(*a, trace=trace, **kw)
    rec["cpu"] = time.process_time() - t0
    rec["passes"] = {p: dict(v) for p, v in rec["passes"].items()}
    rec["result"] = {"pos": out[1], **out[2]}
    calls.append(rec)
    return out


allocation.polish_for = traced

if __name__ == "__main__":
    cut = sys.argv.index("--")
    out, scen, variants = sys.argv[1], sys.argv[2:cut], sys.argv[cut + 1 :]
    for path in scen:
        sc = load_scenario(path)
        prior = build_prior(sc.map)
        for name in variants:
            calls.clear()
            opt = _options(name)
            t0, w0 = time.process_time(), time.perf_counter()
            plan = allocation.make_allocation_plan(sc, prior=prior, options=opt)
            cpu, wall = time.process_time() - t0, time.perf_counter() - w0
            st = plan["optimizer"]["settings"]
            rec = {"scenario": os.path.basename(path), "variant": name, "cpu_s": round(cpu, 2),
                   "wall_s": round(wall, 2), "load1": os.getloadavg()[0],
                   "posc": plan["posc"], "start": plan["start"],
                   "polish": st.get("polish"), "calls": calls[:]}  # fmt: skip
            with open(out, "a") as f:
                f.write(json.dumps(rec) + "\n")
            print(rec["scenario"], name, rec["cpu_s"], round(plan["posc"], 4), st.get("polish"),
                  flush=True)  # fmt: skip
