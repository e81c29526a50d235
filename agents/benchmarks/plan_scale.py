"""Issue 24's "any size" figures: ``poc-env bench plan --scale`` (called by
:mod:`poc_env.agents.benchmarks.plan`).

* **Quality**, per map (``--scale-maps``, default ``paper_6_2`` and ``large_400``: 400 x 400 km,
  12 UAVs from 3 airfields): ``allocation_plan`` and ``greedy_rectangles`` flown in the
  environment on the same random priors (episode seeds ``--seed0 ..``, the priors of
  :func:`poc_env.agents.experiments.evaluate.episode_prior`), the two policies interleaved per
  seed; each episode's POSC over its prior's rule-aware bound
  (:func:`poc_env.theory.bound.rule_bound`). Figures: the mean share of each policy
  (target: allocation >= 0.90), the allocation's paired lead and its wins over the seeds.
* **Cell size**: the allocation plan of the scenario's own prior on ``paper_6_2`` with 2.5, 5
  and 10 km cells, planned POS_C and flown POSC (target: planned within 3 % of flown).
* **Planning time**: :func:`poc_env.agents.planning.allocation.make_allocation_plan`, median
  of ``--runs`` after a warm-up, on ``paper_6_2`` (target <= 2 s) and on ``large_400`` with
  2.5 km cells (160 x 160) and 24 UAVs (target <= 10 s), one core.
* **Planning time with no-fly zones** (``--scale-parts zones``, ``--zones N``): the same two
  cases planned with and without ``N`` random zones inside the search area
  (:func:`random_zones`), the two interleaved per run; medians, their ratio, and the planned
  POS_C of both. Not part of the default parts.
* **Spill charge** (``--scale-parts spill``, with ``quality`` for the flown ratios): the
  spill-charged bound beside the rule-aware one on the same priors (i24-spill). Not part of
  the default parts.

Figures are quoted in docs/PLANNER.md with the command; the machine's load changes the times.
"""

from __future__ import annotations

import json
import os
import statistics
import time
from typing import Any

import numpy as np

from poc_env.stats import ci95

#: the maps of the quality figures.
MAPS = ("paper_6_2", "large_400")
#: the cell sizes (km) of the planned-vs-flown figures.
CELLS_KM = (2.5, 5.0, 10.0)


def _line(name: str, value: float, note: str = "") -> None:
    print(f"{name:34s} {value:12.4g}  {note}".rstrip(), flush=True)


def _flown(sc, policy, seed: int, prior: np.ndarray | None,
           states: list | None = None) -> tuple[float, dict]:  # fmt: skip
    """POSC of ``policy`` (a registered name, or a policy object with ``reset`` and
    ``predict``) flown on ``sc`` with ``prior`` (None: the scenario's), and its plan; the
    flight's final ``sim_state`` is appended to ``states`` when given."""
    from poc_env.agents.experiments.evaluate import play
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario=sc)
    pol = make_policy(policy) if isinstance(policy, str) else policy
    play(env, pol, seed, prior)
    if states is not None:
        states.append(env.sim_state)
    return float(env.sim_state.posc[0]), getattr(pol, "plan", {})


