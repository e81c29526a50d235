"""Score policies on the same episodes: mean POSC with Student's t 95 % intervals
(:func:`poc_env.stats.ci95`), detection, violations.

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
from poc_env.stats import ci95


def check_once(policies: Sequence[str]) -> None:
    """ConfigError naming ``policies`` when a name is given twice (it would fly twice, and its
    runs would be pooled into one row over twice the episodes)."""
    names = list(policies)
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ConfigError("policies", names, f"each policy once (repeated: {', '.join(repeated)})")


def check_policies(policies: Sequence[str]) -> None:
    """Make every policy once, so that a bad name fails before any episode runs.

    Raises
    ------
    ConfigError
        Field ``policies`` for a name given twice (:func:`check_once`), or for a name the
        registry does not know (listing the registered ones).
    """
    check_once(policies)
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
    #: rule-aware bound of this episode's prior (:func:`rule_effort_bound`)
    bound_rule: float | None = None
    #: moving-target bound of this episode (:func:`moving_effort_bound`; None when the
    #: scenario's target stands still)
    bound_moving: float | None = None

    @property
    def normalised(self) -> float | None:
        """POSC / reach-aware bound (None without the bound)."""
        return None if not self.bound_reach else self.posc / self.bound_reach

    @property
    def normalised_rule(self) -> float | None:
        """POSC / rule-aware bound (None without the bound)."""
        return None if not self.bound_rule else self.posc / self.bound_rule


#: Second entropy word of the evaluation priors' generators: ``default_rng([seed, STREAM])``.
#: Training draws its priors from ``SeedSequence(train_seed).spawn(n_envs)`` (spawned, so
#: with a non-empty spawn key), which never yields this generator.
EVAL_PRIOR_STREAM = 0x5EA7C4


def _half(row: dict[str, Any], key: str = "posc_ci95") -> str:
    """A table's interval column: ``-`` for one episode (no spread to estimate; the records
    keep :func:`poc_env.stats.ci95`'s 0)."""
    return "-" if row["episodes"] < 2 else f"{row[key]:.4f}"


def episode_prior(scenario: Any, seed: int) -> np.ndarray:
    """The random Gaussian-mixture prior of evaluation episode ``seed`` (``--random-priors``)."""
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import Grid, random_gaussian_mixture

    grid = Grid.from_config(load_scenario(scenario).map)
    return random_gaussian_mixture(grid, np.random.default_rng([seed, EVAL_PRIOR_STREAM]))


