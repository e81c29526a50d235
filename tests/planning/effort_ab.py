"""Issue 24, session i24-effort (docs/PLANNER.md, "Effort levels"): a script, not a test.

``digest OUT.json``
    A digest (sha256 of every UAV's waypoints and the planned POS, ``repr`` of the floats) of
    the default allocation plan on ``paper_6_2``'s own prior, two of its random priors
    (episode seeds 0, 1), ``small`` and ``large_400``'s own prior: run before and after a
    change that must not alter the default plans, and compare the two files.
``digest OUT.json --effort VARIANT``
    The same digest of the plans of a variant (:func:`_options`: ``thorough``,
    ``default+polish=2``, ...) on ``paper_6_2``'s own prior and its random priors 0-2
    (i24-fastpolish: a speed-up of the polish must leave ``thorough``'s plans equal).
``plan MAP SEED0 SEED1 VARIANT[,VARIANT...] OUT.json``
    Planned POS_C over the rule-aware bound on ``MAP``'s random priors (the priors of
    ``poc-env bench plan --scale``; validation priors: 5000-5011 on ``paper_6_2``, 5000-5002
    on ``large_400``), every variant of :data:`VARIANTS` per seed in turn (interleaved, so the
    time ratios are paired); records rewritten after every seed; paired summary against
    ``default``.
``polish MAP SEED0 SEED1 VARIANT[,VARIANT...] OUT.json``
    As ``plan`` (seed -1: the map's own prior; i24-polish, docs/PLANNER.md "Polish by the
    environment's model"), records kept and resumed as ``fly``'s, and each
    plan's routes also scored on a finer sample lattice (``sensor.samples_per_cell = 8``, the
    same routes, ``sampled_sweep``): a polish that only learned to put lines on the 2 x 2
    sample rows would gain on the first and not on the second. Paired summaries of both
    against the first variant.
``chain MAP SEED0 SEED1 VARIANT[,VARIANT...] OUT.json``
    The planned loss chain (:func:`poc_env.agents.benchmarks.losschain.loss_chain`, no flight:
    the planned POS stands in for the flown) of each variant's plan per seed (-1: the map's own
    prior), and the mean of every link over the rule-aware bound per variant.
``fly MAP SEED0 SEED1 POLICY[,POLICY...] OUT.json CHECK RECORDS.json...``
    Registered policies (or ``allocation_plan@VARIANT``: the allocation policy with a
    variant's options) flown in the environment on the same random priors, records rewritten
    after every flight (a partial run gives paired figures; a rerun resumes): the first policy
    on every seed, the others on the first ``CHECK`` seeds only, to check they equal the stored
    ``poc-env bench plan --scale`` records (results/plan_scale/*.json), which then stand in for
    them; the rule-aware bound is the stored one (recomputed and checked on those seeds).
    Each record also has the plan's CPU time (``cpu_s``, after a warm-up plan of every
    variant) and the flight's eq. 21 / 24 violation steps (``violations``); the variants flown
    here are paired with each other too (:func:`among`; i24-sampled).
``violations MAP SEED[,SEED...] VARIANT [VARIANT...]``
    Flown violation steps and POSC per variant (``de``: ``de_plan``); on ``small`` as
    tests/policies/test_allocation.py flies it (``small 1 default q3 q3np de``).
``paired OUT.json RECORDS.json...``
    The paired summary of a ``fly`` run against the stored ``allocation_plan`` and
    ``greedy_rectangles`` flights.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
tests/planning/effort_ab.py plan paper_6_2 5000 5012 default,thorough out.json``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import statistics
import sys
import time

import numpy as np

from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.config import load_scenario
from poc_env.theory.bound import rule_bound
from poc_env.theory.probability_map import build_prior

#: named variants (a preset and ``+field=value`` changes; tuples ``:``-separated).
NAMED = {
    "q3": "default+graded=1+sampled=1+refine_sampled=1+airspace_penalty=1",
    "q3np": "default+graded=1+sampled=1+refine_sampled=1",
}


def _options(name: str):
    """The plan options of variant ``name``: a preset or a :data:`NAMED` variant, with
    ``+field=value`` changes (``thorough+angles=45``, ``q3+angles=22.5:45:67.5``)."""
    from poc_env.agents.planning.options import PlanOptions

    head, *rest = name.split("+")
    if head in NAMED:
        head, *more = NAMED[head].split("+")
        rest = more + rest
    base, changes = head, rest
    opt = PlanOptions.preset(base)
    for ch in changes:
        key, val = ch.split("=", 1)
        cur = getattr(opt, key)
        if isinstance(cur, bool):
            new: object = val.lower() in ("1", "true", "yes", "on")
        elif isinstance(cur, tuple) and cur and all(isinstance(x, int) for x in cur):
            new = tuple(int(x) for x in val.split(":") if x)  # i24-cheapolish: windows
        elif isinstance(cur, tuple):
            new = tuple(float(x) for x in val.split(":") if x)
        elif isinstance(cur, int):
            new = int(val)
        elif isinstance(cur, float):
            new = float(val)
        else:
            new = val
        opt = dataclasses.replace(opt, **{key: new})
    return opt


def _digest(plan: dict) -> str:
    h = hashlib.sha256()
    for u in plan["uavs"]:
        h.update(repr([[float(a), float(b)] for a, b in u["waypoints_m"]]).encode())
    h.update(repr(float(plan["posc"])).encode())
    return h.hexdigest()


def digest(out: str, effort: str | None = None) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    cases = [("paper_6_2", None), ("paper_6_2", 0), ("paper_6_2", 1), ("small", None),
             ("large_400", None)]  # fmt: skip
    if effort is not None:
        cases = [("paper_6_2", None), ("paper_6_2", 0), ("paper_6_2", 1), ("paper_6_2", 2)]
    opt = None if effort is None else _options(effort)
    recs = {}
    for name, seed in cases:
        sc = load_scenario(name)
        prior = None if seed is None else episode_prior(sc, seed)
        t0, c0 = time.perf_counter(), time.process_time()
        p = make_allocation_plan(sc, prior=prior, options=opt)
        key = f"{name}:{'scenario' if seed is None else seed}"
        if effort is not None:
            key += f":{effort}"
        recs[key] = {"digest": _digest(p), "posc": float(p["posc"]), "start": p["start"],
                     "plan_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0,
                     "load": os.getloadavg()[0]}  # fmt: skip
        print(key, recs[key], flush=True)
    with open(out + ".tmp", "w") as f:
        json.dump(recs, f, indent=1)
    os.replace(out + ".tmp", out)


def summary(recs: list[dict], key: str, base_name: str) -> None:
    from poc_env.stats import ci95

    names = sorted({r["variant"] for r in recs} - {base_name})
    base = {r["seed"]: r for r in recs if r["variant"] == base_name}
    for v in names:
        rs = [r for r in recs if r["variant"] == v and r["seed"] in base]
        d = np.array([r[key] / r["rule_bound"] - base[r["seed"]][key] / r["rule_bound"]
                      for r in rs])  # fmt: skip
        if not len(d):
            continue
        half = ci95(d) if len(d) > 1 else float("nan")
        wtl = f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}"
        ratio = [r["plan_s"] / base[r["seed"]]["plan_s"] for r in rs if "plan_s" in r]
        cpu = [r["cpu_s"] / base[r["seed"]]["cpu_s"] for r in rs if "cpu_s" in r]
        mean0 = statistics.mean(b[key] / b["rule_bound"] for b in base.values())
        mean1 = statistics.mean(r[key] / r["rule_bound"] for r in rs)
        med = statistics.median(r["plan_s"] for r in rs if "plan_s" in r) if ratio else float("nan")
        print(f"{v} - {base_name} ({key}/rule): {d.mean():+.4f} +- {half:.4f} {wtl} (n {len(d)}); "
              f"{base_name} {mean0:.4f}, {v} {mean1:.4f}; time ratio median "
              f"{statistics.median(ratio) if ratio else float('nan'):.2f}, {v} median {med:.1f} s"
              + (f"; CPU time ratio median {statistics.median(cpu):.2f} (max {max(cpu):.2f})"
                 if cpu else ""), flush=True)  # fmt: skip


def plan(name: str, seed0: int, seed1: int, names: list[str], out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = []
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for v in names:
            opt = _options(v)
            t0 = time.perf_counter()
            p = make_allocation_plan(sc, prior=prior, options=opt)
            dt = time.perf_counter() - t0
            recs.append(
                {"map": name, "seed": seed, "variant": v, "planned_posc": float(p["posc"]),
                 "rule_bound": bound, "start": p["start"], "refined": p["refined"],
                 "plan_s": dt, "load": os.getloadavg()[0]}
            )  # fmt: skip
            print(name, seed, v, round(p["posc"] / bound, 4), p["start"], p["refined"],
                  round(dt, 1), round(os.getloadavg()[0], 1), flush=True)  # fmt: skip
        with open(out, "w") as f:
            json.dump(recs, f, indent=1)
    summary(recs, "planned_posc", names[0])


def fine_posc(sc, prior, plan: dict, samples: int = 8) -> float:
    """``plan``'s routes scored by ``sampled_sweep`` on ``samples x samples`` points a cell."""
    from poc_env.agents.planning.allocation import sampled_sweep
    from poc_env.theory.probability_map import Grid

    fine = load_scenario(sc, overrides={"sensor.samples_per_cell": samples})
    paths = [[u["takeoff_m"], *u["waypoints_m"], u["landing_m"]] if u["waypoints_m"] else []
             for u in plan["uavs"]]  # fmt: skip
    return float(sum(sampled_sweep(fine, Grid.from_config(fine.map), prior, paths)[0]))


