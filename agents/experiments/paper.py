"""The paper's §6 experiments, one command each: ``poc-env experiment NAME``.

Every experiment prints its table, writes ``NAME.csv``, ``NAME.txt`` and ``NAME.png`` into
``OUT/NAME/`` (default ``out/experiments``), and reports beside each POS the physical optimum
for the same effort (:func:`poc_env.theory.bound.physical_optimum`): for a plan, the optimum for the
plan's own total effort (``plan["upper_bound"]``); for policies flown in the environment, the
optimum for the swarm's largest possible effort. The paper's numbers, where it prints them,
are in the ``paper`` columns.

=========  ==================================================================================
name       what
=========  ==================================================================================
table4     §6.1.1 six-polygon survey (Table 4, Figs. 16-17), as given and spacing-optimised
table5     §6.1.2 two-circles-four-polygons survey (Table 5, Figs. 18-19), both variants
table6     §6.2 time-limited adaptive-DE plan (Table 6, Fig. 21)
table7     de_plan, greedy_bayes and potential_game flown in the env, N episodes (Table 7)
fig22      convergence of adaptive DE, classic DE, chaotic ABC, grouped PSO, scipy DE, CMA-ES
table8     POS for 4 to 8 UAVs, increments, POS / reach-aware bound of each fleet (Table 8)
fig23      POS against the sweep width W x 0.6 .. 1.4
fig24      POS against the task area's length and width x 0.5 .. 1.5
fig25      adaptive DE with G = 230, 270, 300 generations
fig26      adaptive DE with NP, 1.5 NP, 2 NP individuals
sorties    3 sorties in a row (poc-env replan), cumulative POS against the bound (issue 24)
all        everything above
=========  ==================================================================================

Budgets: the paper's (NP = 100, G = 300, 10 seeds per optimiser setting, 50 episodes per
policy) by default; ``--quick`` is a reduced budget (NP = 20, G = 30, 2 seeds, 2 episodes,
three points per curve) that runs in about a minute and is what the test suite runs.
Where an experiment runs several seeds per setting, the table shows the mean with a 95 %
interval and the best plan (what a planner would fly: the best of its restarts).
``--preset tuned`` gives every plan the measured DE constants instead of the paper's
(:data:`poc_env.agents.planning.optimizers.TUNED_DE`, same NP and G; docs/PLANNER.md section 4);
``paper`` (the default) is the paper's settings. ``table7``'s ``de_plan`` policy keeps its own.

Seeds: experiment ``NAME`` with ``--seed S`` uses optimiser seeds ``S .. S + seeds - 1``
and episode seeds ``1000 + S ..``; every job is independent of ``--workers`` and of the
order in which jobs run, so the outputs are reproducible from the seed.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import io
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import poc_env.limits as limits
from poc_env.config import Scenario, load_scenario
from poc_env.errors import ConfigError, as_int
from poc_env.io import atomic_dir, write_text_atomic

#: Table 4 / 5 of the paper: (track km, POD, POC, POS) per UAV, and POS_C.
PAPER_TABLE4 = (
    [
        (1143.7, 0.9784, 0.1611, 0.1576),
        (1182.5, 0.9878, 0.1600, 0.1580),
        (1220.6, 0.9988, 0.1233, 0.1231),
        (1347.7, 0.9152, 0.2146, 0.1964),
        (1210.2, 0.9987, 0.1288, 0.1286),
        (1265.8, 0.9784, 0.1805, 0.1766),
    ],
    0.9404,
)
PAPER_TABLE5 = (
    [
        (745.8, 0.9784, 0.1030, 0.1008),
        (1463.2, 0.9878, 0.1941, 0.1917),
        (2511.0, 1.0000, 0.1369, 0.1369),
        (1178.7, 0.9152, 0.1929, 0.1766),
        (2568.82, 0.9999, 0.1851, 0.1849),
        (1071.1, 0.9878, 0.1346, 0.1330),
    ],
    0.9238,
)
#: Table 6: centre (m), (l, w) (m), theta (deg), d (m) per UAV.
PAPER_TABLE6 = [
    ((73156.7, 70191.3), (54599.5, 47520.3), 213.2, 7222.5),
    ((29737.4, 46583.9), (84495.5, 40705.0), 147.7, 9661.2),
    ((134605.5, 100603.7), (67179.1, 41889.8), 70.3, 6601.6),
    ((153218.9, 58636.5), (55627.1, 68995.1), 221.3, 8199.8),
    ((37753.8, 111713.0), (61155.7, 43792.2), 19.5, 6039.9),
    ((106105.0, 29815.4), (53029.2, 48272.9), 252.7, 6473.1),
]
#: Table 7: the six rows the paper prints per method (this paper, [38], [39]). They are the
#: six UAVs' POS, not six runs: this paper's sum to 0.8740, Table 8's POS for six UAVs.
PAPER_TABLE7 = {
    "de_plan": (0.1469, 0.1434, 0.1139, 0.1884, 0.1171, 0.1643),
    "greedy_bayes": (0.1437, 0.1839, 0.1258, 0.1718, 0.1177, 0.1050),
    "potential_game": (0.1404, 0.1387, 0.1390, 0.1372, 0.1430, 0.1389),
}
#: Table 8: POS per number of UAVs.
PAPER_TABLE8 = {4: 0.6156, 5: 0.7673, 6: 0.8740, 7: 0.9172, 8: 0.9394}


@dataclass(frozen=True)
class Budget:
    """How much each experiment spends; :data:`FULL` is the paper's, :data:`QUICK` a smoke."""

    popsize: int | None  # None: the scenario's planner.population (100)
    maxiter: int | None  # None: the scenario's planner.generations (300)
    seeds: int
    episodes: int
    quick: bool
    #: DE settings preset of every plan
    # (:func:`poc_env.agents.planning.optimizers.preset_settings`).
    preset: str = "paper"

    def np_g(self, sc: Scenario) -> tuple[int, int]:
        return (self.popsize or sc.planner.population, self.maxiter or sc.planner.generations)