def play(env, policy, seed: int, prior: np.ndarray | None = None, each=None) -> None:
    """Fly ``policy`` (an object with ``reset(env, seed)`` and ``predict(obs)``) for one episode
    of ``env`` reset with ``seed`` (and ``prior``, if given, as the reset's ``options["prior"]``),
    calling ``each(infos)`` after every step: the one episode loop of the evaluation harness,
    the airspace checks (:func:`poc_env.agents.testing.flights.fly`) and the planner's
    benchmarks. The episode's end state is ``env.sim_state``."""
    obs, _ = env.reset(seed=seed, options=None if prior is None else {"prior": prior})
    policy.reset(env, seed)
    while env.agents:
        actions, _ = policy.predict(obs)
        obs, _, _, _, infos = env.step(actions)
        if each is not None:
            each(infos)


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
    prior = episode_prior(env.scenario, seed) if random_priors else None
    curve: list[float] = []
    play(
        env, make_policy(policy), seed, prior, lambda _: curve.append(float(env.sim_state.posc[0]))
    )
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
        bound_rule=rule_effort_bound(env.scenario, map_file, prior) if random_priors else None,
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
    #: mean time to detection (min) per policy, for episodes that do not record their own
    #: (an episodes.csv written before it had ``time_to_detection_s``: :func:`summarise` takes
    #: the folder's evaluate.csv column); None: computed from the episodes
    time_to_detection_min: dict[str, float | None] | None = None
    #: rule-aware bound (:func:`rule_effort_bound`; the mean over the episodes' priors with
    #: ``random_priors``); None if not computed
    bound_rule: float | None = None

    def rows(self) -> list[dict[str, Any]]:
        out = []
        for p in self.policies:
            eps = [e for e in self.episodes if e.policy == p]
            x = np.array([e.posc for e in eps])
            half = ci95(x)
            ttd = [e.time_to_detection_s for e in eps if e.time_to_detection_s is not None]
            known = self.time_to_detection_min
            t_det = (float(np.mean(ttd) / 60) if ttd else None) if known is None else known[p]
            norm = [e.normalised for e in eps]
            if any(v is None for v in norm) and self.bound_reach:
                norm = [e.posc / self.bound_reach for e in eps]
            rule = [e.normalised_rule for e in eps]
            if any(v is None for v in rule) and self.bound_rule:
                rule = [e.posc / self.bound_rule for e in eps]
            out.append(
                {
                    "policy": p,
                    "episodes": len(eps),
                    "posc_mean": float(x.mean()),
                    "posc_ci95": float(half),
                    "detection_rate": float(np.mean([e.detected for e in eps])),
                    "time_to_detection_min": t_det,
                    "violation_steps": float(np.mean([e.violation_steps for e in eps])),
                    "crashed": float(np.mean([e.crashed for e in eps])),
                    "landed": float(np.mean([e.landed for e in eps])),
                    "bound": self.bound,
                    "bound_reach": self.bound_reach,
                    "normalised": None
                    if any(v is None for v in norm)
                    else float(np.mean(np.asarray(norm, dtype=float))),
                    "bound_rule": self.bound_rule,
                    "normalised_rule": None
                    if any(v is None for v in rule)
                    else float(np.mean(np.asarray(rule, dtype=float))),
                    **_moving_columns(eps),
                }
            )
        return out

    def table(self) -> str:
        width = max(14, *(len(p) for p in self.policies))
        head = (
            f"{'policy':<{width}} {'POSC':>8} {'±95%':>7} {'detected':>9} {'t_det/min':>10} "
            f"{'viol.steps':>10} {'crashed':>8} {'landed':>7} {'POSC/reach':>10} {'POSC/rule':>9}"
        )
        moving = any(e.bound_moving is not None for e in self.episodes)
        head += f" {'POSC/moving':>11}" if moving else ""
        lines = [head, "-" * len(head)]
        for r in self.rows():
            t = f"{r['time_to_detection_min']:.1f}" if r["time_to_detection_min"] else "-"
            nrm = "-" if r["normalised"] is None else f"{r['normalised']:.4f}"
            nrl = "-" if r["normalised_rule"] is None else f"{r['normalised_rule']:.4f}"
            lines.append(
                f"{r['policy']:<{width}} {r['posc_mean']:>8.4f} {_half(r):>7} "
                f"{r['detection_rate']:>9.2f} {t:>10} {r['violation_steps']:>10.1f} "
                f"{r['crashed']:>8.2f} {r['landed']:>7.2f} {nrm:>10} {nrl:>9}"
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
        if self.bound_rule is not None:
            lines.append(
                f"{mean}rule-aware bound (back by 0.85 T, home at v_c; normalises POSC/rule): "
                f"{self.bound_rule:.4f}"
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
        POSC differences (policy - baseline), its 95 % interval (Student's t over the seeds,
        :func:`poc_env.stats.ci95`), and the seeds the policy wins, ties (|difference| <
        1e-12) and loses.

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
            half = ci95(d)
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
                f"{_half(r, 'diff_ci95'):>7} {r['wins']:>5} {r['ties']:>5} {r['losses']:>6}"
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
                "bound_rule": e.bound_rule if e.bound_rule is not None else self.bound_rule,
                "normalised_rule": e.normalised_rule
                if e.normalised_rule is not None
                else (e.posc / self.bound_rule if self.bound_rule else None),
                "detected": e.detected,
                "violation_steps": e.violation_steps,
                "crashed": e.crashed,
                "landed": e.landed,
                "time_to_detection_s": e.time_to_detection_s,
                "steps": e.steps,
                "random_prior": self.random_priors,
                "bound_moving": e.bound_moving,
            }
            for e in self.episodes
        ]

    def episodes_csv(self) -> str:
        """:meth:`episode_rows` as CSV."""
        return csv_text(self.episode_rows())

    def to_csv(self) -> str:
        return csv_text(self.rows())

    def summary_files(self, baselines: Sequence[str] = ()) -> dict[str, str]:
        """The summary files of an evaluation folder, name -> text: ``evaluate.csv``,
        ``evaluate.txt`` (the table, then each baseline's paired table) and ``paired.csv``
        (each baseline's pairings; its header alone without ``baselines``). ``poc-env evaluate
        --out`` writes them beside ``episodes.csv``; ``poc-env summarise`` writes them again
        from ``episodes.csv`` alone (:func:`read_episodes`)."""
        text = self.table()
        for b in baselines:
            text += "\n\n" + self.paired_table(b)
        files = {"evaluate.csv": self.to_csv(), "evaluate.txt": text + "\n"}
        # always written (its header alone without baselines): a folder evaluated again
        # without --baseline keeps no earlier run's pairings for summarise to read back
        rows = [row for b in baselines for row in self.paired(b)]
        files["paired.csv"] = csv_text(rows) if rows else ",".join(PAIRED_COLUMNS) + "\r\n"
        return files