def resumed(out: str) -> tuple[list[dict], set[tuple[int, str]]]:
    """The records already in ``out`` (a run goes on where it stopped) and their (seed,
    variant) pairs."""
    recs: list[dict] = []
    if os.path.exists(out):
        with open(out) as f:
            recs = json.load(f)
    return recs, {(r["seed"], r["variant"]) for r in recs}


def polish(name: str, seed0: int, seed1: int, names: list[str], out: str) -> None:
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs, done = resumed(out)
    # warm-up (JIT, caches), so the first plan's CPU time is the plan's own
    make_allocation_plan(sc, options=_options("default+polish=1+polish_grade=1+polish_lines=1"))
    for seed in range(seed0, seed1):  # seed -1: the scenario's own prior
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        for v in names:
            if (seed, v) in done:
                continue
            opt = _options(v)
            t0, c0 = time.perf_counter(), time.process_time()
            p = make_allocation_plan(sc, prior=prior, options=opt)
            dt, dc = time.perf_counter() - t0, time.process_time() - c0
            moves = p["optimizer"]["settings"].get("polish", {}).get("moves", 0)
            recs.append(
                {"map": name, "seed": seed, "variant": v, "planned_posc": float(p["posc"]),
                 "fine_posc": fine_posc(sc, prior, p), "rule_bound": bound,
                 "start": p["start"], "moves": moves, "plan_s": dt, "cpu_s": dc,
                 "load": os.getloadavg()[0]}
            )  # fmt: skip
            r = recs[-1]
            print(name, seed, v, round(r["planned_posc"] / bound, 4),
                  round(r["fine_posc"] / bound, 4), moves, round(dt, 1),
                  round(os.getloadavg()[0], 1), flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)
    for base in names:
        if "polish" not in base:
            fam = [base] + [v for v in names if v.startswith(base + "+polish")]
            sub = [r for r in recs if r["variant"] in fam]
            summary(sub, "planned_posc", base)
            summary(sub, "fine_posc", base)


