"""Issue 24, i24-tightbound: the stored ``poc-env bench plan --scale`` records of a map with
more than two airfields renormalised by the tight rule-aware bound, no re-flying.

:func:`poc_env.theory.bound.rule_bound` used to merge airfields beyond two (a valid, loose
relaxation); since i24-tightbound it is the least of the merged relaxations and of sums over
blocks of at most two fields. For each record file this recomputes each seed's bound from the
seed's prior (``episode_prior``, the bench's), checks that the stored ``rule_bound`` is the
merged relaxation's (``RuleBound.merged``, to 1e-9), and rewrites the file (atomically) with
``rule_bound`` the new bound, ``rule_bound_merged`` the stored one, ``rule_bound_how`` how it
was obtained, and the summary's ratios recomputed as ``poc_env.agents.benchmarks.plan_scale.
quality`` computes them (``*_rule_merged``: the old ones). Files already rewritten are checked
against the recomputed bound instead.

``timing [N]``: the relaxation alone (one solve) against ``rule_bound`` on ``large_400``,
``wide_400`` and ``paper_6_2``'s random priors 0..N-1 (default 3), interleaved per prior;
medians and the median ratio (run with ``OMP_NUM_THREADS=1``).

    PYTHONPATH=. OMP_NUM_THREADS=1 python results/plan_scale/rebound.py \
        results/plan_scale/large_400.json results/plan_scale/large_400_b.json
"""

from __future__ import annotations

import json
import sys

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.io import atomic_path
from poc_env.theory.bound import rule_bound


def _summary(eps: list[dict], key: str) -> dict[str, float]:
    out: dict[str, float] = {}
    for name in sorted({e["map"] for e in eps}):
        share = {
            pol: np.array(
                [e["posc"] / e[key] for e in eps if e["map"] == name and e["policy"] == pol]
            )
            for pol in ("allocation_plan", "greedy_rectangles")
        }
        sfx = "" if key == "rule_bound" else "_merged"
        for pol, x in share.items():
            out[f"{name}_{pol}_rule{sfx}"] = float(np.mean(x))
        planned = [e["planned_posc"] / e[key] for e in eps
                   if e["map"] == name and e["policy"] == "allocation_plan"]  # fmt: skip
        out[f"{name}_allocation_planned_rule{sfx}"] = float(np.mean(planned))
        d = share["allocation_plan"] - share["greedy_rectangles"]
        out[f"{name}_lead{sfx}"] = float(d.mean())
        out[f"{name}_wins{sfx}"] = float(np.sum(d > 0))
    return out


def rebound(path: str) -> None:
    with open(path) as f:
        data = json.load(f)
    eps = data["episodes"]
    for name in sorted({e["map"] for e in eps}):
        sc = load_scenario(name)
        for seed in sorted({e["seed"] for e in eps if e["map"] == name}):
            rb = rule_bound(sc, episode_prior(sc, seed))
            for e in eps:
                if e["map"] != name or e["seed"] != seed:
                    continue
                old = e.get("rule_bound_merged", e["rule_bound"])
                if abs(old - rb.merged) > 1e-9 * max(1.0, rb.merged):
                    raise SystemExit(f"{path}: seed {seed}: stored bound {old} is not {rb.merged}")
                if "rule_bound_merged" in e and abs(e["rule_bound"] - rb.upper) > 1e-9:
                    raise SystemExit(f"{path}: seed {seed}: {e['rule_bound']} is not {rb.upper}")
                e.update(rule_bound=rb.upper, rule_bound_merged=old, rule_bound_how=rb.how)
            print(f"{name} {seed}: merged {rb.merged:.4f} -> {rb.upper:.4f} ({rb.how})", flush=True)
    data["summary"] = {**_summary(eps, "rule_bound"), **_summary(eps, "rule_bound_merged")}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n")
    print(json.dumps(data["summary"], indent=1))


def timing(n: int) -> None:
    import os
    import time

    from poc_env.theory.bound import _rule_relaxation, env_limits

    print(f"load average {os.getloadavg()[0]:.1f}")
    for name in ("large_400", "wide_400", "paper_6_2"):
        sc = load_scenario(name)
        rho = env_limits(sc).spill_m
        one, full = [], []
        for seed in range(n):
            prior = episode_prior(sc, seed)
            t = time.perf_counter()
            _rule_relaxation(sc, prior, rho)
            one.append(time.perf_counter() - t)
            t = time.perf_counter()
            rule_bound(sc, prior)
            full.append(time.perf_counter() - t)
        ratio = np.median(np.array(full) / np.array(one))
        print(f"{name}: relaxation {np.median(one):.3f} s, rule_bound {np.median(full):.3f} s, "
              f"ratio {ratio:.2f} (median of {n})")  # fmt: skip
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    if sys.argv[1] == "timing":
        timing(int(sys.argv[2]) if len(sys.argv) > 2 else 3)
        sys.exit()
    for p in sys.argv[1:]:
        rebound(p)