#: The columns of paired.csv (:meth:`Evaluation.paired`).
PAIRED_COLUMNS = (
    "policy",
    "baseline",
    "episodes",
    "diff_mean",
    "diff_ci95",
    "wins",
    "ties",
    "losses",
)

#: Columns every episodes.csv has (:meth:`Evaluation.episode_rows`); ``time_to_detection_s``,
#: ``steps`` and ``random_prior`` came later and are optional when reading.
EPISODE_COLUMNS = (
    "policy", "seed", "posc", "bound", "bound_reach", "normalised", "detected",
    "violation_steps", "crashed", "landed",
)  # fmt: skip
#: Largest episodes.csv :func:`read_episodes` reads (about 100 bytes a row).
MAX_EPISODES_CSV_BYTES = 64 * 2**20


def read_episodes(
    path: str | os.PathLike[str], time_to_detection_min: dict[str, float | None] | None = None
) -> Evaluation:
    """The :class:`Evaluation` an ``episodes.csv`` records (its policies in order of first
    appearance, the bounds as :func:`evaluate` computes them), whose summary equals the one
    ``evaluate`` wrote beside it. The episodes' POSC curves are not in the file (the figure
    cannot be redrawn from it). An older file without ``time_to_detection_s`` needs the
    per-policy means ``time_to_detection_min`` (else they are reported as unknown); without
    ``random_prior`` the priors count as random when the episodes' bounds differ.

    Raises
    ------
    ConfigError
        Field ``episodes`` for a missing, unreadable or oversized file, a missing column, a
        value that is not what its column holds, or a policy with other seeds than the first.
    """
    import csv
    import io

    from poc_env.errors import as_number

    where = os.fspath(path)
    try:
        size = os.path.getsize(where)
        if size > MAX_EPISODES_CSV_BYTES:
            raise ConfigError("episodes", where, f"an episodes.csv of at most "
                              f"{MAX_EPISODES_CSV_BYTES} bytes (this one: {size})")  # fmt: skip
        with open(where, encoding="utf-8", newline="") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as err:
        why = getattr(err, "strerror", None) or "not UTF-8 text"
        raise ConfigError(
            "episodes", where, f"an episodes.csv of poc-env evaluate ({why})"
        ) from None
    try:
        rows = list(csv.DictReader(io.StringIO(text)))
    except csv.Error as err:  # a field past csv's size limit, a NUL byte, ...
        raise ConfigError(
            "episodes", where, f"an episodes.csv of poc-env evaluate ({err})"
        ) from None
    if not rows:
        raise ConfigError("episodes", where, "an episodes.csv with a header and episode rows")
    missing = [c for c in EPISODE_COLUMNS if c not in rows[0]]
    if missing:
        columns = ", ".join(EPISODE_COLUMNS)
        allowed = f"an episodes.csv with the columns {columns} (missing: {', '.join(missing)})"
        raise ConfigError("episodes", where, allowed)

    def cell(i: int, col: str, kind: str) -> Any:
        value = rows[i].get(col)
        field = f"episodes.csv row {i + 1} {col}"
        if kind == "bool":
            if value not in ("True", "False"):
                raise ConfigError(field, value, "True or False")
            return value == "True"
        if value in ("", None) and kind == "float?":
            return None
        try:
            number = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ConfigError(field, value, "a number") from None
        if kind == "int":
            return as_int(field, number, 0, limits.MAX_SEED)
        if col == "time_to_detection_s":
            return as_number(field, number, 0.0, 1e12)
        return as_number(field, number, 0.0, 1.0)  # POSC and its bounds: probabilities

    episodes = []
    has_ttd = "time_to_detection_s" in rows[0]
    has_rule = "bound_rule" in rows[0]  # written since the rule-aware bound (issue 24)
    has_moving = "bound_moving" in rows[0]  # since the moving-target bound (issue 25)
    for i, r in enumerate(rows):
        if not r.get("policy"):
            raise ConfigError(f"episodes.csv row {i + 1} policy", r.get("policy"), "a policy name")
        episodes.append(
            Episode(
                policy=r["policy"],
                seed=cell(i, "seed", "int"),
                posc=cell(i, "posc", "float"),
                detected=cell(i, "detected", "bool"),
                time_to_detection_s=cell(i, "time_to_detection_s", "float?") if has_ttd else None,
                violation_steps=cell(i, "violation_steps", "int"),
                crashed=cell(i, "crashed", "int"),
                landed=cell(i, "landed", "int"),
                steps=cell(i, "steps", "int") if "steps" in rows[0] else -1,
                posc_curve=(),
                bound=cell(i, "bound", "float"),
                bound_reach=cell(i, "bound_reach", "float?"),
                bound_rule=cell(i, "bound_rule", "float?") if has_rule else None,
                bound_moving=cell(i, "bound_moving", "float?") if has_moving else None,
            )
        )
    policies = tuple(dict.fromkeys(e.policy for e in episodes))
    seeds = [e.seed for e in episodes if e.policy == policies[0]]
    for p in policies:  # every policy flew the same seeds, in the same order (evaluate's)
        if [e.seed for e in episodes if e.policy == p] != seeds:
            raise ConfigError("episodes", where, f"every policy on the seeds of {policies[0]!r} "
                              f"({len(seeds)} episodes); {p!r} has others")  # fmt: skip
    first = [e for e in episodes if e.policy == policies[0]]
    if "random_prior" in rows[0]:
        random_priors = cell(0, "random_prior", "bool")
    else:
        random_priors = len({e.bound for e in first}) > 1
    if random_priors:  # as evaluate: the mean over the first policy's episodes (same seeds)
        bound = float(np.mean([float(e.bound or 0.0) for e in first]))
        reach: float | None = float(np.mean([float(e.bound_reach or 0.0) for e in first]))
        rule: float | None = (
            float(np.mean([float(e.bound_rule or 0.0) for e in first])) if has_rule else None
        )
    else:
        bound, reach = float(first[0].bound or 0.0), first[0].bound_reach
        rule = first[0].bound_rule
    if not has_ttd and time_to_detection_min is not None:
        time_to_detection_min = {p: time_to_detection_min.get(p) for p in policies}
    elif not has_ttd:
        time_to_detection_min = dict.fromkeys(policies)
    else:
        time_to_detection_min = None
    name = Path(where).parent.name
    return Evaluation(name, tuple(episodes), bound, policies, random_priors, reach,
                      time_to_detection_min=time_to_detection_min, bound_rule=rule)  # fmt: skip


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
    ``seed``: its prior and its uniform velocity (the gridded field, if any, from the
    scenario), read from an environment reset with the seed; None when the target stands
    still."""
    from poc_env.envs.parallel import UAVSearchParallelEnv
    from poc_env.theory.moving_bound import moving_bound

    env = UAVSearchParallelEnv(scenario=scenario, map_file=map_file)
    if env.params.motion is None:
        return None
    prior = episode_prior(env.scenario, seed) if random_priors else None
    env.reset(seed=seed, options=None if prior is None else {"prior": prior})
    st = env.sim_state
    assert st.drift is not None
    side = None if st.leeway_side is None else float(st.leeway_side[0])
    return moving_bound(env.scenario, st.belief[0], st.drift[0], env.params.s, side=side).upper


def _moving(args):
    return moving_effort_bound(*args)


def _scenario_and_prior(scenario: Any, map_file: str | None, prior: np.ndarray | None):
    """The resolved scenario and the prior a bound is computed on: ``prior``, else the
    scenario's prior or ``map_file``."""
    from poc_env.config import load_scenario
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario(scenario)
    return sc, (build_prior(sc.map, map_file) if prior is None else prior)