def chain(name: str, seed0: int, seed1: int, names: list[str], out: str) -> None:
    from poc_env.agents.benchmarks.losschain import loss_chain
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    recs = []
    for seed in range(seed0, seed1):
        prior = build_prior(sc.map) if seed < 0 else episode_prior(sc, seed)
        for v in names:
            p = make_allocation_plan(sc, prior=prior, options=_options(v))
            c = loss_chain(sc, prior, p)
            b = c["values"]["bound"]
            recs.append({"map": name, "seed": seed, "variant": v, "bound": b,
                         "links": {k: x / b for k, x in c["links"].items()},
                         "values": {k: x / b for k, x in c["values"].items()}})  # fmt: skip
            print(name, seed, v, {k: round(x, 4) for k, x in recs[-1]["links"].items()},
                  flush=True)  # fmt: skip
        with open(out + ".tmp", "w") as f:
            json.dump(recs, f, indent=1)
        os.replace(out + ".tmp", out)
    for v in names:
        rs = [r for r in recs if r["variant"] == v]
        mean = {k: statistics.mean(r["links"][k] for r in rs) for k in rs[0]["links"]}
        planned = statistics.mean(r["values"]["planned"] for r in rs)
        print(f"{v} (n {len(rs)}): planned {planned:.4f};",
              "; ".join(f"{k} {x:.4f}" for k, x in mean.items()), flush=True)  # fmt: skip


