"""Score policies on the same episodes: mean POSC with 95 % intervals, detection, violations.

Every policy runs the same ``episodes`` seeds (``seed0 .. seed0 + episodes - 1``); each episode
creates a fresh environment reset with its seed, so results do not depend on ``workers`` or on
the order in which episodes run. Besides POSC (eq. 13) the table reports the hidden target's
detection rate and mean time to detection, constraint-violation steps, crashes, and two upper
bounds no policy can exceed in the environment (:mod:`poc_env.theory.bound`): the plain
physical optimum for the swarm's largest effort (every UAV sweeping at ``max_speed`` for as long
as the environment lets it sense, until the endurance T or the horizon), and the reach-aware
bound (the same UAVs must first fly from their airfields to the cells, at most at ``max_speed``).
The normalised score is POSC / reach-aware bound, per episode and averaged (``normalised``).
Policies are named as in :mod:`poc_env.agents.policies.registry` (``ppo:PATH`` included).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

import poc_env.limits as limits
from poc_env.agents.experiments.pool import process_pool, run_jobs  # noqa: F401 (process_pool: API)
from poc_env.agents.policies.registry import make_policy
from poc_env.errors import ConfigError, as_int
from poc_env.io import csv_text


def check_policies(policies: Sequence[str]) -> None:
    """Make every policy once, so that a bad name fails before any episode runs.

    Raises
    ------
    ConfigError
        Field ``policies`` for a name the registry does not know (listing the registered ones).
    """
    for p in policies:
        try:
            make_policy(p)
        except ConfigError as err:
            if err.field != "policy":
                raise
            raise ConfigError("policies", err.value, err.allowed) from None


@dataclass(frozen=True)
class Episode:
    policy: str
    seed: int
    posc: float
    detected: bool
    time_to_detection_s: float | None
    violation_steps: int
    crashed: int
    landed: int
    steps: int
    posc_curve: tuple[float, ...] = field(repr=False)
    #: plain physical optimum of this episode's prior for the swarm's largest effort
    #: (:func:`effort_bound`; None until known: :func:`evaluate` fills it in)
    bound: float | None = None
    #: reach-aware bound of this episode's prior (:func:`reach_effort_bound`)
    bound_reach: float | None = None
    #: moving-target bound of this episode (:func:`moving_effort_bound`; None when the
    #: scenario's target stands still)
    bound_moving: float | None = None

    @property
    def normalised(self) -> float | None:
        """POSC / reach-aware bound (None without the bound)."""
        return None if not self.bound_reach else self.posc / self.bound_reach


#: Second entropy word of the evaluation priors' generators: ``default_rng([seed, STREAM])``.
#: Training draws its priors from ``SeedSequence(train_seed).spawn(n_envs)`` (spawned, so
#: with a non-empty spawn key), which never yields this generator.
EVAL_PRIOR_STREAM = 0x5EA7C4


def episode_prior(scenario: Any, seed: int) -> np.ndarray:
    """The random Gaussian-mixture prior of evaluation episode ``seed`` (``--random-priors``)."""
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid, random_gaussian_mixture

    grid = Grid.from_config(load_scenario(scenario).map)
    return random_gaussian_mixture(grid, np.random.default_rng([seed, EVAL_PRIOR_STREAM]))


def run_episode(
    scenario: Any,
    policy: str,
    seed: int,
    map_file: str | None = None,
    random_priors: bool = False,
) -> Episode:
    """One episode of ``policy`` (a name of :func:`poc_env.agents.policies.registry.registered`) on
    a fresh env reset with ``seed`` (and, with ``random_priors``, the prior :func:`episode_prior`
    of ``seed``)."""
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario=scenario, map_file=map_file)
    pol = make_policy(policy)
    prior = episode_prior(env.scenario, seed) if random_priors else None
    options = None if prior is None else {"prior": prior}
    obs, _ = env.reset(seed=seed, options=options)
    pol.reset(env, seed)
    curve = []
    while env.agents:
        actions, _ = pol.predict(obs)
        obs, *_ = env.step(actions)
        curve.append(float(env.sim_state.posc[0]))
    st = env.sim_state
    return Episode(
        policy=policy,
        seed=seed,
        posc=float(st.posc[0]),
        detected=bool(st.detected[0]),
        time_to_detection_s=float(st.detect_step[0] * env.params.dt) if st.detected[0] else None,
        violation_steps=int(st.violations[0].sum()),
        crashed=int(st.crashed[0].sum()),
        landed=int(st.landed[0].sum()),
        steps=int(st.step[0]),
        posc_curve=tuple(curve),
        bound=effort_bound(env.scenario, map_file, prior) if random_priors else None,
        bound_reach=reach_effort_bound(env.scenario, map_file, prior) if random_priors else None,
    )


def _run(args):
    return run_episode(*args)


@dataclass(frozen=True)
class Evaluation:
    scenario: str
    episodes: tuple[Episode, ...]
    bound: float
    policies: tuple[str, ...]
    random_priors: bool = False
    #: reach-aware bound (mean over the episodes' priors with ``random_priors``); None if not
    #: computed (then ``bound_reach`` and ``normalised`` are left empty)
    bound_reach: float | None = None

    def rows(self) -> list[dict[str, Any]]:
        out = []
        for p in self.policies:
            eps = [e for e in self.episodes if e.policy == p]
            x = np.array([e.posc for e in eps])
            half = 1.96 * x.std(ddof=1) / np.sqrt(len(x)) if len(x) > 1 else 0.0
            ttd = [e.time_to_detection_s for e in eps if e.time_to_detection_s is not None]
            norm = [e.normalised for e in eps]
            if any(v is None for v in norm) and self.bound_reach:
                norm = [e.posc / self.bound_reach for e in eps]
            out.append(
                {
                    "policy": p,
                    "episodes": len(eps),
                    "posc_mean": float(x.mean()),
                    "posc_ci95": float(half),
                    "detection_rate": float(np.mean([e.detected for e in eps])),
                    "time_to_detection_min": float(np.mean(ttd) / 60) if ttd else None,
                    "violation_steps": float(np.mean([e.violation_steps for e in eps])),
                    "crashed": float(np.mean([e.crashed for e in eps])),
                    "landed": float(np.mean([e.landed for e in eps])),
                    "bound": self.bound,
                    "bound_reach": self.bound_reach,
                    "normalised": None
                    if any(v is None for v in norm)
                    else float(np.mean(np.asarray(norm, dtype=float))),
                    **_moving_columns(eps),
                }
            )
        return out

    def table(self) -> str:
        width = max(14, *(len(p) for p in self.policies))
        head = (
            f"{'policy':<{width}} {'POSC':>8} {'±95%':>7} {'detected':>9} {'t_det/min':>10} "
            f"{'viol.steps':>10} {'crashed':>8} {'landed':>7} {'POSC/reach':>10}"
        )
        moving = any(e.bound_moving is not None for e in self.episodes)
        head += f" {'POSC/moving':>11}" if moving else ""
        lines = [head, "-" * len(head)]
        for r in self.rows():
            t = f"{r['time_to_detection_min']:.1f}" if r["time_to_detection_min"] else "-"
            nrm = "-" if r["normalised"] is None else f"{r['normalised']:.4f}"
            lines.append(
                f"{r['policy']:<{width}} {r['posc_mean']:>8.4f} {r['posc_ci95']:>7.4f} "
                f"{r['detection_rate']:>9.2f} {t:>10} {r['violation_steps']:>10.1f} "
                f"{r['crashed']:>8.2f} {r['landed']:>7.2f} {nrm:>10}"
                + (f" {r['normalised_moving']:>11.4f}" if moving else "")
            )
        lines.append("-" * len(head))
        mean = "mean over the episodes' random priors of the " if self.random_priors else ""
        lines.append(
            f"{mean}physical optimum for the swarm's largest effort (all UAVs at max speed "
            f"until T): {self.bound:.4f}"
        )
        if self.bound_reach is not None:
            lines.append(
                f"{mean}reach-aware bound (transit from the airfields at max speed; normalises "
                f"POSC/reach): {self.bound_reach:.4f}"
            )
        if moving:
            first = self.episodes[: len(self.episodes) // len(self.policies)]
            mb = [float(e.bound_moving or 0.0) for e in first]
            lines.append(
                "mean over the episodes of the moving-target bound (poc_env.theory.moving_bound; "
                f"the target moves, so the static bounds do not hold): {np.mean(mb):.4f}"
            )
        return "\n".join(lines)

    def paired(self, baseline: str) -> list[dict[str, Any]]:
        """Every other policy against ``baseline`` on the same seeds: the mean of the per-seed
        POSC differences (policy - baseline), its 95 % interval (1.96 standard errors of the
        differences), and the seeds the policy wins, ties (|difference| < 1e-12) and loses.

        The seeds are shared, so the prior-to-prior spread that dominates each policy's own
        interval cancels: this is the comparison to quote when two policies' intervals overlap.

        Raises
        ------
        ConfigError
            Field ``baseline`` when ``baseline`` is not one of the evaluated policies.
        """
        if baseline not in self.policies:
            raise ConfigError("baseline", baseline, "one of the evaluated policies: "
                              + ", ".join(self.policies))  # fmt: skip
        ref = {e.seed: e.posc for e in self.episodes if e.policy == baseline}
        out = []
        for p in self.policies:
            if p == baseline:
                continue
            d = np.array([e.posc - ref[e.seed] for e in self.episodes if e.policy == p])
            half = 1.96 * d.std(ddof=1) / np.sqrt(len(d)) if len(d) > 1 else 0.0
            out.append(
                {
                    "policy": p,
                    "baseline": baseline,
                    "episodes": len(d),
                    "diff_mean": float(d.mean()),
                    "diff_ci95": float(half),
                    "wins": int((d > 1e-12).sum()),
                    "ties": int((np.abs(d) <= 1e-12).sum()),
                    "losses": int((d < -1e-12).sum()),
                }
            )
        return out

    def paired_table(self, baseline: str) -> str:
        """:meth:`paired` as text: the difference, its interval, and wins/ties/losses."""
        rows = self.paired(baseline)
        width = max(14, *(len(p) for p in self.policies))
        head = (
            f"{'policy':<{width}} {'- ' + baseline:>{max(16, len(baseline) + 2)}} {'±95%':>7} "
            f"{'wins':>5} {'ties':>5} {'losses':>6}"
        )
        lines = [f"paired differences in POSC against {baseline} (same seeds)", head]
        lines.append("-" * len(head))
        for r in rows:
            lines.append(
                f"{r['policy']:<{width}} {r['diff_mean']:>+{max(16, len(baseline) + 2)}.4f} "
                f"{r['diff_ci95']:>7.4f} {r['wins']:>5} {r['ties']:>5} {r['losses']:>6}"
            )
        return "\n".join(lines)

    def episode_rows(self) -> list[dict[str, Any]]:
        """One row per episode: POSC, both bounds of its prior and POSC / reach-aware bound."""
        reach = self.bound_reach
        return [
            {
                "policy": e.policy,
                "seed": e.seed,
                "posc": e.posc,
                "bound": e.bound if e.bound is not None else self.bound,
                "bound_reach": e.bound_reach if e.bound_reach is not None else reach,
                "normalised": e.normalised
                if e.normalised is not None
                else (e.posc / reach if reach else None),
                "detected": e.detected,
                "violation_steps": e.violation_steps,
                "crashed": e.crashed,
                "landed": e.landed,
                "bound_moving": e.bound_moving,
            }
            for e in self.episodes
        ]

    def episodes_csv(self) -> str:
        """:meth:`episode_rows` as CSV."""
        return csv_text(self.episode_rows())

    def to_csv(self) -> str:
        return csv_text(self.rows())


def _moving_columns(eps: Sequence[Episode]) -> dict[str, Any]:
    """The moving-target bound's columns of one policy's row (empty for a static target)."""
    if any(e.bound_moving is None for e in eps):
        return {}
    mb = np.array([float(e.bound_moving or 0.0) for e in eps])
    x = np.array([e.posc for e in eps])
    ratio = np.divide(x, mb, out=np.zeros_like(x), where=mb > 0)
    return {"bound_moving": float(mb.mean()), "normalised_moving": float(ratio.mean())}


def moving_effort_bound(
    scenario: Any, seed: int, map_file: str | None = None, random_priors: bool = False
) -> float | None:
    """The moving-target bound (:func:`poc_env.theory.moving_bound.moving_bound`) of episode
    ``seed``: its prior and its drift velocity, read from an environment reset with the seed;
    None when the scenario's target stands still or moves in a gridded field."""
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory.moving_bound import moving_bound

    env = UAVSearchParallelEnv(scenario=scenario, map_file=map_file)
    if env.params.motion is None or env.params.motion.field is not None:
        return None  # a gridded velocity field: not covered by the bound (its docstring)
    prior = episode_prior(env.scenario, seed) if random_priors else None
    env.reset(seed=seed, options=None if prior is None else {"prior": prior})
    st = env.sim_state
    assert st.drift is not None
    return moving_bound(env.scenario, st.belief[0], st.drift[0], env.params.s).upper