FULL = Budget(popsize=None, maxiter=None, seeds=10, episodes=50, quick=False)
QUICK = Budget(popsize=20, maxiter=30, seeds=2, episodes=2, quick=True)


@dataclass
class Result:
    """One experiment's output: rows (CSV), the printed table, files written."""

    name: str
    rows: list[dict[str, Any]]
    table: str
    files: list[Path] = field(default_factory=list)

    def csv(self) -> str:
        buf = io.StringIO()
        keys: list[str] = []
        for r in self.rows:
            keys += [k for k in r if k not in keys]
        w = csv.DictWriter(buf, fieldnames=keys)
        w.writeheader()
        w.writerows(self.rows)
        return buf.getvalue()


class Runner:
    """Runs independent jobs over ``workers`` processes (results in job order)."""

    def __init__(self, workers: int = 1, progress: bool = False) -> None:
        self.workers = as_int("workers", workers, 1, limits.MAX_WORKERS)
        self.progress = progress
        self._pool: ProcessPoolExecutor | None = None

    def map(self, fn: Callable[[Any], Any], jobs: Sequence[Any], desc: str) -> list[Any]:
        from poc_env.agents.experiments.pool import process_pool, run_jobs

        if self.workers > 1 and len(jobs) > 1 and self._pool is None:
            self._pool = process_pool(self.workers)
        try:
            return run_jobs(
                fn, jobs, self.workers, pool=self._pool, desc=desc if self.progress else None
            )
        except BaseException:
            self._pool = None  # run_jobs stopped it
            raise

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None


# -- jobs (module level: they run in worker processes) ----------------------------------------
def _plan_job(job: tuple[Scenario, dict[str, Any]]) -> dict[str, Any]:
    """Plan ``scenario`` with ``make_plan(**kwargs)``; the figures the experiments need."""
    from poc_env.agents.planning.planner import make_plan

    sc, kw = job
    plan = make_plan(sc, **kw)
    return {
        "posc": plan["posc"],
        "bound": plan["upper_bound"],
        "objective": plan["objective"],
        "history": plan["history"],
        "runtime_s": plan["runtime_s"],
        "plan": plan,
    }


def _mean_ci(x: Sequence[float]) -> tuple[float, float]:
    """Mean and Student's t 95 % half-width (:func:`poc_env.stats.ci95`)."""
    from poc_env.stats import ci95

    a = np.asarray(x, dtype=float)
    return float(a.mean()), ci95(a)


def _fmt_table(rows: list[dict[str, Any]], cols: Sequence[tuple[str, str, str]]) -> str:
    """Fixed-width text: ``cols`` = (key, header, format spec)."""
    cells = [[h for _, h, _ in cols]]
    for r in rows:
        line = []
        for key, _, spec in cols:
            v = r.get(key)
            line.append("-" if v is None or v == "" else format(v, spec))
        cells.append(line)
    widths = [max(len(c[i]) for c in cells) for i in range(len(cols))]
    out = [" ".join(c.rjust(w) for c, w in zip(cells[0], widths))]
    out.append("-" * len(out[0]))
    out += [" ".join(c.rjust(w) for c, w in zip(line, widths)) for line in cells[1:]]
    return "\n".join(out)


def _figure(size=(7.0, 4.5)):
    from poc_env.viz.plots import _figure as fig

    return fig(size)


def _save(fig, path: Path) -> Path:
    from poc_env.viz.plots import save_figure_atomic

    return save_figure_atomic(fig, path)