def violations(name: str, seeds: list[int], names: list[str]) -> None:
    """Flown separation-violation steps (eq. 21 / 24, the environment's count) and POSC of the
    allocation policy with each variant's options (``de`` for ``de_plan`` at the test's budget,
    popsize 16, 20 generations): on ``small`` the episode's own prior, as
    tests/policies/test_allocation.py flies it; elsewhere the random prior of the seed."""
    from poc_env.agents.policies.allocation import AllocationPlanPolicy
    from poc_env.agents.policies.de_plan import DEPlanPolicy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    sc = load_scenario(name)
    for seed in seeds:
        opts = None if name == "small" else {"prior": episode_prior(sc, seed)}
        for v in names:
            env = UAVSearchParallelEnv(scenario=sc)
            if v == "de":
                pol: object = DEPlanPolicy(popsize=16, maxiter=20)
            else:
                pol = AllocationPlanPolicy()
                pol.options = _options(v)  # type: ignore[attr-defined]
            obs, _ = env.reset(seed=seed, options=opts)
            pol.reset(env, seed)  # type: ignore[attr-defined]
            while env.agents:
                obs, *_ = env.step(pol.predict(obs)[0])  # type: ignore[attr-defined]
            st = env.sim_state
            print(name, seed, v, "violation steps", int(st.violations[0].sum()), "posc",
                  round(float(st.posc[0]), 4), flush=True)  # fmt: skip


def _policy(spec: str):
    """A registered policy's name, or ``allocation_plan@VARIANT``: the allocation policy with
    :func:`_options` of ``VARIANT`` (``allocation_plan@default+polish=2``)."""
    if "@" not in spec:
        return spec
    from poc_env.agents.policies.allocation import AllocationPlanPolicy

    head, variant = spec.split("@", 1)
    if head != "allocation_plan":
        raise SystemExit(f"{spec}: only allocation_plan@VARIANT is known")

    class Timed(AllocationPlanPolicy):
        """The allocation policy recording its planning CPU time (``cpu_s``; i24-sampled)."""

        cpu_s = float("nan")

        def make(self, env, prior, seed):  # type: ignore[no-untyped-def]
            c0 = time.process_time()
            out = super().make(env, prior, seed)
            self.cpu_s = time.process_time() - c0
            return out

    pol = Timed()
    pol.options = _options(variant)
    return pol


def stored(paths: list[str]) -> dict[tuple[int, str], dict]:
    """The episodes of ``poc-env bench plan --scale`` records (results/plan_scale/*.json) by
    (seed, policy)."""
    out = {}
    for p in paths:
        with open(p) as f:
            data = json.load(f)
        if isinstance(data, list):  # a ``fly`` run's records (results/plan_scale/effort)
            data = {"episodes": [{**r, "policy": r["variant"]} for r in data]}
        for e in data["episodes"]:
            out[e["seed"], e["policy"]] = e
    return out


