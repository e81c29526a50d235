"""The polish and the zone credit on maps with no-fly zones (i24-zonepolish): a script, not a
test.

``run OUT.jsonl --seeds A-B --variants V,...``
    For each case seed in ``A..B-1`` the random scenario with no-fly zones of the mission
    property test (:func:`test_mission_property._layout` and ``_mapping_case``: a 30-50 km area,
    1-3 zones, several concave or beside an airfield, 1-3 UAVs from 1-2 fields, 5 km cells,
    its one-blob prior) is planned by the allocation planner with each variant's options
    (:data:`VARIANTS`), variants interleaved per seed (``--family near``: the prior's blob
    centred near a zone's edge; ``--family paper``: ``paper_6_2`` with 2 random zones and its
    random priors; ``--family free``: the ``prop`` cases without their zones,
    :func:`scenario`), and each plan flown once in the
    environment by the plan policies' follower (:func:`poc_env.agents.testing.flights.fly`,
    episode seed = case seed): one JSON line per plan with the planned ``posc``, the flown POSC,
    the no-fly, out-of-bounds and eq. 21 collision steps, the planning time and the 1-minute
    load average.
``summary FILES... --base V --new W``
    Paired differences ``W - V`` (flown and planned POSC) over the seeds both hold: mean,
    Student's t 95 % interval, wins/ties/losses (ties within 1e-9), the planning time ratio
    (median of per-seed ratios, loaded machine), and the totals of no-fly and collision steps.

Run from the repository root, one thread: ``OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python
tests/planning/zone_ab.py run results/plan_scale/zonepolish/val.jsonl --seeds 5000-5030
--variants default,standard``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent / "mission"), str(HERE.parent)]

from poc_env.agents.planning.allocation import make_allocation_plan  # noqa: E402
from poc_env.agents.planning.options import PlanOptions  # noqa: E402
from poc_env.agents.policies.base import PlanPolicy  # noqa: E402
from poc_env.agents.testing.flights import fly  # noqa: E402
from poc_env.config import load_scenario  # noqa: E402
from poc_env.theory.probability_map import build_prior  # noqa: E402


def _opts(effort: str, **kw: Any) -> PlanOptions:
    return dataclasses.replace(PlanOptions.preset(effort), **kw)


#: the variants: name -> options.
VARIANTS: dict[str, Any] = {
    "default": lambda: PlanOptions(),
    "standard": lambda: _opts("standard"),  # the polish with zones (i24-zonepolish)
    "standard_skip": lambda: _opts("standard", polish_zones=False),  # as before: skipped
    **{
        f"reach{r:g}": (lambda r=r: _opts("default", zone_reach=r))
        for r in (0.25, 0.75, 1.0, 1.5, 2.0, 4.0)
    },
    "soft": lambda: PlanOptions(),  # the zone credit by one line's POD (_soft_share)
    "standard_soft": lambda: _opts("standard"),
    **{
        f"standard_reach{r:g}": (lambda r=r: _opts("standard", zone_reach=r))
        for r in (0.75, 1.0, 1.5, 2.0)
    },
}


def _soft_share(self, grid, *, reach_m, zones_only=False, samples_per_cell=None):
    """The ``soft`` variant's zone credit (an experiment, patched into the router for the
    run; not in the planner): each point inside the keep-out area credited by the
    inverse-cube POD of one line flown along its outside at its depth ``d``,
    ``1 - exp(-W^2 / (4 pi d^2))`` (1 within W/4), as a sum of the router's binary
    shares at depths W/4 .. 4 W (``ZoneRouter.reach_share``, the one implementation)."""
    w = 2.0 * reach_m  # the planner asks for W/2
    r = w * np.array([0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0])
    p = 1.0 - np.exp(-(w**2) / (4 * np.pi * r**2))
    p[0] = 1.0
    wts = p - np.append(p[1:], 0.0)
    return sum(wt * _PLAIN_SHARE(self, grid, reach_m=float(rr)) for wt, rr in zip(wts, r))


_PLAIN_SHARE: Any = None


class _Fly(PlanPolicy):
    """Flies a given plan with the plan policies' follower."""

    def __init__(self, plan: dict) -> None:
        self.given = plan

    def make(self, env: Any, prior: np.ndarray, seed: int) -> dict:
        return self.given


def scenario(seed: int, family: str = "prop"):
    """The property test's mapping case of ``seed`` (zones, fields, fleet, one-blob prior).
    ``family`` ``"near"``: the prior's blob centred near a zone's edge instead (a point of the
    first zone's boundary, uniform along it, moved by up to 2 sweep widths (5 km) in a
    uniform direction, kept in the area): the mass the zone credit is about."""
    import shapely
    import test_mission_property as T

    rng = np.random.default_rng(seed)
    lay = T._layout(rng)
    if family == "near":
        edge = shapely.Polygon(lay["zones"][0]).exterior
        p = edge.interpolate(float(rng.uniform(0, edge.length)))
        r, a = float(rng.uniform(0, 5)), float(rng.uniform(0, 2 * np.pi))
        lay["mean"] = [float(np.clip(p.x + r * np.cos(a), 0, lay["w"])),
                       float(np.clip(p.y + r * np.sin(a), 0, lay["h"]))]  # fmt: skip
    elif family == "paper":
        return _paper(seed)
    elif family not in ("prop", "free"):
        raise ValueError(family)
    case = T._mapping_case(rng, lay)
    if family == "free":  # the same case without its zones (is a change the zones' doing?)
        case["map"]["no_fly_zones_km"], case["map"]["no_fly_names"] = [], []
    sc = load_scenario(case)
    return sc, build_prior(sc.map)