def quality(maps, episodes: int, seed0: int, records: list | None = None) -> dict[str, float]:
    """Flown ``allocation_plan`` and ``greedy_rectangles`` over the rule-aware bound; each
    episode's figures are appended to ``records`` when given."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.config import load_scenario
    from poc_env.theory.bound import rule_bound

    out: dict[str, float] = {}
    for name in maps:
        sc = load_scenario(name)
        share: dict[str, list[float]] = {"allocation_plan": [], "greedy_rectangles": []}
        planned: list[float] = []
        for seed in range(seed0, seed0 + episodes):
            prior = episode_prior(sc, seed)
            bound = rule_bound(sc, prior).upper
            for pol in share:  # interleaved per seed
                posc, plan = _flown(sc, pol, seed, prior)
                share[pol].append(posc / bound)
                if pol == "allocation_plan":
                    planned.append(float(plan["posc"]) / bound)
                if records is not None:
                    print(
                        f"  {name} seed {seed} {pol}: {posc / bound:.4f} of the rule bound "
                        f"({plan.get('start', '')})",
                        flush=True,
                    )
                    records.append(
                        {
                            "map": name,
                            "seed": seed,
                            "policy": pol,
                            "posc": posc,
                            "rule_bound": bound,
                            "planned_posc": float(plan.get("posc", float("nan"))),
                            "start": plan.get("start"),
                            "plan_s": float(plan.get("runtime_s", float("nan"))),
                            "load": os.getloadavg()[0],
                        }
                    )
        a = np.array(share["allocation_plan"])
        g = np.array(share["greedy_rectangles"])
        n = len(a)
        for pol, x in share.items():
            out[f"{name}_{pol}_rule"] = float(np.mean(x))
            note = f"flown POSC / rule bound, {n} priors"
            _line(f"{name} {pol}", out[f"{name}_{pol}_rule"], note)
        out[f"{name}_allocation_planned_rule"] = float(np.mean(planned))
        _line(f"{name} allocation planned", float(np.mean(planned)), "planned POS_C / rule bound")
        d = a - g
        half = ci95(d)
        out[f"{name}_lead"] = float(d.mean())
        out[f"{name}_wins"] = float(np.sum(d > 0))
        _line(f"{name} lead", float(d.mean()), f"allocation - greedy, +- {half:.4f} (95 %)")
        _line(f"{name} wins", float(np.sum(d > 0)), f"of {n} priors (allocation ahead)")
    return out


def single(maps, episodes: int, seed0: int) -> dict[str, float]:
    """Where the routes lose: each airfield's first UAV alone (the rest of the fleet removed),
    its planned POS over its own rule-aware bound, on the same random priors. A plan of one
    UAV has no other UAV to share the mass with, so what it misses of its bound is the route's
    (or the bound's) alone."""
    import dataclasses

    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.config import load_scenario
    from poc_env.theory.bound import rule_bound

    out: dict[str, float] = {}
    for name in maps:
        sc = load_scenario(name)
        shares = []
        for g in sc.fleet:
            one = dataclasses.replace(sc, fleet=(dataclasses.replace(g, count=1),))
            for seed in range(seed0, seed0 + episodes):
                prior = episode_prior(sc, seed)
                shares.append(
                    make_allocation_plan(one, prior=prior)["posc"] / rule_bound(one, prior).upper
                )
        out[f"{name}_single_rule"] = float(np.mean(shares))
        _line(
            f"{name} one UAV alone",
            out[f"{name}_single_rule"],
            f"planned / its rule bound, mean of {len(shares)} (min {min(shares):.3f}, "
            f"max {max(shares):.3f})",
        )
    return out


def spill(maps, episodes: int, seed0: int, records: list | None = None) -> dict[str, float]:
    """The spill-charged bound (:func:`poc_env.theory.spill_bound.spill_bound`) beside the
    rule-aware bound on the same random priors: the mean share of the rule-aware bound the
    charge removes, and, for the episodes of ``quality`` in ``records`` (same invocation), each
    policy's flown POSC over the spill-charged bound (``spill_bound`` added to the records)."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.config import load_scenario
    from poc_env.theory.spill_bound import spill_bound

    out: dict[str, float] = {}
    for name in maps:
        sc = load_scenario(name)
        cut = []
        share: dict[str, list[float]] = {}
        for seed in range(seed0, seed0 + episodes):
            b = spill_bound(sc, episode_prior(sc, seed))
            cut.append(1.0 - b.upper / b.rule)
            for r in records or []:
                if r["map"] == name and r["seed"] == seed:
                    r["spill_bound"] = b.upper
                    share.setdefault(r["policy"], []).append(r["posc"] / b.upper)
        out[f"{name}_spill_removed"] = float(np.mean(cut))
        note = f"share of the rule bound removed, {len(cut)} priors (max {max(cut):.4f})"
        _line(f"{name} spill charge", float(np.mean(cut)), note)
        for pol, x in share.items():
            out[f"{name}_{pol}_spill"] = float(np.mean(x))
            note = f"flown POSC / spill-charged bound, +- {ci95(np.array(x)):.4f} (95 %)"
            _line(f"{name} {pol}", float(np.mean(x)), note)
    return out


def tight(maps, episodes: int, seed0: int) -> dict[str, float]:
    """How loose the rule-aware bound is for one flight: the cases of :func:`single` (each
    airfield's first UAV alone), its planned POS over its rule-aware bound and over the
    tour-charged bound (:func:`poc_env.theory.tour_bound.tour_bound`, the travel between the
    searched blocks charged); and, in the planners' own coverage model (W x length per cell,
    no spill), the plan's POS over the same two bounds with ``rho = 0``."""
    import dataclasses

    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.agents.planning.flight_rules import path_coverage
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid
    from poc_env.theory.search_theory import pod_from_coverage
    from poc_env.theory.tour_bound import tour_bound

    out: dict[str, float] = {}
    for name in maps:
        sc = load_scenario(name)
        grid = Grid.from_config(sc.map)
        rows: dict[str, list[float]] = {"rule": [], "tour": [], "rule0": [], "tour0": []}
        for g in sc.fleet:
            one = dataclasses.replace(sc, fleet=(dataclasses.replace(g, count=1),))
            for seed in range(seed0, seed0 + episodes):
                prior = episode_prior(sc, seed)
                plan = make_allocation_plan(one, prior=prior)
                u = plan["uavs"][0]
                path = [one.takeoff_m[0], *u["waypoints_m"], one.landing_m[0]]
                cov = path_coverage(path, grid, one.sensor.sweep_width_m)
                model = float(np.sum(prior * pod_from_coverage(cov, one.sensor.law)))
                env_b = tour_bound(one, prior)
                plan_b = tour_bound(one, prior, spill_m=0.0)
                rows["rule"].append(plan["posc"] / env_b.rule)
                rows["tour"].append(plan["posc"] / env_b.upper)
                rows["rule0"].append(model / plan_b.rule)
                rows["tour0"].append(model / plan_b.upper)
                print(
                    f"  {name} field {g.takeoff} seed {seed}: planned {plan['posc']:.4f}, "
                    f"rule {env_b.rule:.4f}, tour {env_b.upper:.4f}; model {model:.4f}, "
                    f"rule(rho 0) {plan_b.rule:.4f}, tour(rho 0) {plan_b.upper:.4f}",
                    flush=True,
                )
        notes = {
            "rule": "planned / rule-aware bound",
            "tour": "planned / tour-charged bound",
            "rule0": "model POS / rule-aware bound, rho 0",
            "tour0": "model POS / tour-charged bound, rho 0",
        }
        for key, x in rows.items():
            out[f"{name}_alone_{key}"] = float(np.mean(x))
            _line(
                f"{name} alone {key}",
                out[f"{name}_alone_{key}"],
                f"{notes[key]}, mean of {len(x)} (min {min(x):.3f}, max {max(x):.3f})",
            )
    return out


def cells(name: str = "paper_6_2") -> dict[str, float]:
    """Planned and flown POS of the allocation plan at each cell size of :data:`CELLS_KM`."""
    from poc_env.config import load_scenario

    out: dict[str, float] = {}
    for km in CELLS_KM:
        sc = load_scenario(name, {"map.cell_km": km})
        posc, plan = _flown(sc, "allocation_plan", 0, None)
        out[f"cells_{km:g}km_planned"] = float(plan["posc"])
        out[f"cells_{km:g}km_flown"] = posc
        _line(
            f"{name} {km:g} km cells",
            float(plan["posc"]) / posc - 1.0 if posc > 0 else float("nan"),
            f"planned {plan['posc']:.4f} / flown {posc:.4f} - 1 (target within 3 %)",
        )
    return out


def timing(runs: int) -> dict[str, float]:
    """Allocation planning time on ``paper_6_2`` and on 160 x 160 cells with 24 UAVs, with the
    scenario's prior and with one of 300 small blobs (many separate regions of coverage: the
    allocation start's lines per region took 30 of 48 s on such a prior before 2026-11-28)."""
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid, random_gaussian_mixture

    big = load_scenario("large_400", {"map.cell_km": 2.5})
    blobs = random_gaussian_mixture(
        Grid.from_config(big.map), np.random.default_rng(0), (300, 300), (0.003, 0.008), (0, 0)
    )
    cases = {
        "paper_6_2": (load_scenario("paper_6_2"), None, 2.0, None),
        "large_400_160x160_24uav": (big, 24, 10.0, None),
        "large_400_160x160_24uav_300blobs": (big, 24, 10.0, blobs),
    }
    out: dict[str, float] = {}
    for label, (sc, uavs, target, prior) in cases.items():
        make_allocation_plan(sc, prior=prior, uavs=uavs, refine=0)  # warm-up (JIT)
        times = []
        for _ in range(runs):
            t0 = time.perf_counter()
            make_allocation_plan(sc, prior=prior, uavs=uavs)
            times.append(time.perf_counter() - t0)
        out[f"{label}_plan_s"] = statistics.median(times)
        _line(f"{label} plan_s", out[f"{label}_plan_s"], f"median of {runs} (target <= {target} s)")
    return out


#: the shapes of :func:`random_zones` (those of the mission property test, tests/mission).
ZONE_SHAPES = ("rect", "tri", "L", "U")


def random_zones(
    w_km: float, h_km: float, n: int, rng: np.random.Generator, size: tuple = (0.06, 0.15)
) -> list[list[list[float]]]:
    """``n`` no-fly zones (km) inside the ``w_km x h_km`` search area: rectangles, triangles,
    L and U shapes (concave, as the mission property test draws them), each side a share
    ``size`` of the area's shorter side, anywhere inside the area; drawn from ``rng``."""
    side = min(w_km, h_km)
    zones = []
    for _ in range(n):
        kind = ZONE_SHAPES[int(rng.integers(len(ZONE_SHAPES)))]
        a, b = rng.uniform(size[0] * side, size[1] * side, 2)
        x, y = rng.uniform(0, w_km - a), rng.uniform(0, h_km - b)
        t = min(a, b) * rng.uniform(0.2, 0.33)  # the arms' thickness (L, U)
        if kind == "rect":
            z = [[x, y], [x + a, y], [x + a, y + b], [x, y + b]]
        elif kind == "tri":
            z = [[x, y], [x + a, y], [x + rng.uniform(0, a), y + b]]
        elif kind == "L":
            z = [[x, y], [x + a, y], [x + a, y + t], [x + t, y + t], [x + t, y + b], [x, y + b]]
        else:
            z = [[x, y], [x + a, y], [x + a, y + b], [x + a - t, y + b], [x + a - t, y + t],
                 [x + t, y + t], [x + t, y + b], [x, y + b]]  # fmt: skip
        zones.append([[float(px), float(py)] for px, py in z])
    return zones


#: the cases of :func:`timing_zones`: label -> (scenario, overrides, UAVs or None), those of
#: :func:`timing`.
ZONE_CASES: dict[str, tuple[str, dict, int | None]] = {
    "paper_6_2": ("paper_6_2", {}, None),
    "large_400_160x160_24uav": ("large_400", {"map.cell_km": 2.5}, 24),
}


def timing_zones(
    runs: int, n_zones: int, seed: int = 0, cases: dict | None = None
) -> dict[str, float]:
    """Allocation planning time of ``cases`` (default :data:`ZONE_CASES`) with and without
    ``n_zones`` random zones (:func:`random_zones`, ``default_rng(seed)``), interleaved per
    run: medians, the ratio with / without, and the planned POS_C of both (the zones' router
    builds a visibility graph, reroutes every leg and discounts the zones' interior mass)."""
    from poc_env.agents.planning.allocation import make_allocation_plan
    from poc_env.config import load_scenario

    rng = np.random.default_rng(seed)
    cases = ZONE_CASES if cases is None else cases
    out: dict[str, float] = {}
    for label, (name, over, uavs) in cases.items():
        plain = load_scenario(name, over)
        m = plain.map
        ox, oy = (v / 1000 for v in m.origin_m)
        drawn = random_zones(m.width_m / 1000, m.height_m / 1000, n_zones, rng)
        zones = [[[x + ox, y + oy] for x, y in z] for z in drawn]
        names = [f"Z-{i + 1}" for i in range(n_zones)]
        zoned = load_scenario(name, {**over, "map.no_fly_zones_km": zones,
                                     "map.no_fly_names": names})  # fmt: skip
        times: dict[str, list[float]] = {"plain": [], "zones": []}
        posc: dict[str, float] = {}
        for sc in (plain, zoned):
            make_allocation_plan(sc, uavs=uavs, refine=0)  # warm-up (JIT, caches)
        for _ in range(runs):
            for tag, sc in (("plain", plain), ("zones", zoned)):
                t0 = time.perf_counter()
                plan = make_allocation_plan(sc, uavs=uavs)
                times[tag].append(time.perf_counter() - t0)
                posc[tag] = float(plan["posc"])
        for tag in times:
            out[f"{label}_{tag}_plan_s"] = statistics.median(times[tag])
            out[f"{label}_{tag}_posc"] = posc[tag]
        ratio = out[f"{label}_zones_plan_s"] / out[f"{label}_plain_plan_s"]
        out[f"{label}_zones_ratio"] = ratio
        _line(f"{label} plan_s", out[f"{label}_plain_plan_s"],
              f"no zones, median of {runs}; planned POS_C {posc['plain']:.4f}")  # fmt: skip
        _line(f"{label} plan_s +{n_zones} zones", out[f"{label}_zones_plan_s"],
              f"median of {runs}, interleaved; planned POS_C {posc['zones']:.4f}")  # fmt: skip
        _line(f"{label} zones / none", ratio, "planning time ratio")
    return out


def main(
    maps,
    episodes: int,
    seed0: int,
    runs: int,
    parts=None,
    out_path: str | None = None,
    zones: int = 4,
) -> dict[str, Any]:
    """The ``parts`` (default: quality, cells, timing); ``out_path``: a JSON file of every
    episode's figures (map, seed, policy, POSC, rule-aware bound, planned POS_C, the start the
    allocation plan kept, planning time, load average), written atomically at the end."""
    parts = ("quality", "cells", "timing") if parts is None else tuple(parts)  # "single": asked
    what = (
        f"{episodes} random priors per map (seeds {seed0}..), allocation_plan and "
        "greedy_rectangles interleaved per seed; "
        if {"quality", "single"} & set(parts)
        else ""
    )
    print(
        f"# issue 24 scale figures ({' '.join(parts)}): {what}one core; load average "
        f"{os.getloadavg()[0]:.1f} at the start",
        flush=True,
    )
    out: dict[str, Any] = {}
    records: list[dict[str, Any]] = []
    if "quality" in parts:
        out.update(quality(maps, episodes, seed0, records))
    if "single" in parts:
        out.update(single(maps, episodes, seed0))
    if "tight" in parts:
        out.update(tight(maps, episodes, seed0))
    if "spill" in parts:
        out.update(spill(maps, episodes, seed0, records))
    if "cells" in parts:
        out.update(cells())
    if "timing" in parts:
        out.update(timing(runs))
    if "zones" in parts:
        out.update(timing_zones(runs, zones))
    _line("load average", os.getloadavg()[0], "at the end (1 min)")
    if out_path is not None:
        from poc_env.io import write_text_atomic

        write_text_atomic(out_path, json.dumps({"summary": out, "episodes": records}, indent=1))
    return out