def fly(name: str, seed0: int, seed1: int, policies: list[str], out: str, check: int,
        records: list[str]) -> None:  # fmt: skip
    """``policies[0]`` flown on every seed, the others on the first ``check`` seeds only (to
    check they equal the stored ``records``, which then stand in for them)."""
    from poc_env.agents.benchmarks.plan_scale import _flown
    from poc_env.agents.planning.allocation import make_allocation_plan

    sc = load_scenario(name)
    old = stored(records)
    recs, done = resumed(out)
    for pol in policies:  # warm-up (JIT, caches), so a plan's CPU time is the plan's own
        if "@" in pol:
            make_allocation_plan(sc, options=_options(pol.split("@", 1)[1]))
    for seed in range(seed0, seed1):
        prior = episode_prior(sc, seed)
        bound = None
        for pol in policies if seed - seed0 < check else policies[:1]:
            if (seed, pol) in done:
                continue
            if bound is None:
                known = old.get((seed, "allocation_plan"))
                bound = known["rule_bound"] if known else rule_bound(sc, prior).upper
                if seed - seed0 < check and known:  # the stored bound is this prior's
                    assert abs(rule_bound(sc, prior).upper - bound) <= 1e-9 * bound, seed
            t0 = time.perf_counter()
            who, states = _policy(pol), []
            posc, p = _flown(sc, who, seed, prior, states)
            recs.append(
                {"map": name, "seed": seed, "variant": pol, "posc": float(posc),
                 "planned_posc": float(p.get("posc", float("nan"))), "rule_bound": bound,
                 "start": p.get("start"), "plan_s": float(p.get("runtime_s", float("nan"))),
                 "cpu_s": float(getattr(who, "cpu_s", float("nan"))),
                 "violations": int(states[0].violations[0].sum()),
                 "episode_s": time.perf_counter() - t0, "load": os.getloadavg()[0]}
            )  # fmt: skip
            ref = old.get((seed, pol))
            same = "" if ref is None else f" stored {ref['posc'] / bound:.4f}"
            print(name, seed, pol, round(posc / bound, 4), round(recs[-1]["plan_s"], 1),
                  round(os.getloadavg()[0], 1), same, flush=True)  # fmt: skip
            with open(out + ".tmp", "w") as f:
                json.dump(recs, f, indent=1)
            os.replace(out + ".tmp", out)
    paired(out, records)


def paired(out: str, records: list[str]) -> None:
    """Flown ``fly`` records paired per seed with every stored policy flown on all of their
    seeds (``allocation_plan``, ``greedy_rectangles``; ``allocation_plan_thorough`` from
    results/plan_scale/effort's records), checked equal where flown here too."""
    from poc_env.stats import ci95

    with open(out) as f:
        recs = json.load(f)
    old = stored(records)
    for r in recs:  # the default flown here equals the stored flight, seed for seed
        ref = old.get((r["seed"], r["variant"]))
        if ref is not None:
            same = abs(ref["posc"] - r["posc"]) <= 1e-12
            print(f"check seed {r['seed']} {r['variant']}: flown {r['posc']:.6f} stored "
                  f"{ref['posc']:.6f} {'equal' if same else 'DIFFERENT'}")  # fmt: skip
    mine = [r for r in recs if r["variant"] not in old_policies(old)]
    for pol in sorted({r["variant"] for r in mine}):
        rs = sorted((r for r in mine if r["variant"] == pol), key=lambda r: r["seed"])
        a = np.array([r["posc"] / r["rule_bound"] for r in rs])
        for base in sorted(old_policies(old)):
            if any((r["seed"], base) not in old for r in rs):
                continue
            b = np.array([old[r["seed"], base]["posc"] / r["rule_bound"] for r in rs])
            d = a - b
            half = ci95(d) if len(d) > 1 else float("nan")
            print(f"{pol} - {base} (flown/rule, n {len(d)}): {d.mean():+.4f} +- {half:.4f} "
                  f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}; min "
                  f"{d.min():+.4f}; {pol} {a.mean():.4f} +- {ci95(a) if len(a) > 1 else 0:.4f}, "
                  f"{base} {b.mean():.4f}; priors >= 0.90: {(a >= 0.9).sum()} vs "
                  f"{(b >= 0.9).sum()}")  # fmt: skip
        t = [r["plan_s"] for r in rs]
        lo, hi = min(r["load"] for r in rs), max(r["load"] for r in rs)
        print(f"{pol} planning time median {statistics.median(t):.1f} s (max {max(t):.1f}); "
              f"load {lo:.1f}-{hi:.1f}")  # fmt: skip
    among(recs)