def effort_bound(
    scenario: Any, map_file: str | None = None, prior: np.ndarray | None = None
) -> float:
    """Plain physical optimum for every UAV sweeping at ``max_speed`` for as long as the
    environment lets it sense (:func:`poc_env.theory.bound.honest_optimum`), on ``prior``
    (default: the scenario's prior or ``map_file``)."""
    from poc_env.theory.bound import honest_optimum

    return honest_optimum(*_scenario_and_prior(scenario, map_file, prior)).pos


def reach_effort_bound(
    scenario: Any, map_file: str | None = None, prior: np.ndarray | None = None
) -> float:
    """Reach-aware bound (:func:`poc_env.theory.bound.reach_bound`, its certified upper value)
    on ``prior`` (default: the scenario's prior or ``map_file``)."""
    from poc_env.theory.bound import reach_bound

    return reach_bound(*_scenario_and_prior(scenario, map_file, prior)).upper


def rule_effort_bound(
    scenario: Any, map_file: str | None = None, prior: np.ndarray | None = None
) -> float:
    """Rule-aware bound (:func:`poc_env.theory.bound.rule_bound`, its certified upper value)
    on ``prior`` (default: the scenario's prior or ``map_file``)."""
    from poc_env.theory.bound import rule_bound

    return rule_bound(*_scenario_and_prior(scenario, map_file, prior)).upper


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
        rule = float(np.mean([float(e.bound_rule or 0.0) for e in results[:episodes]]))
    else:
        bound = effort_bound(sc, map_file)
        reach = reach_effort_bound(sc, map_file)
        rule = rule_effort_bound(sc, map_file)
        results = tuple(
            replace(e, bound=bound, bound_reach=reach, bound_rule=rule) for e in results
        )
    seeds = [(sc, seed0 + k, map_file, random_priors) for k in range(episodes)]
    if sc.target.model != "static":  # the moving-target bound of each seed's episode
        moving = dict(zip(range(seed0, seed0 + episodes), run_jobs(_moving, seeds, workers)))
        results = tuple(replace(e, bound_moving=moving[e.seed]) for e in results)
    return Evaluation(
        sc.name, results, bound, tuple(policies), random_priors, reach, bound_rule=rule
    )


def plot_curves(ev: Evaluation, path: str | os.PathLike[str], dt_s: float) -> Path:
    """POSC over time per policy (mean over episodes, shaded Student's t 95 % band)."""
    from poc_env.viz.plots import _figure, save_figure_atomic

    fig = _figure((7.0, 4.5))
    ax = fig.add_subplot()
    for p in ev.policies:
        curves = [e.posc_curve for e in ev.episodes if e.policy == p]
        n = max(len(c) for c in curves)
        arr = np.array([list(c) + [c[-1]] * (n - len(c)) for c in curves])
        t = (np.arange(n) + 1) * dt_s / 60
        m = arr.mean(axis=0)
        h = ci95(arr, axis=0)
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