def _moving(args):
    return moving_effort_bound(*args)


def effort_bound(
    scenario: Any, map_file: str | None = None, prior: np.ndarray | None = None
) -> float:
    """Plain physical optimum for every UAV sweeping at ``max_speed`` for as long as the
    environment lets it sense (:func:`poc_env.theory.bound.honest_optimum`), on ``prior``
    (default: the scenario's prior or ``map_file``)."""
    from poc_env.config import load_scenario
    from poc_env.theory.bound import honest_optimum
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario(scenario)
    if prior is None:
        prior = build_prior(sc.map, map_file)
    return honest_optimum(sc, prior).pos


def reach_effort_bound(
    scenario: Any, map_file: str | None = None, prior: np.ndarray | None = None
) -> float:
    """Reach-aware bound (:func:`poc_env.theory.bound.reach_bound`, its certified upper value)
    on ``prior`` (default: the scenario's prior or ``map_file``)."""
    from poc_env.config import load_scenario
    from poc_env.theory.bound import reach_bound
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario(scenario)
    if prior is None:
        prior = build_prior(sc.map, map_file)
    return reach_bound(sc, prior).upper


def evaluate(
    scenario: Any,
    policies: Sequence[str],
    episodes: int = 10,
    seed0: int = 1000,
    workers: int = 1,
    map_file: str | None = None,
    progress: bool = False,
    random_priors: bool = False,
) -> Evaluation:
    """Run every policy on the same seeds; see the module docstring."""
    from poc_env.config import load_scenario

    episodes = as_int("episodes", episodes, 1, limits.MAX_EPISODES)
    workers = as_int("workers", workers, 1, limits.MAX_WORKERS)
    seed0 = as_int("seed", seed0, 0, limits.MAX_SEED)
    check_policies(policies)
    sc = load_scenario(scenario)
    if random_priors and map_file is not None:
        raise ConfigError("map", map_file, "no map file with --random-priors (one or the other)")
    jobs = [(sc, p, seed0 + k, map_file, random_priors) for p in policies for k in range(episodes)]
    results = tuple(run_jobs(_run, jobs, workers, desc="episodes" if progress else None))
    if random_priors:  # each episode's own prior; the same seeds for every policy
        bound = float(np.mean([float(e.bound or 0.0) for e in results[:episodes]]))
        reach = float(np.mean([float(e.bound_reach or 0.0) for e in results[:episodes]]))
    else:
        bound = effort_bound(sc, map_file)
        reach = reach_effort_bound(sc, map_file)
        results = tuple(replace(e, bound=bound, bound_reach=reach) for e in results)
    seeds = [(sc, seed0 + k, map_file, random_priors) for k in range(episodes)]
    if sc.target.model != "static":  # the moving-target bound of each seed's episode
        moving = dict(zip(range(seed0, seed0 + episodes), run_jobs(_moving, seeds, workers)))
        results = tuple(replace(e, bound_moving=moving[e.seed]) for e in results)
    return Evaluation(sc.name, results, bound, tuple(policies), random_priors, reach)