def among(recs: list[dict], line: float = 3.70) -> None:
    """The variants flown here paired with each other (i24-sampled): flown POSC over the
    rule-aware bound against the second variant flown (the first is the CPU reference, e.g.
    ``allocation_plan@default``), Student's t 95 % and wins / ties / losses; the eq. 21 / 24
    violation steps per flight; the planning CPU over the first variant's on the same prior
    (median, max, and the priors over ``line``: 2 s at the default's quiet 0.54 s, the rule
    of docs/PLANNER.md "Speed and a new standard")."""
    from poc_env.stats import ci95

    order = list(dict.fromkeys(r["variant"] for r in recs))
    if len(order) < 2:
        return
    by = {(r["seed"], r["variant"]): r for r in recs}
    seeds = sorted({r["seed"] for r in recs if all((r["seed"], v) in by for v in order)})
    ref, base = order[0], order[1]
    for v in order:
        rs = [by[s, v] for s in seeds]
        a = np.array([r["posc"] / r["rule_bound"] for r in rs])
        viol = [r.get("violations", float("nan")) for r in rs]
        ratio = [by[s, v]["cpu_s"] / by[s, ref]["cpu_s"] for s in seeds]
        over = [s for s, x in zip(seeds, ratio, strict=True) if x > line]
        head = (
            f"{v} (n {len(rs)}): flown/rule {a.mean():.4f} +- {ci95(a):.4f}, >= 0.90 "
            f"{(a >= 0.9).sum()}; violation steps mean {statistics.mean(viol):.2f} "
            f"(total {sum(viol)}); CPU median {statistics.median(r['cpu_s'] for r in rs):.2f} s"
        )
        if v != ref:
            head += (
                f", CPU / {ref} median {statistics.median(ratio):.2f} (max "
                f"{max(ratio):.2f}), priors over {line}: {over or 'none'}"
            )
        print(head)
        if v not in (ref, base):
            b = np.array([by[s, base]["posc"] / by[s, base]["rule_bound"] for s in seeds])
            d = a - b
            dv = np.array(viol, float) - [by[s, base].get("violations", np.nan) for s in seeds]
            print(f"  {v} - {base}: {d.mean():+.4f} +- {ci95(d):.4f} "
                  f"{(d > 1e-9).sum()}/{(abs(d) <= 1e-9).sum()}/{(d < -1e-9).sum()}; min "
                  f"{d.min():+.4f}; violation steps {dv.mean():+.2f} +- {ci95(dv):.2f} "
                  f"(more on {(dv > 0).sum()}, fewer on {(dv < 0).sum()})")  # fmt: skip
    lo, hi = min(r["load"] for r in recs), max(r["load"] for r in recs)
    print(f"load {lo:.1f}-{hi:.1f}")


def old_policies(old: dict) -> set[str]:
    return {k[1] for k in old}


if __name__ == "__main__":
    if sys.argv[1] == "digest":
        eff = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--effort" else None
        digest(sys.argv[2], eff)
        sys.exit()
    if sys.argv[1] == "violations":
        violations(sys.argv[2], [int(x) for x in sys.argv[3].split(",")], sys.argv[4:])
        sys.exit()
    if sys.argv[1] == "paired":
        paired(sys.argv[2], sys.argv[3:])
        sys.exit()
    cmd, name, s0, s1, vs, out = sys.argv[1:7]
    if cmd == "plan":
        plan(name, int(s0), int(s1), vs.split(","), out)
    elif cmd == "chain":
        chain(name, int(s0), int(s1), vs.split(","), out)
    elif cmd == "polish":
        polish(name, int(s0), int(s1), vs.split(","), out)
    else:  # fly ... CHECK RECORDS.json...
        fly(name, int(s0), int(s1), vs.split(","), out, int(sys.argv[7]), sys.argv[8:])