# -- §6.1: region surveys -------------------------------------------------------------------
def _survey(name: str, regions: str, paper, out: Path) -> Result:
    from poc_env.agents.planning.region_planner import optimise_regions
    from poc_env.agents.planning.survey import load_regions, run_survey
    from poc_env.theory.probability_map import build_prior
    from poc_env.viz.plots import plot_survey

    sc = load_scenario("paper_6_1")
    prior = build_prior(sc.map)
    given = load_regions(regions)
    rows: list[dict[str, Any]] = []
    files = []
    texts = []
    for variant, plan in (("as given", given), ("optimised", optimise_regions(sc, given))):
        res = run_survey(sc, plan, prior=prior)
        for k, r in enumerate(res.rows):
            p = paper[0][k]
            rows.append(
                {
                    "variant": variant,
                    "uav": r.id,
                    "pattern": r.pattern,
                    "spacing_km": r.spacing_km,
                    "direction_deg": r.direction_deg,
                    "track_km": r.track_length_km,
                    "paper_track_km": p[0],
                    "pod": r.pod,
                    "paper_pod": p[1],
                    "poc": r.poc,
                    "paper_poc": p[2],
                    "pos": r.pos,
                    "paper_pos": p[3],
                    "pos_flown": r.pos_flown,
                    "time_h": r.flight_time_h,
                    "feasible": r.feasible,
                    "posc": res.posc,
                    "paper_posc": paper[1],
                    "posc_flown": res.posc_flown,
                    "bound": res.bound,
                }
            )
        suffix = "" if variant == "as given" else "_optimised"
        files.append(plot_survey(res, sc, plan, prior, out / f"{name}{suffix}.png"))
        texts.append(
            f"{variant}: POS_C {res.posc:.4f} (paper {paper[1]:.4f}), flown {res.posc_flown:.4f}, "
            f"physical optimum for the same effort {res.bound:.4f}"
        )
    cols = [
        ("variant", "variant", ""),
        ("uav", "No.", "d"),
        ("pattern", "pattern", ""),
        ("track_km", "track/km", ".1f"),
        ("paper_track_km", "paper", ".1f"),
        ("pod", "POD", ".4f"),
        ("paper_pod", "paper", ".4f"),
        ("poc", "POC", ".4f"),
        ("paper_poc", "paper", ".4f"),
        ("pos", "POS", ".4f"),
        ("paper_pos", "paper", ".4f"),
        ("time_h", "time/h", ".2f"),
        ("feasible", "ok", ""),
    ]
    table = _fmt_table(rows, cols) + "\n" + "\n".join(texts)
    return Result(name, rows, table, files)


