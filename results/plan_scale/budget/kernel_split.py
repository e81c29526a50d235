"""i24-budget: where the polish's compiled kernel (``exposure_gains``) spends its time, on the
calls of one real plan (a script, not a test).

``python results/plan_scale/budget/kernel_split.py SEED OUT.json`` (-1: ``paper_6_2``'s own
prior): records every ``exposure_gains`` call of ``standard``'s plan of the prior, then replays
them (3 rounds, one thread, CPU time) through

* ``reference``: the kernel as it was before i24-budget (every candidate step computed);
* ``no_steps``: the reference without the candidates' steps (the old steps, the copies of
  ``base`` and the sums only; not a gain, a split);
* ``no_sum``: the reference without the ``expm1`` sum (the steps only; a split);
* ``kept``: this branch's kernel (a candidate's step that is an old step adds its kept
  values), checked bit for bit against ``reference`` on every call;

and counts the candidates' steps that are old steps.
"""

import json
import math
import os
import sys
import time

import numpy as np
from numba import njit

sys.path.insert(0, "tests/planning")

from effort_ab import _options

import poc_env.agents.planning.polish as pol
from poc_env._kernels import sensing
from poc_env._kernels.sensing import leg_exposure
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario
from poc_env.io import write_text_atomic
from poc_env.theory.probability_map import build_prior


@njit(error_model="numpy")
def reference(live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach, cell, h, base,
              work, out, mode):  # fmt: skip
    """``exposure_gains`` before i24-budget (``mode`` 0); 1 without the candidates' steps, 2
    without the sum."""
    ny, nx = live.shape
    box_o = np.array([ny, 0, nx, 0])
    for o in range(old_a.shape[0]):
        leg_exposure(law, old_a[o, 0], old_a[o, 1], old_b[o, 0], old_b[o, 1], w, cutoff, reach,
                     cell, h, -1.0, base, box_o)  # fmt: skip
    box = np.empty(4, np.int64)
    for c in range(first.shape[0] - 1):
        box[:] = box_o
        for j in range(box_o[0], box_o[1]):
            for k in range(box_o[2], box_o[3]):
                work[j, k] = base[j, k]
        if mode != 1:
            for i in range(first[c], first[c + 1]):
                leg_exposure(law, new_a[i, 0], new_a[i, 1], new_b[i, 0], new_b[i, 1], w, cutoff,
                             reach, cell, h, 1.0, work, box)  # fmt: skip
        g = 0.0
        for j in range(box[0], box[1]):
            for k in range(box[2], box[3]):
                d = work[j, k]
                if d != 0.0:
                    if mode != 2:
                        g += live[j, k] * -math.expm1(-d)
                    work[j, k] = 0.0
        out[c] = g
    for j in range(box_o[0], box_o[1]):
        for k in range(box_o[2], box_o[3]):
            base[j, k] = 0.0


class _Recorder:
    def __init__(self, calls):
        self.calls = calls

    def __getattr__(self, name):
        return getattr(sensing, name)

    def exposure_gains(self, *a):
        self.calls.append([x.copy() if isinstance(x, np.ndarray) else x for x in a])
        sensing.exposure_gains(*a)


def main(seed: int, out: str) -> None:
    sc = load_scenario("paper_6_2")
    prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
    calls: list = []
    pol._sensing = _Recorder(calls)
    make_allocation_plan(sc, prior=prior, options=_options("standard"))
    pol._sensing = sensing
    steps = kept = 0
    for a in calls:
        old = {(tuple(x), tuple(y)) for x, y in zip(a[1], a[2], strict=True)}
        for x, y in zip(a[3], a[4], strict=True):
            steps += 1
            kept += (tuple(x), tuple(y)) in old

    def run(f, *extra):
        c0 = time.process_time()
        outs = []
        for a in calls:
            a = list(a)
            a[14] = np.empty_like(a[14])
            f(*a, *extra)
            outs.append(a[14])
        return time.process_time() - c0, outs

    rec = {"seed": seed, "calls": len(calls), "candidate_steps": steps, "old_steps": kept,
           "rounds": []}  # fmt: skip
    _, ref = run(reference, 0)
    _, new = run(sensing.exposure_gains)
    rec["bit_equal"] = all(
        np.array_equal(x.view(np.int64), y.view(np.int64)) for x, y in zip(ref, new, strict=True)
    )
    run(reference, 1)
    run(reference, 2)
    for _ in range(3):
        r = {name: run(*f)[0] for name, f in (("reference", (reference, 0)),
                                               ("no_steps", (reference, 1)),
                                               ("no_sum", (reference, 2)),
                                               ("kept", (sensing.exposure_gains,)))}  # fmt: skip
        r["load"] = os.getloadavg()[0]
        rec["rounds"].append(r)
        print(json.dumps(r), flush=True)
    print(json.dumps({k: v for k, v in rec.items() if k != "rounds"}), flush=True)
    write_text_atomic(out, json.dumps(rec, indent=1))


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