def _paper(seed: int):
    """``paper_6_2`` (6 UAVs, 40 x 30 cells) with 2 random zones inside its search area
    (:func:`~poc_env.agents.benchmarks.plan_scale.random_zones`, ``default_rng(seed)``) and
    its random prior of episode seed ``seed`` (:func:`~poc_env.agents.experiments.evaluate.
    episode_prior`)."""
    from poc_env.agents.benchmarks.plan_scale import random_zones
    from poc_env.agents.experiments.evaluate import episode_prior

    sc0 = load_scenario("paper_6_2")
    g = sc0.map
    zones = random_zones(g.width_m / 1e3, g.height_m / 1e3, 2, np.random.default_rng(seed))
    sc = load_scenario("paper_6_2", {"map.no_fly_zones_km": zones})
    return sc, episode_prior(sc, seed)


def run(out: Path, seeds: range, variants: list[str], family: str = "prop") -> None:
    for s in seeds:
        sc, prior = scenario(s, family)
        for v in variants:
            global _PLAIN_SHARE
            from poc_env.sim.routing import ZoneRouter

            if _PLAIN_SHARE is None:
                _PLAIN_SHARE = ZoneRouter.reach_share
            ZoneRouter.reach_share = _soft_share if v.startswith("soft") else _PLAIN_SHARE
            t0 = time.process_time()
            plan = make_allocation_plan(sc, prior=prior, seed=s, options=VARIANTS[v]())
            cpu = time.process_time() - t0
            f = fly(sc, _Fly(plan), s, prior)
            pol = plan["optimizer"]["settings"].get("polish", {})
            rec = {
                "seed": s, "family": family, "variant": v, "planned": plan["posc"], "flown": f.posc,
                "nofly": f.nofly_steps, "oob": f.oob_steps, "collision": f.collision_steps,
                "landed": f.landed, "uavs": len(plan["uavs"]),
                "zones": len(sc.map.no_fly_zones_m), "plan_cpu_s": round(cpu, 3),
                "moves": pol.get("moves"), "skipped": pol.get("skipped"),
                "load": round(os.getloadavg()[0], 2),
            }  # fmt: skip
            with out.open("a") as fh:
                fh.write(json.dumps(rec) + "\n")
            print(json.dumps(rec), flush=True)


def _ci(d: np.ndarray) -> tuple[float, float, float]:
    from poc_env.stats import ci95

    m, h = float(d.mean()), float(ci95(d))
    return m, m - h, m + h


def summary(files: list[Path], base: str, new: str) -> None:
    recs: dict[tuple[int, str], dict] = {}
    for f in files:
        for line in f.read_text().splitlines():
            r = json.loads(line)
            recs[(r["seed"], r["variant"])] = r
    seeds = sorted(s for s, v in recs if v == base and (s, new) in recs)
    a = [recs[(s, base)] for s in seeds]
    b = [recs[(s, new)] for s in seeds]
    print(f"{new} - {base}: {len(seeds)} seeds ({seeds[0]}..{seeds[-1]})")
    for key in ("flown", "planned"):
        d = np.array([y[key] - x[key] for x, y in zip(a, b)])
        m, lo, hi = _ci(d)
        w, t = int((d > 1e-9).sum()), int((abs(d) <= 1e-9).sum())
        mean_a = float(np.mean([x[key] for x in a]))
        mean_b = float(np.mean([y[key] for y in b]))
        print(f"  {key}: {base} {mean_a:.4f} -> {new} {mean_b:.4f}; diff {m:+.4f} "
              f"[{lo:+.4f}, {hi:+.4f}]; wins/ties/losses {w}/{t}/{len(d) - w - t}")  # fmt: skip
    ratio = [y["plan_cpu_s"] / max(x["plan_cpu_s"], 1e-9) for x, y in zip(a, b)]
    print(f"  plan CPU: {base} median {np.median([x['plan_cpu_s'] for x in a]):.2f} s, "
          f"{new} {np.median([y['plan_cpu_s'] for y in b]):.2f} s; ratio median "
          f"{np.median(ratio):.2f} (loads {min(x['load'] for x in a + b):.1f}-"
          f"{max(x['load'] for x in a + b):.1f})")  # fmt: skip
    for v, rs in ((base, a), (new, b)):
        print(f"  {v}: nofly {sum(r['nofly'] for r in rs)}, oob {sum(r['oob'] for r in rs)}, "
              f"collision {sum(r['collision'] for r in rs)} steps")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--seeds", required=True)
    r.add_argument("--variants", required=True)
    r.add_argument("--family", default="prop", choices=("prop", "near", "paper", "free"))
    s = sub.add_parser("summary")
    s.add_argument("files", type=Path, nargs="+")
    s.add_argument("--base", required=True)
    s.add_argument("--new", required=True)
    a = ap.parse_args()
    if a.cmd == "run":
        lo, hi = (int(v) for v in a.seeds.split("-"))
        a.out.parent.mkdir(parents=True, exist_ok=True)
        run(a.out, range(lo, hi), a.variants.split(","), a.family)
    else:
        summary(a.files, a.base, a.new)


if __name__ == "__main__":
    main()