def exp_table4(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    return _survey("table4", "paper_6_1_polygons", PAPER_TABLE4, out)


def exp_table5(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    return _survey("table5", "paper_6_1_mixed", PAPER_TABLE5, out)


# -- §6.2: the time-limited plan --------------------------------------------------------------
def exp_table6(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import plan_table, plot_plan
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario("paper_6_2")
    popsize, maxiter = budget.np_g(sc)
    plan = _plan_job(
        (sc, {"seed": seed, "popsize": popsize, "maxiter": maxiter, "preset": budget.preset})
    )["plan"]
    rows = []
    for u, p in zip(plan["uavs"], PAPER_TABLE6):
        r = u["rectangle"]
        rows.append(
            {
                "uav": u["id"],
                "x_km": r["center_m"][0] / 1e3,
                "y_km": r["center_m"][1] / 1e3,
                "l_km": r["length_m"] / 1e3,
                "w_km": r["width_m"] / 1e3,
                "theta_deg": r["theta_deg"],
                "d_km": u["spacing_m"] / 1e3,
                "pos": u["pos"],
                "time_h": u["flight_time_s"] / 3600,
                "paper_x_km": p[0][0] / 1e3,
                "paper_y_km": p[0][1] / 1e3,
                "paper_l_km": p[1][0] / 1e3,
                "paper_w_km": p[1][1] / 1e3,
                "paper_theta_deg": p[2],
                "paper_d_km": p[3] / 1e3,
                "posc": plan["posc"],
                "bound": plan["upper_bound"],
            }
        )
    fig = plot_plan(plan, sc, build_prior(sc.map), out / "table6.png")
    write_plan(plan, out / "plan.json")
    cols = [
        ("uav", "No.", "d"),
        ("x_km", "x/km", ".1f"),
        ("paper_x_km", "paper", ".1f"),
        ("y_km", "y/km", ".1f"),
        ("paper_y_km", "paper", ".1f"),
        ("l_km", "l/km", ".1f"),
        ("paper_l_km", "paper", ".1f"),
        ("w_km", "w/km", ".1f"),
        ("paper_w_km", "paper", ".1f"),
        ("theta_deg", "theta", ".1f"),
        ("paper_theta_deg", "paper", ".1f"),
        ("d_km", "d/km", ".2f"),
        ("paper_d_km", "paper", ".2f"),
        ("pos", "POS", ".4f"),
    ]
    table = _fmt_table(rows, cols) + "\n" + plan_table(plan).splitlines()[-1]
    table += (
        "\nThe paper prints no POS for Table 6; Table 8 gives 0.8740 for these six UAVs "
        f"(ours {plan['posc']:.4f}, physical optimum for the same effort "
        f"{plan['upper_bound']:.4f})."
    )
    return Result("table6", rows, table, [fig, out / "plan.json"])


def exp_table7(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    from poc_env.agents.experiments.evaluate import (
        Evaluation,
        _run,
        effort_bound,
        plot_curves,
        reach_effort_bound,
    )

    popsize, maxiter = budget.np_g(load_scenario("paper_6_2"))
    sc = load_scenario("paper_6_2", {"planner.population": popsize, "planner.generations": maxiter})
    # the paper's three methods, then the allocation planner (beyond the paper: issue 12)
    policies = ("de_plan", "greedy_bayes", "potential_game", "allocation_plan")
    jobs = [(sc, p, 1000 + seed + k) for p in policies for k in range(budget.episodes)]
    episodes = runner.map(_run, jobs, "table7")
    ev = Evaluation(
        sc.name, tuple(episodes), effort_bound(sc), policies, bound_reach=reach_effort_bound(sc)
    )
    rows = []
    for r in ev.rows():
        paper = PAPER_TABLE7.get(r["policy"])
        rows.append({**r, "paper_posc": float(np.sum(paper)) if paper else None})
    fig = plot_curves(ev, out / "table7.png", sc.episode.dt_s)
    table = (
        ev.table()
        + "\n"
        + (
            "paper (the sum of its six rows, one per UAV; its own method's sum is Table 8's "
            "0.8740): " + ", ".join(f"{p} {np.sum(v):.4f}" for p, v in PAPER_TABLE7.items())
        )
    )
    return Result("table7", rows, table, [fig])


# -- §6.3-6.4: optimisers and parameters ------------------------------------------------------
OPTIMIZERS = ("adaptive_de", "classic_de", "chaotic_abc", "grouped_pso", "scipy_de", "cmaes")


def _convergence_plot(curves: dict[str, list[list[float]]], path: Path, title: str, xlabel: str):
    fig = _figure()
    ax = fig.add_subplot()
    lows: list[float] = []
    tops: list[float] = []
    for k, (label, hs) in enumerate(curves.items()):
        n = min(len(h) for h in hs)
        h = np.array([hh[:n] for hh in hs])
        x = np.linspace(0.0, 1.0, n) if xlabel.startswith("share") else np.arange(n)
        m, s = h.mean(axis=0), h.std(axis=0)
        ax.plot(x, m, color=f"C{k}", label=label)
        ax.fill_between(x, m - s, m + s, color=f"C{k}", alpha=0.15)
        lows.append(float(m[-1] - s[-1]))
        tops.append(float(m[-1]))
    # Overtime penalties (eq. 26, M = 1000 per second) make early values 1e7 times the final
    # ones; when every curve ends feasible (eq. 26 <= 0), show the feasible range only.
    lo = min(lows)
    if max(tops) <= 0.0 and np.isfinite(lo) and lo < 0.0:
        ax.set_ylim(1.1 * lo, -0.05 * lo)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("best eq. 26 objective (lower is better)")
    ax.set_title(title)
    ax.legend(fontsize=8)
    return _save(fig, path)


def _setting_rows(results: dict[str, list[dict[str, Any]]], key: str) -> list[dict[str, Any]]:
    rows = []
    for label, rs in results.items():
        obj, obj_ci = _mean_ci([r["objective"] for r in rs])
        posc, posc_ci = _mean_ci([r["posc"] for r in rs])
        best = min(rs, key=lambda r: r["objective"])
        feasible = [all(u["feasible"] for u in r["plan"]["uavs"]) for r in rs]
        rows.append(
            {
                key: label,
                "seeds": len(rs),
                "feasible": f"{sum(feasible)}/{len(rs)}",
                "objective_mean": obj,
                "objective_ci95": obj_ci,
                "posc_mean": posc,
                "posc_ci95": posc_ci,
                "best_posc": best["posc"],
                "bound_of_best": best["bound"],
                "runtime_s_mean": float(np.mean([r["runtime_s"] for r in rs])),
            }
        )
    return rows


_SETTING_COLS = [
    ("feasible", "feasible", ""),
    ("objective_mean", "objective", ".4f"),
    ("objective_ci95", "±95%", ".4f"),
    ("posc_mean", "POS_C", ".4f"),
    ("posc_ci95", "±95%", ".4f"),
    ("best_posc", "best POS_C", ".4f"),
    ("bound_of_best", "its bound", ".4f"),
    ("runtime_s_mean", "time/s", ".2f"),
]


def exp_fig22(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    sc = load_scenario("paper_6_2")
    popsize, maxiter = budget.np_g(sc)
    jobs = [
        (
            sc,
            {
                "optimizer": o,
                "seed": seed + k,
                "popsize": popsize,
                "maxiter": maxiter,
                "preset": budget.preset,
            },
        )
        for o in OPTIMIZERS
        for k in range(budget.seeds)
    ]
    res = runner.map(_plan_job, jobs, "fig22")
    by = {o: res[i * budget.seeds : (i + 1) * budget.seeds] for i, o in enumerate(OPTIMIZERS)}
    rows = _setting_rows(by, "optimizer")
    ref = [r["objective"] for r in by["classic_de"]]
    for row in rows:
        mine = [r["objective"] for r in by[row["optimizer"]]]
        row["wins_vs_classic_de"] = int(sum(a < b for a, b in zip(mine, ref)))
    fig = _convergence_plot(
        {o: [r["history"] for r in by[o]] for o in OPTIMIZERS},
        out / "fig22.png",
        f"paper_6_2, NP {popsize}, G {maxiter}, preset {budget.preset}, {budget.seeds} seeds "
        "(mean ± sd)",
        "share of the evaluation budget",
    )
    cols = [("optimizer", "optimizer", ""), *_SETTING_COLS, ("wins_vs_classic_de", "wins", "d")]
    table = _fmt_table(rows, cols) + (
        "\nwins: seeds on which the optimiser's final objective beats classic DE's (same seed)."
        f"\npreset {budget.preset}: F0, CR of the two DEs "
        f"({', '.join(f'{k} {v}' for k, v in _de_constants(sc, budget.preset).items())})."
    )
    return Result("fig22", rows, table, [fig])


def _de_constants(sc: Scenario, preset: str) -> dict[str, float]:
    from poc_env.agents.planning.optimizers import preset_settings

    pl = preset_settings(preset, sc.planner)
    return {"F0": pl["f0"], "CR": pl["cr"]}


def _sweep(
    name: str,
    budget: Budget,
    runner: Runner,
    out: Path,
    seed: int,
    settings: list[tuple[Any, Scenario, dict[str, Any]]],
    key: str,
    xlabel: str,
    paper: dict[Any, float] | None = None,
    results: dict[Any, list[dict[str, Any]]] | None = None,
    bound_reach: dict[Any, float] | None = None,
) -> Result:
    """Plan every setting with ``budget.seeds`` seeds (or take ``results``); POS (best and
    mean) and bound per setting; with ``bound_reach`` (per setting) also the environment's
    reach-aware bound and POS_C / that bound (best plan and mean), as ``table7`` reports it."""
    if results is None:
        jobs = [
            (sc, {**kw, "seed": seed + k}) for _, sc, kw in settings for k in range(budget.seeds)
        ]
        res = runner.map(_plan_job, jobs, name)
        n = budget.seeds
        by = {label: res[i * n : (i + 1) * n] for i, (label, _, _) in enumerate(settings)}
    else:
        by = results
    rows = _setting_rows(by, key)
    prev = None
    for row in rows:
        if paper is not None:
            row["paper_pos"] = paper.get(row[key])
        row["increment"] = None if prev is None else row["best_posc"] - prev
        prev = row["best_posc"]
        if bound_reach is not None:
            reach = bound_reach[row[key]]
            row["bound_reach"] = reach
            row["best_over_reach"] = row["best_posc"] / reach if reach > 0 else None
            row["mean_over_reach"] = row["posc_mean"] / reach if reach > 0 else None
    fig = _figure()
    ax = fig.add_subplot()
    xs = [r[key] for r in rows]
    ax.plot(xs, [r["best_posc"] for r in rows], "o-", label="best plan POS_C")
    ax.errorbar(
        xs,
        [r["posc_mean"] for r in rows],
        yerr=[r["posc_ci95"] for r in rows],
        fmt="s--",
        ms=4,
        label="mean over seeds (95 %)",
    )
    ax.plot(xs, [r["bound_of_best"] for r in rows], "k:", label="physical optimum (same effort)")
    if bound_reach is not None:
        ax.plot(xs, [r["bound_reach"] for r in rows], "k--", label="reach-aware bound (env)")
    if paper is not None:
        ax.plot(list(paper), list(paper.values()), "r^-", label="paper")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("POS_C")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=8)
    ax.set_title(f"{name}: NP {budget.np_g(settings[0][1])[0]}, G {budget.np_g(settings[0][1])[1]}")
    path = _save(fig, out / f"{name}.png")
    cols = [(key, key, ""), *_SETTING_COLS, ("increment", "increment", ".4f")]
    if bound_reach is not None:
        cols += [
            ("bound_reach", "reach bound", ".4f"),
            ("best_over_reach", "best/reach", ".4f"),
            ("mean_over_reach", "mean/reach", ".4f"),
        ]
    if paper is not None:
        cols.append(("paper_pos", "paper", ".4f"))
    return Result(name, rows, _fmt_table(rows, cols), [path])


def grow_plan(x_small, small, large, rng: np.random.Generator) -> np.ndarray:
    """A warm start for the larger fleet ``large`` (a PlanObjective) from the best individual
    ``x_small`` of ``small``: every UAV of the small fleet keeps its genes (matched to a UAV of
    the large fleet that takes off from the same airfield, in order); a new UAV copies the
    genes of a UAV from its own airfield (so its plan is just as feasible; the §3.1.6 overlap
    rule credits the shared cells once, so it adds nothing yet), or gets genes drawn uniformly
    within the bounds if its airfield had none. The warm start therefore scores what the
    smaller fleet had, and DE's greedy selection never loses it."""
    from poc_env.agents.planning.objective import PARAMS_PER_UAV as K

    lo, hi = np.asarray(large.bounds, dtype=float).T
    out = rng.uniform(lo, hi)
    xs = np.asarray(x_small, dtype=float)
    free = list(range(large.n))
    for i in range(small.n):
        j = next(j for j in free if np.allclose(large.takeoff_m[j], small.takeoff_m[i]))
        free.remove(j)
        out[K * j : K * (j + 1)] = xs[K * i : K * (i + 1)]
    for j in free:
        same = [i for i in range(small.n) if np.allclose(small.takeoff_m[i], large.takeoff_m[j])]
        if same:
            out[K * j : K * (j + 1)] = xs[K * same[0] : K * (same[0] + 1)]
    return np.clip(out, lo, hi)


def _fleet_job(job: tuple[Scenario, dict[str, Any], Sequence[int]]) -> list[dict[str, Any]]:
    """Plans for fleets of ``sizes`` UAVs with one seed, each warm-started from the last."""
    from poc_env.agents.planning.objective import PlanObjective
    from poc_env.theory.probability_map import build_prior

    sc, kw, sizes = job
    prior = build_prior(sc.map)
    rng = np.random.default_rng([kw["seed"], 8])
    out: list[dict[str, Any]] = []
    prev = None
    for n in sizes:
        init = None
        if prev is not None:
            small = PlanObjective(sc, prior, uavs=prev[0])
            large = PlanObjective(sc, prior, uavs=n)
            init = grow_plan(prev[1], small, large, rng)[None]
        r = _plan_job((sc, {**kw, "uavs": n, "init": init}))
        prev = (n, r["plan"]["x"])
        out.append(r)
    return out


def largest_area_for(pos: float, effort_m2: float, law: str = "inverse_cube") -> float:
    """The largest area (m^2) over which a uniformly spread target mass can still be found
    with probability ``pos`` by ``effort_m2`` of sweep (POD = eq. 10 / the law at coverage
    effort / area, the optimal uniform allocation). A map reaches ``pos`` with that effort
    only if its mass is at least this concentrated."""
    from scipy.optimize import brentq

    from poc_env.theory.search_theory import pod_from_coverage

    c = brentq(lambda z: float(pod_from_coverage(z, law)) - pos, 1e-9, 50.0)
    return effort_m2 / c


def exp_table8(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    from poc_env.agents.experiments.evaluate import reach_effort_bound

    sc = load_scenario("paper_6_2")
    popsize, maxiter = budget.np_g(sc)
    sizes = list(range(4, 9))
    kw = {"popsize": popsize, "maxiter": maxiter, "preset": budget.preset}
    jobs = [(sc, {**kw, "seed": seed + k}, sizes) for k in range(budget.seeds)]
    chains = runner.map(_fleet_job, jobs, "table8")
    settings: list[tuple[Any, Scenario, dict[str, Any]]] = [(n, sc, {}) for n in sizes]
    by = {n: [chain[i] for chain in chains] for i, n in enumerate(sizes)}
    # the environment's reach-aware bound of each fleet, as table7 and ``evaluate`` report it
    # (a plan's own ``bounds`` are its scenario's fleet's, not the n UAVs it planned)
    reach = {n: reach_effort_bound(sc.with_uavs(n)) for n in sizes}
    res = _sweep(
        "table8", budget, runner, out, seed, settings, "uavs", "number of UAVs", PAPER_TABLE8,
        results=by, bound_reach=reach,
    )  # fmt: skip
    u = sc.uav
    area = sc.map.width_m * sc.map.height_m
    lines = ["How concentrated the paper's map must be for its Table 8 (effort: every UAV "
             "sweeping W for the whole usable 0.85 T at v_s, transit ignored):"]  # fmt: skip
    for n, pos in PAPER_TABLE8.items():
        effort = n * u.usable_endurance_s * u.search_speed_mps * sc.sensor.sweep_width_m
        a = largest_area_for(pos, effort, sc.sensor.law)
        lines.append(
            f"  {n} UAVs: POS {pos:.4f} needs the mass within {a / 1e6:,.0f} km^2 "
            f"({a / area:.0%} of the {area / 1e6:,.0f} km^2 area) if spread evenly"
        )
    res.table += "\n" + "\n".join(lines)
    return res


def _scales(budget: Budget, lo: float, hi: float) -> list[float]:
    if budget.quick:
        return [lo, 1.0, hi]
    return [round(float(v), 2) for v in np.arange(lo, hi + 1e-9, 0.1)]


def exp_fig23(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    base = load_scenario("paper_6_2")
    popsize, maxiter = budget.np_g(base)
    w_km = base.sensor.sweep_width_m / 1e3
    settings = [
        (f, load_scenario("paper_6_2", {"sensor.sweep_width_km": w_km * f}),
         {"popsize": popsize, "maxiter": maxiter, "preset": budget.preset})
        for f in _scales(budget, 0.6, 1.4)
    ]  # fmt: skip
    return _sweep("fig23", budget, runner, out, seed, settings, "w_scale", "W / 5 km")


def scaled_area(factor: float) -> Scenario:
    """paper_6_2 with the task area's length and width times ``factor``: the grid keeps its
    30 x 40 cells (cell size x factor) and the prior is the same map stretched with it
    (component means and spreads x factor); airfields, UAVs and W stay."""
    import yaml

    from poc_env.config import CONFIG_DIR

    raw = yaml.safe_load((CONFIG_DIR / "paper_6_2.yaml").read_text(encoding="utf-8"))
    m = raw["map"]
    comps = [
        {
            **c,
            "mean_km": [v * factor for v in c["mean_km"]],
            "sigma_km": [v * factor for v in c["sigma_km"]],
        }
        for c in m["prior"]["components"]
    ]
    return load_scenario(
        "paper_6_2",
        {
            "map.width_km": m["width_km"] * factor,
            "map.height_km": m["height_km"] * factor,
            "map.cell_km": m["cell_km"] * factor,
            "map.prior.components": comps,
        },
    )


def exp_fig24(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    popsize, maxiter = budget.np_g(load_scenario("paper_6_2"))
    kw = {"popsize": popsize, "maxiter": maxiter, "preset": budget.preset}
    settings = [(f, scaled_area(f), kw) for f in _scales(budget, 0.5, 1.5)]
    return _sweep("fig24", budget, runner, out, seed, settings, "area_scale", "side length x")


def _parameter(name: str, budget, runner, out, seed, key, values, label) -> Result:
    sc = load_scenario("paper_6_2")
    popsize, maxiter = budget.np_g(sc)
    jobs = []
    for v in values:
        kw = {"popsize": popsize, "maxiter": maxiter, "preset": budget.preset, key: v}
        jobs += [(sc, {**kw, "seed": seed + k}) for k in range(budget.seeds)]
    res = runner.map(_plan_job, jobs, name)
    n = budget.seeds
    by = {f"{label} {v}": res[i * n : (i + 1) * n] for i, v in enumerate(values)}
    rows = _setting_rows(by, "setting")
    fig = _convergence_plot(
        {k: [r["history"] for r in rs] for k, rs in by.items()},
        out / f"{name}.png",
        f"adaptive DE on paper_6_2, {n} seeds (mean ± sd)",
        "generation",
    )
    return Result(name, rows, _fmt_table(rows, [("setting", "setting", ""), *_SETTING_COLS]), [fig])


def exp_fig25(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    g = budget.np_g(load_scenario("paper_6_2"))[1]
    values = [round(g * f) for f in (230 / 300, 270 / 300, 1.0)]
    return _parameter("fig25", budget, runner, out, seed, "maxiter", values, "G")


def exp_fig26(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    p = budget.np_g(load_scenario("paper_6_2"))[0]
    values = [p, round(1.5 * p), 2 * p]
    return _parameter("fig26", budget, runner, out, seed, "popsize", values, "NP")


# -- beyond the paper: the next sortie (issue 24) ----------------------------------------------
#: Scenarios and number of sorties of :func:`exp_sorties`.
SORTIE_SCENARIOS = ("small", "paper_6_2")
SORTIES = 3


def _sorties_job(job: tuple[str, int, int | None]) -> list[dict[str, Any]]:
    """One random prior (:func:`~poc_env.agents.experiments.evaluate.episode_prior` of
    ``seed``), :data:`SORTIES` allocation plans in a row (``poc-env replan``'s
    :func:`~poc_env.agents.planning.replan.next_sortie`), and after each sortie ``k`` the
    cumulative POS beside the honest bound for ``k`` sorties."""
    from poc_env.agents.experiments.evaluate import episode_prior
    from poc_env.agents.planning.planner import make_plan
    from poc_env.agents.planning.replan import next_sortie
    from poc_env.theory.bound import honest_optimum

    name, seed, refine = job
    sc = load_scenario(name)
    prior = episode_prior(name, seed)
    plans = [make_plan(sc, prior=prior, planner="allocation", seed=seed, refine=refine)]
    while len(plans) < SORTIES:
        plans.append(next_sortie(sc, prior, plans, seed=seed, refine=refine))
    rows = []
    for k, plan in enumerate(plans, start=1):
        cum = float(plan.get("cumulative_posc", plan["posc"]))
        own = float(plan.get("sortie_posc", plan["posc"]))  # on the belief the flights left
        bound = honest_optimum(sc, prior, sorties=k).pos
        rows.append({"scenario": name, "seed": seed, "sortie": k, "sortie_posc": own,
                     "posc": cum, "bound": bound, "ratio": cum / bound})  # fmt: skip
    return rows


def exp_sorties(budget: Budget, runner: Runner, out: Path, seed: int) -> Result:
    """Three sorties in a row (``poc-env replan``) on ``small`` and ``paper_6_2``, random priors
    (episode priors ``seed .. seed + seeds - 1``): the cumulative POS after each sortie ``k``
    against the honest bound for ``k`` sorties, :func:`poc_env.theory.bound.honest_optimum`
    with ``sorties=k`` -- the static honest bound with ``k`` times the endurance. It is a valid
    upper bound: each sortie spends at most one sortie's effort, and by eq. 14 the sorties
    together detect what one flight made of all their tracks (``k`` times the effort at most)
    would, which the allocation bound for that effort caps (the argument in full is in
    ``honest_optimum``'s docstring). ``--quick`` plans without the waypoint refinement."""
    jobs = [(n, seed + k, 0 if budget.quick else None) for n in SORTIE_SCENARIOS
            for k in range(budget.seeds)]  # fmt: skip
    per_seed = [r for rows in runner.map(_sorties_job, jobs, "sorties") for r in rows]
    rows = []
    for name in SORTIE_SCENARIOS:
        for k in range(1, SORTIES + 1):
            rs = [r for r in per_seed if r["scenario"] == name and r["sortie"] == k]
            mean, ci = _mean_ci([r["posc"] for r in rs])
            ratios = [r["ratio"] for r in rs]
            rows.append({
                "scenario": name, "sortie": k, "seeds": len(rs),
                "sortie_posc_mean": float(np.mean([r["sortie_posc"] for r in rs])),
                "posc_mean": mean, "posc_ci95": ci,
                "bound": float(np.mean([r["bound"] for r in rs])),
                "ratio_mean": float(np.mean(ratios)), "ratio_min": float(np.min(ratios)),
            })  # fmt: skip
    cols = [
        ("scenario", "scenario", "s"),
        ("sortie", "sortie", "d"),
        ("sortie_posc_mean", "this sortie", ".4f"),
        ("posc_mean", "cumulative", ".4f"),
        ("posc_ci95", "+-95%", ".4f"),
        ("bound", "bound(k)", ".4f"),
        ("ratio_mean", "cum/bound", ".3f"),
        ("ratio_min", "min", ".3f"),
    ]
    table = _fmt_table(rows, cols) + (
        f"\n{budget.seeds} random priors per scenario; allocation planner, sortie k+1 planned "
        "by poc-env replan on the prior less what sorties 1..k searched (eq. 14); bound(k): "
        "the honest bound for k x the fleet's endurance (theory.bound.honest_optimum)."
    )
    fig = _figure()
    ax = fig.subplots()
    for name, style in zip(SORTIE_SCENARIOS, ("o-", "s-")):
        rs = [r for r in rows if r["scenario"] == name]
        ks = [r["sortie"] for r in rs]
        line = ax.plot(ks, [r["posc_mean"] for r in rs], style, label=f"{name}: cumulative POS")
        ax.plot(ks, [r["bound"] for r in rs], "--", color=line[0].get_color(),
                label=f"{name}: honest bound, k x endurance")  # fmt: skip
    ax.set_xlabel("sortie k")
    ax.set_ylabel("POS (mean over random priors)")
    ax.set_xticks(range(1, SORTIES + 1))
    ax.set_ylim(0, 1.02)
    ax.legend(loc="lower right", fontsize=8)
    path = _save(fig, out / "sorties.png")
    return Result("sorties", rows, table, [path])


EXPERIMENTS: dict[str, Callable[[Budget, Runner, Path, int], Result]] = {
    "table4": exp_table4,
    "table5": exp_table5,
    "table6": exp_table6,
    "table7": exp_table7,
    "fig22": exp_fig22,
    "table8": exp_table8,
    "fig23": exp_fig23,
    "fig24": exp_fig24,
    "fig25": exp_fig25,
    "fig26": exp_fig26,
    "sorties": exp_sorties,
}


def run_experiment(
    name: str,
    *,
    quick: bool = False,
    out: str | Path = "out/experiments",
    workers: int = 1,
    seed: int = 0,
    progress: bool = False,
    echo: Callable[[str], None] | None = print,
    preset: str = "paper",
) -> list[Result]:
    """Run experiment ``name`` (or ``all``); write and return its results.

    ``preset`` (``paper`` or ``tuned``, :func:`poc_env.agents.planning.optimizers.preset_settings`):
    the DE settings of every plan the experiments make.
    """
    from poc_env.agents.planning.optimizers import PRESETS

    if name != "all" and name not in EXPERIMENTS:
        raise ConfigError("experiment", name, "one of " + ", ".join([*EXPERIMENTS, "all"]))
    if not isinstance(preset, str) or preset not in PRESETS:
        raise ConfigError("preset", preset, " or ".join(PRESETS))
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError("seed", seed, "an integer >= 0")
    names = list(EXPERIMENTS) if name == "all" else [name]
    budget = dataclasses.replace(QUICK if quick else FULL, preset=preset)
    runner = Runner(workers, progress)
    results: list[Result] = []
    # The command's set of outputs is complete or absent: one experiment stages its own folder;
    # ``all`` stages the whole of ``out``, so a kill part-way leaves the previous run's results
    # as they were, never mixed with some of the new run's.
    whole = atomic_dir(out) if name == "all" else contextlib.nullcontext(None)
    held: list[str] = []  # ``all``: the ``wrote`` lines, said once ``out`` is in place
    try:
        with whole as stage:
            for k, n in enumerate(names):
                final = Path(out) / n
                if echo is not None and len(names) > 1:
                    echo(f"\n[{k + 1}/{len(names)}] {n} ...")
                t0 = time.perf_counter()
                inner = (
                    contextlib.nullcontext(stage / n) if stage is not None else atomic_dir(final)
                )
                with inner as folder:  # each experiment's folder: complete or absent
                    folder.mkdir(parents=True, exist_ok=True)
                    res = EXPERIMENTS[n](budget, runner, folder, seed)
                    wall = time.perf_counter() - t0
                    res.files[:0] = [
                        write_text_atomic(folder / f"{n}.csv", res.csv()),
                        write_text_atomic(folder / f"{n}.txt", res.table + "\n"),
                    ]
                res.files = [final / Path(p).relative_to(folder) for p in res.files]
                results.append(res)
                if echo is not None:
                    budget_name = "quick" if quick else "paper budget"
                    echo(f"\n== {n} ({budget_name}, {wall:.1f} s) ==")
                    echo(res.table)
                    said = "wrote " + ", ".join(str(p) for p in res.files)
                    if stage is None:
                        echo(said)
                    else:
                        held.append(said)
    finally:
        runner.close()
    if echo is not None:
        for said in held:
            echo(said)
    return results


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="poc-env experiment", description="Reproduce the paper's §6 experiments."
    )
    add_arguments(ap)
    ns = ap.parse_args(argv)
    return cmd(ns)


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("name", help="one of " + ", ".join([*EXPERIMENTS, "all"]))
    ap.add_argument("--quick", action="store_true", help="reduced budget (about a minute)")
    ap.add_argument("--out", default="out/experiments", help="output folder")
    ap.add_argument("--workers", type=int, default=1, help="worker processes")
    ap.add_argument("--seed", type=int, default=0, help="first optimiser seed")
    ap.add_argument("--quiet", action="store_true", help="no progress bar")
    ap.add_argument(
        "--preset",
        default="paper",
        help="DE settings of every plan: paper or tuned (docs/PLANNER.md)",
    )


def cmd(ns: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    run_experiment(
        ns.name,
        quick=ns.quick,
        out=ns.out,
        workers=ns.workers,
        seed=ns.seed,
        progress=not ns.quiet,
        preset=ns.preset,
    )
    print(f"\ntotal wall time {time.perf_counter() - t0:.1f} s ({ns.workers} workers)")
    return 0
