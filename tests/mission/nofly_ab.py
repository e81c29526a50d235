"""Issue 24's no-fly figures (docs/missions.md, results/nofly/): a script, not a test.

``cases OUT.jsonl [--first I] [--last J] [--exports]``
    The slow property test's cases ``I..J-1`` (its 200 seeds, ``default_rng(2024)``), each
    checked by :func:`test_mission_property.check_case` as the test does (without the four
    exports unless ``--exports``: they take most of a case's time and do not touch the
    routes), one JSON line per case. Each plan is flown twice: by the follower as it is (the
    counted flight) and by the follower before issue 24's rules
    (``closest_approach=False, guard_zones=False``) on the same plan; each plan's least
    distance from its routes (take-off, waypoints, landing) to a zone, over ``c``, and how many
    of its routes enter a zone are recorded too.
``flown MAP N OUT.jsonl``
    Flown ``allocation_plan`` over the rule-aware bound on ``MAP``'s random priors (episode
    seeds ``0..N-1``, the priors of ``poc-env bench plan --scale``): each seed planned once and
    flown by both followers, interleaved.
``summary FILES...``
    Totals of ``cases`` files.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 python
tests/mission/nofly_ab.py cases results/nofly/cases.jsonl``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import shapely

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]

import test_mission_property as T  # noqa: E402

from poc_env.agents.policies.base import PlanPolicy  # noqa: E402
from poc_env.agents.testing.flights import fly as fly_episode  # noqa: E402
from poc_env.sim.routing import clearance_m  # noqa: E402


class _Given(PlanPolicy):
    """Flies a given plan with the follower as it is (``fixed``) or before issue 24's rules."""

    def __init__(self, plan: dict, fixed: bool) -> None:
        self.given, self.fixed = plan, fixed

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return self.given

    def reset(self, env: Any, seed: int) -> None:
        super().reset(env, seed)
        self.follower.closest_approach = self.fixed
        self.follower.guard_zones = self.fixed


def cases(out: Path, first: int, last: int, exports: bool) -> None:
    if not exports:
        T.FORMATS = ()  # type: ignore[assignment]
    seeds = [int(v) for v in np.random.default_rng(2024).integers(0, 2**31, size=200)]
    extra: dict[str, list] = {}

    def fly(sc, policy, seed):
        new = fly_episode(sc, policy, seed)
        old = fly_episode(sc, _Given(policy.given, False), seed)
        zones = shapely.union_all([shapely.Polygon(z) for z in sc.map.no_fly_zones_m])
        dmin, enters = np.inf, 0
        for k, u in enumerate(policy.given["uavs"]):
            if u["waypoints_m"]:
                line = shapely.LineString([sc.takeoff_m[k], *u["waypoints_m"], sc.landing_m[k]])
                dmin = min(dmin, line.distance(zones))
                enters += int(line.intersects(zones))
        extra.setdefault("old_nofly", []).append(old.nofly_steps)
        extra.setdefault("route_min_over_c", []).append(dmin / clearance_m(sc))
        extra.setdefault("routes_entering", []).append(enters)
        return new

    tmp = Path(tempfile.mkdtemp(prefix="nofly_"))
    for i in range(first, last):
        s = seeds[i]
        extra.clear()
        folder = tmp / f"case{s}"
        folder.mkdir()
        t0 = time.perf_counter()
        try:
            c = T.check_case(fly, s, folder)
            rec: dict[str, Any] = {"i": i, "seed": s, "counts": dict(c), **extra}
        except Exception as err:
            rec = {"i": i, "seed": s, "raised": f"{type(err).__name__}: {err}"}
        rec["s"] = round(time.perf_counter() - t0, 1)
        rec["load"] = round(os.getloadavg()[0], 1)
        with out.open("a") as f:
            f.write(json.dumps(rec) + "\n")


def flown(name: str, n: int, out: Path) -> None:
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.policies.registry import make_policy
    from poc_env.config import load_scenario
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory.bound import rule_bound

    sc = load_scenario(name)

    def run(pol, seed, prior) -> tuple[float, int]:
        f = fly_episode(sc, pol, seed, prior)
        return f.posc, f.nofly_steps

    for seed in range(n):
        prior = episode_prior(sc, seed)
        bound = rule_bound(sc, prior).upper
        pol = make_policy("allocation_plan")
        env = UAVSearchParallelEnv(scenario=sc)
        env.reset(seed=seed, options={"prior": prior})
        pol.reset(env, seed)
        rec: dict[str, Any] = {"map": name, "seed": seed, "bound": bound,
                               "planned": float(pol.plan["posc"]) / bound,
                               "load": os.getloadavg()[0]}  # fmt: skip
        for tag, fixed in (("new", True), ("old", False)):
            posc, nf = run(_Given(pol.plan, fixed), seed, prior)
            rec[tag], rec[tag + "_nofly"] = posc / bound, nf
        with out.open("a") as f:
            f.write(json.dumps(rec) + "\n")


def summary(files: list[str]) -> dict[str, Any]:
    tot: Counter = Counter()
    bad, old_bad, raised, least = [], [], [], []
    for fn in files:
        for line in Path(fn).read_text().splitlines():
            r = json.loads(line)
            if "raised" in r:
                raised.append((r["seed"], r["raised"][:200]))
                continue
            c = r["counts"]
            tot["cases"] += 1
            for k in ("plans", "flown", *T.BAD):
                tot[k] += c.get(k, 0)
            tot["old_nofly_steps"] += sum(r["old_nofly"])
            tot["old_nofly_flights"] += sum(1 for x in r["old_nofly"] if x)
            tot["routes_entering"] += sum(r["routes_entering"])
            least += r["route_min_over_c"]
            if any(c.get(k) for k in T.BAD):
                bad.append((r["seed"], {k: v for k, v in c.items() if ":" in k}))
            if sum(r["old_nofly"]):
                old_bad.append((r["seed"], r["old_nofly"]))
    return {"totals": dict(tot), "failing": bad, "old_follower_failing": old_bad,
            "raised": raised, "least_route_distance_over_c": min(least, default=None),
            "plans_below_c": sum(1 for x in least if x < 1.0)}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    a = sub.add_parser("cases")
    a.add_argument("out", type=Path)
    a.add_argument("--first", type=int, default=0)
    a.add_argument("--last", type=int, default=200)
    a.add_argument("--exports", action="store_true")
    b = sub.add_parser("flown")
    b.add_argument("map")
    b.add_argument("n", type=int)
    b.add_argument("out", type=Path)
    s = sub.add_parser("summary")
    s.add_argument("files", nargs="+")
    args = ap.parse_args()
    if args.what == "cases":
        cases(args.out, args.first, args.last, args.exports)
    elif args.what == "flown":
        flown(args.map, args.n, args.out)
    else:
        print(json.dumps(summary(args.files), indent=1))


if __name__ == "__main__":
    main()