def plot_curves(ev: Evaluation, path: str | os.PathLike[str], dt_s: float) -> Path:
    """POSC over time per policy (mean over episodes, shaded 95 % band)."""
    from poc_env.viz.plots import _figure, save_figure_atomic

    fig = _figure((7.0, 4.5))
    ax = fig.add_subplot()
    for p in ev.policies:
        curves = [e.posc_curve for e in ev.episodes if e.policy == p]
        n = max(len(c) for c in curves)
        arr = np.array([list(c) + [c[-1]] * (n - len(c)) for c in curves])
        t = (np.arange(n) + 1) * dt_s / 60
        m = arr.mean(axis=0)
        h = 1.96 * arr.std(axis=0, ddof=1) / np.sqrt(len(arr)) if len(arr) > 1 else 0 * m
        ax.plot(t, m, label=p)
        ax.fill_between(t, m - h, m + h, alpha=0.2)
    ax.axhline(ev.bound, color="k", ls="--", lw=0.8, label="physical optimum (plain)")
    if ev.bound_reach is not None:
        ax.axhline(ev.bound_reach, color="k", ls=":", lw=0.8, label="reach-aware bound")
    ax.set_xlabel("time / min")
    ax.set_ylabel("POSC")
    ax.set_title(f"{ev.scenario}: POSC over time ({len(ev.episodes)} episodes)")
    ax.legend()
    return save_figure_atomic(fig, path)
