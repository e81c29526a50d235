"""The ``poc-env`` command line.

Subcommands: ``scenarios`` (list the built-ins), ``survey`` (Table 4 / 5 analog of a region
plan), ``figures`` (regenerate the docs' pictures), ``demo`` (the main job on the default
scenario), ``train`` (PPO; options generated from ``poc_env.agents.rl.args.TrainArgs``). Bad input
ends with ``error: ...`` naming the field, the value and what is allowed, and exit status 2 -- never
a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import os
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

import numpy as np

import poc_env.limits as limits
from poc_env.errors import (
    EXTRA_MODULES,
    ConfigError,
    MissingExtraError,
    PocEnvError,
    as_int,
    has_extra,
    require_extra,
    say_warning,
    skipped_for_extra,
)
from poc_env.helptext import examples, use_everywhere, walk
from poc_env.io import check_distinct
from poc_env.io import check_out as _check_out

#: Optional dependencies and the extra that installs each (pyproject.toml).
_EXTRA_OF = {
    "torch": "rl",
    "stable_baselines3": "rl",
    "tensorboard": "rl",
    "ray": "rllib",
    "matplotlib": "plot",
    "PIL": "plot",
}

#: Option values that may start with ``-`` (``--origin -45,7``: a negative latitude).
_NEGATIVE_VALUE_OPTIONS = ("--origin",)


def _check_int(field: str, value: int | None, lo: int, hi: int | None = None) -> None:
    """Raise ConfigError unless ``value`` (None: the default) is an integer in [lo, hi]."""
    if value is not None:
        as_int(field, value, lo, hi)


def _check_baselines(baselines: list[str], policies: list[str], where: str) -> None:
    """ConfigError naming ``baseline`` unless each baseline is one of ``policies`` and there is
    another policy to pair with it (a lone baseline left the paired table empty, and writing it
    failed after every episode had flown)."""
    for b in baselines:
        if b not in policies:
            raise ConfigError("baseline", b, f"one or more of {where}: " + ", ".join(policies))
        if len(policies) < 2:
            raise ConfigError(
                "baseline", b, f"a policy of {where} with at least one other policy to pair with"
            )


_STAGED: list[tuple[Path, list[Callable[[], object]]]] = []
"""The staging folders of the open :func:`_output_folder` blocks (innermost last), each with
what :func:`_once_in_place` holds back until its files are in place (``wrote PATH`` lines, a
file written beside the folder)."""


@contextlib.contextmanager
def _output_folder(field: str, path: str | os.PathLike[str]) -> Iterator[Path]:
    """:func:`poc_env.io.atomic_dir` with file-system errors reported as ``field`` errors.

    The ``wrote PATH`` lines of the files staged in the block are printed (and the outputs
    written beside the folder, such as ``survey --plan-out``, are written) once they are in
    place: a run refused at the end (or interrupted) writes and says nothing.
    """
    from poc_env.io import atomic_dir

    try:
        stage_cm = atomic_dir(path, field)
        stage = stage_cm.__enter__()
    except OSError as err:
        raise ConfigError(
            field, os.fspath(path), f"a folder poc-env can write ({err.strerror})"
        ) from None
    entry: tuple[Path, list[Callable[[], object]]] = (stage, [])
    _STAGED.append(entry)
    try:
        try:
            yield stage
        except BaseException:
            if not stage_cm.__exit__(*sys.exc_info()):
                raise
        else:
            try:
                stage_cm.__exit__(None, None, None)
            except OSError as err:
                raise ConfigError(
                    field, os.fspath(path), f"a folder poc-env can write ({err.strerror})"
                ) from None
            for then in entry[1]:
                then()
    finally:
        _STAGED.remove(entry)


def _wrote(paths, stage: Path | None = None, dest: Path | None = None) -> None:
    """Print ``wrote PATH`` for each path, as it will be named once ``stage`` is ``dest``.

    A ``stage`` inside an open :func:`_output_folder` block: the lines wait for its end.
    """
    lines = []
    for p in paths:
        if stage is not None and dest is not None:
            p = dest / Path(p).relative_to(stage)
        lines.append(f"wrote {p}")
    _say(lines, stage)


def _say(lines: list[str], where: Path | None) -> None:
    """Print ``lines`` about files written at ``where``, once they are in place."""
    _once_in_place(where, lambda: print(*lines, sep="\n") if lines else None)


def _once_in_place(where: Path | None, then: Callable[[], object]) -> None:
    """Call ``then`` now or, ``where`` inside an open :func:`_output_folder` block, once that
    block's files are in place (never, if they are not)."""
    inside = Path(where) if where is not None else None
    for root, pending in reversed(_STAGED):
        if inside is not None and (inside == root or root in inside.parents):
            pending.append(then)
            return
    then()


def _add_gain_per_hour(p: argparse.ArgumentParser) -> None:
    """``--gain-per-hour``, ``plan``'s and ``replan``'s (checked by
    :func:`_check_gain_per_hour`)."""
    p.add_argument(
        "--gain-per-hour",
        type=float,
        default=None,
        metavar="G",
        help="allocation planner: a UAV flies only if its route adds at least G of the prior's "
        "mass per flight hour to POS_C (its marginal POS over its eq. 17 hours); the others stay "
        "home, longest flight first, each against the plan left by the ones before, so the "
        "plan gives up less than G x the hours saved. Default 1e-4 (0.01 %% per aircraft-hour); "
        "0: every route flies; at most 0.01 (docs/PLANNER.md, 'A floor per flight hour')",
    )


def _check_gain_per_hour(args: argparse.Namespace) -> None:
    """Refuse a bad ``--gain-per-hour`` (with ``--effort``'s options) before any planning,
    naming the option (:func:`poc_env.agents.planning.planner.plan_options`)."""
    if args.gain_per_hour is not None:
        from poc_env.agents.planning.planner import plan_options

        plan_options(args.effort, args.gain_per_hour)


def _add_projection(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--projection",
        default="aeqd",
        help="aeqd (azimuthal equidistant at the origin) or utm",
    )
    p.add_argument("--utm-zone", type=int, default=None, help="UTM zone (default: the origin's)")


def _add_overrides(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--overrides",
        nargs="+",
        default=None,
        metavar="KEY=VALUE",
        help="scenario keys to change, YAML values (e.g. sensor.sweep_width_km=4 "
        "episode.horizon_steps=50)",
    )


def _add_scenario(p: argparse.ArgumentParser, default: str | None) -> None:
    p.add_argument("--scenario", default=default, help="built-in name or YAML path")
    _add_overrides(p)
    p.add_argument("--map", dest="map_file", default=None, help="prior map (.npy or .csv)")


def cmd_scenarios(args: argparse.Namespace) -> int:
    from poc_env.config import builtin_scenarios, load_scenario

    for name in builtin_scenarios():
        sc = load_scenario(name)
        print(
            f"{name:<12} {sc.map.width_m / 1e3:g} x {sc.map.height_m / 1e3:g} km, "
            f"{sc.map.nx} x {sc.map.ny} cells, {sc.n_uavs} UAVs -- {sc.description}"
        )
    return 0


def cmd_policies(args: argparse.Namespace) -> int:
    """Every registered policy as ``evaluate --policies`` spells it, with what it does."""
    from poc_env.agents.policies.registry import registered, shipped, spec

    width = max(len(p) for p in registered())
    for spelling in registered():
        s = spec(spelling)
        what = s.summary
        if s.argument is not None:
            what += f"; {spelling.partition(':')[2]}: {s.argument_help or s.argument}"
        print(f"{spelling:<{width}}  {what}")
    print(
        "\nshipped checkpoints and chooser models (ppo: the rl extra flies them; rllib: the "
        "rllib extra; plan_choice, receding_choice: none):"
    )
    print("\n".join(f"  {n}" for n in shipped()))
    return 0


def cmd_tasks(args: argparse.Namespace) -> int:
    from poc_env.tasks import task_table

    rows = task_table()
    width = max(len(r["id"]) for r in rows)
    print(
        f"{'task':<{width}}  {'scenario':<10} {'control':<10} prior   UAVs  horizon  "
        f"{'obs':<8} target"
    )
    for r in rows:
        prior = "random" if r["random_prior"] else "fixed "
        print(
            f"{r['id']:<{width}}  {r['scenario']:<10} {r['control']:<10} {prior}  "
            f"{r['n_uavs']:>4}  {r['horizon_steps']:>7}  {r['obs']:<8} {r['motion']}"
        )
    return 0


def cmd_record(args: argparse.Namespace) -> int:
    from poc_env.recorded import main_args

    return main_args(args)


def cmd_spec(args: argparse.Namespace) -> int:
    from poc_env.spec import main_args

    return main_args(args)


def _check_crs_options(args: argparse.Namespace, recorded_in: str | None = None) -> None:
    """``--projection`` and ``--utm-zone`` shape the crs made at ``--origin``: without an
    origin they would be ignored, and so would ``--origin`` itself without the output that
    records it (``recorded_in``, an option such as ``plan_out``, when one is needed)."""
    if args.origin is None:
        why = ("without it the crs is the scenario's own map.projection at map.origin_deg, if it "
               "records one")  # fmt: skip
        if args.projection != "aeqd":
            raise ConfigError("projection", args.projection, f"only with --origin ({why})")
        if args.utm_zone is not None:
            raise ConfigError("utm_zone", args.utm_zone, f"only with --origin ({why})")
    elif recorded_in is not None and getattr(args, recorded_in) is None:
        option = "--" + recorded_in.replace("_", "-")
        raise ConfigError("origin", args.origin, f"only with {option} (the file that records "
                          "the crs; nothing else uses it)")  # fmt: skip


def cmd_survey(args: argparse.Namespace) -> int:
    _check_out("out", args.out, "folder")
    _check_out("plan_out", args.plan_out, "file")
    _check_crs_options(args, "plan_out")
    from poc_env.agents.planning.survey import SURVEY_FILES

    written = [Path(args.out) / n for n in SURVEY_FILES] if args.out else None
    check_distinct({"out": written, "plan_out": args.plan_out}, _inputs_of(args))
    if args.origin is not None:
        from poc_env.agents.mission.crs import make_crs

        make_crs(args.projection, args.origin, zone=args.utm_zone)  # checked before the survey
    if not args.out:
        return _survey(args, None, None)
    with _output_folder("out", args.out) as stage:
        return _survey(args, stage, Path(args.out))


def _survey(args: argparse.Namespace, stage: Path | None, dest: Path | None) -> int:
    """The survey of ``cmd_survey``, its files written into ``stage`` (shown as ``dest``)."""
    from poc_env.agents.mission.plan import check_map_option, map_source
    from poc_env.agents.planning.survey import load_regions, run_survey, write_survey
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.theory.probability_map import build_prior

    sc = load_scenario(args.scenario, parse_overrides(args.overrides or []))
    check_map_option(sc, args.map_file)
    plan = load_regions(args.regions or f"{sc.name}_polygons")
    prior = build_prior(sc.map, args.map_file)
    if getattr(args, "optimise", False):
        from poc_env.agents.planning.region_planner import optimise_regions

        plan = optimise_regions(sc, plan)
        print("Spacing and direction optimised per region (Table 3 analog):")
        for r in plan.regions:
            print(
                f"  {r.id}: {r.pattern:<16} S = {r.spacing_m / 1e3:6.2f} km, "
                f"direction {np.degrees(r.direction_rad):5.1f} deg"
            )
    result = run_survey(sc, plan, prior=prior)
    print(
        f"Survey of {plan.name} on {sc.name} (W = {sc.sensor.sweep_width_m / 1e3:g} km, "
        f"law {sc.sensor.law}, usable endurance {sc.uav.usable_endurance_s / 3600:.2f} h)"
    )
    print(result.table())
    from poc_env.agents.planning.planner import moving_target_warning

    if (warning := moving_target_warning(sc)) is not None:
        say_warning(warning)
    if stage is not None:
        figure = has_extra("plot")  # the tables still, the figure not
        if not figure:
            print(skipped_for_extra("plot", "survey.png"))
        shown = prior if figure else None
        _wrote(write_survey(result, stage, prior=shown, scenario=sc, plan=plan), stage, dest)
    if getattr(args, "plan_out", None):
        from poc_env.agents.mission.plan import with_scenario_file, write_plan
        from poc_env.agents.planning.survey import survey_plan

        doc = survey_plan(
            result,
            sc,
            plan,
            prior,
            map_source=map_source(sc, args.map_file),
            origin_deg=args.origin,
            projection=args.projection,
            zone=args.utm_zone,
        )
        doc = with_scenario_file(doc, args.scenario)
        _once_in_place(stage, lambda: print(f"wrote {write_plan(doc, args.plan_out)}"))
    return 0


def _state_policy(scenario, name: str, seed: int):
    """A registered policy (``poc_env.agents.policies.registry``) as ``policy_fn(state, rng)`` for
    :func:`~poc_env.viz.rendering.render_episode`.

    The policy is reset with an environment reset by ``seed``, whose state is the rendered
    episode's first state (both start from ``default_rng(seed)``); then each step it gets the
    rendered state's observations of the flying UAVs, built by the environment's engine
    (:meth:`poc_env.sim.engine.Engine.observe_state`). Its own generators come from ``seed``:
    ``rng`` is not used.
    """
    from poc_env.agents.policies.registry import make_policy
    from poc_env.envs.parallel import UAVSearchParallelEnv

    policy = make_policy(name)
    env = UAVSearchParallelEnv(scenario)
    agents = env.possible_agents
    started = False

    def policy_fn(state, rng):
        nonlocal started
        if not started or int(state.step[0]) == 0:
            env.reset(seed=seed)
            policy.reset(env, seed)
            started = True
        obs = env.engine.observe_state(state)
        ras, vec = obs["raster"][0], obs["vector"][0]
        flying = state.flying[0]
        acts, _ = policy.predict(
            {a: {"raster": ras[i], "vector": vec[i]} for i, a in enumerate(agents) if flying[i]}
        )
        out = np.zeros((1, len(agents), 3))
        for i, a in enumerate(agents):
            if a in acts:
                out[0, i] = acts[a]
        return out

    return policy_fn


def cmd_render(args: argparse.Namespace) -> int:
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.viz.rendering import render_episode

    _check_int("seed", args.seed, 0, limits.MAX_SEED)
    _check_int("max_steps", args.max_steps, 1, limits.MAX_STEPS)
    _check_int("every", args.every, 1, limits.MAX_STEPS)
    _check_out("out", args.out, "file")
    sc = load_scenario(args.scenario, parse_overrides(args.overrides or []))
    _check_render_frames(args, sc)
    path = render_episode(
        sc,
        _state_policy(sc, args.policy, args.seed),
        args.out,
        seed=args.seed,
        max_steps=args.max_steps,
        every=args.every,
    )
    print(f"wrote {path}")
    return 0


#: Bytes of one rendered frame held until the GIF is written: 640 x 480 RGBA pixels (the
#: renderer's default figure) plus the palette image the GIF writer makes of it.
_FRAME_BYTES = 640 * 480 * 5


def _check_render_frames(args: argparse.Namespace, sc) -> None:
    """The frames ``render`` would hold fit the memory guard: the episode ends at its horizon,
    so ``--max-steps`` beyond it costs nothing, but a horizon of 10^7 steps drawn every step
    is ten million frames (tens of TB) -- refused up front, naming the field."""
    steps = min(sc.horizon_steps, args.max_steps or sc.horizon_steps)
    frames = steps // args.every + 2
    field, value = (
        ("every", args.every) if args.max_steps is None else ("max_steps", args.max_steps)
    )
    limits.check_memory(
        field, value, float(frames) * _FRAME_BYTES,
        f"animation ({frames:,} frames of 640 x 480; raise --every or lower --max-steps)",
    )  # fmt: skip


#: ``poc-env bench WHAT``: the module each benchmark runs (``python -m``); each has ``main`` and
#: ``build_parser`` (its ``--help``).
BENCHMARKS = {
    "env": "poc_env.agents.benchmarks.env",
    "plan": "poc_env.agents.benchmarks.plan",
    "train": "poc_env.agents.benchmarks.train",
    "campaign": "poc_env.agents.testing.campaign",
    "baselines": "poc_env.agents.benchmarks.baselines",
    "suite": "poc_env.agents.benchmarks.suite",
    "learning": "poc_env.agents.benchmarks.learning",
    "generalise": "poc_env.agents.benchmarks.generalise",
    "peers": "poc_env.agents.benchmarks.peers",
    "moving-bound": "poc_env.agents.benchmarks.moving_bound",
}


def cmd_bench(args: argparse.Namespace) -> int:
    """Run a benchmark in a fresh interpreter, so one-thread settings precede numpy's import.

    On Linux the benchmark dies with ``poc-env`` (:func:`_die_with_parent`): a SIGKILL or
    SIGTERM of the command (a scheduler ending the job) left it running on, orphaned, writing
    its ``--out`` folder after the kill.
    """
    import os
    import subprocess

    modules = BENCHMARKS
    env = dict(os.environ, OMP_NUM_THREADS="1", NUMBA_NUM_THREADS="1", MKL_NUM_THREADS="1")
    cmd = [sys.executable, "-m", modules[args.what], *args.rest]
    if not sys.platform.startswith("linux"):
        return subprocess.call(cmd, env=env)
    parent = os.getpid()
    return subprocess.call(cmd, env=env, preexec_fn=lambda: _die_with_parent(parent))


def _die_with_parent(parent: int) -> None:
    """In a child process (before it runs its program): ask Linux for SIGTERM when the parent
    dies (``prctl(PR_SET_PDEATHSIG)``), and end now if the parent ``parent`` is already gone."""
    import signal

    from poc_env.proc import die_with_parent

    die_with_parent(signal.SIGTERM)
    if os.getppid() != parent:  # died before the request took effect
        os._exit(143)


def cmd_evaluate(args: argparse.Namespace) -> int:
    _check_int("seed", args.seed, 0, limits.MAX_SEED)
    _check_int("episodes", args.episodes, 1, limits.MAX_EPISODES)
    _check_int("workers", args.workers, 1, limits.MAX_WORKERS)
    names = [p.strip() for p in args.policies.split(",") if p.strip()]
    if not names:
        from poc_env.agents.policies.registry import registered

        allowed = "a comma-separated list of registered policies: " + ", ".join(registered())
        raise ConfigError("policies", args.policies, allowed)
    from poc_env.agents.experiments.evaluate import check_once

    check_once(names)  # before the output folder (a baseline's paired table failed on a repeat)
    _check_out("out", args.out, "folder")
    baselines = [b.strip() for b in (args.baseline or "").split(",") if b.strip()]
    _check_baselines(baselines, names, "--policies")
    args.baselines = baselines
    with _ray(args):
        if not args.out:
            return _evaluate(args, names, None, None)
        with _output_folder("out", args.out) as stage:
            return _evaluate(args, names, stage, Path(args.out))


def _ray(args: argparse.Namespace) -> contextlib.AbstractContextManager:
    """``--ray [ADDRESS]``: the command's jobs run on Ray
    (poc_env.agents.experiments.pool.ray_jobs)."""
    if getattr(args, "ray", None) is None:
        return contextlib.nullcontext()
    from poc_env.agents.experiments.pool import ray_jobs

    return ray_jobs(args.ray)


def _add_ray(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--ray",
        nargs="?",
        const="local",
        default=None,
        metavar="ADDRESS",
        help="run the episodes as Ray tasks: on a new local instance (no ADDRESS), or on the "
        "cluster at ADDRESS (host:port of a head node, ray://host:10001, auto); results equal "
        "--workers 1 for the same seeds. Needs the rllib extra",
    )


def _evaluate(
    args: argparse.Namespace, names: list[str], stage: Path | None, dest: Path | None
) -> int:
    """The evaluation of ``cmd_evaluate``, its files written into ``stage`` (shown as ``dest``)."""
    from poc_env.agents.experiments.evaluate import evaluate, plot_curves
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.io import write_text_atomic

    scenario, random_priors, label = args.scenario, args.random_priors, None
    if args.task is not None:  # the task's scenario and prior kind (poc_env.tasks)
        from poc_env.tasks import get_task

        task = get_task(args.task)
        if scenario is not None:
            raise ConfigError("task", args.task, "either --task or --scenario, not both")
        if random_priors and not task.random_prior:  # would print random priors' scores
            from poc_env.tasks import TASKS  # under a fixed-prior task's id

            sibling = [t for t in TASKS.values() if t.random_prior and t.kwargs == {
                **task.kwargs, "random_prior": True}]  # fmt: skip
            raise ConfigError(
                "random_priors", True, "not with --task: the id says whether its priors are "
                "random, and " + (f"{sibling[0].id} flies random ones" if sibling else
                f"{task.id} has no -Random- version"),
            )  # fmt: skip
        scenario, random_priors, label = task.scenario, task.random_prior, task.id
        if args.overrides:  # another MDP than the id's: said where the scores are printed
            label += f" with --overrides {' '.join(args.overrides)} (not the registered task)"
        from poc_env.agents.rl.policy import checkpoint_control, checkpoint_origin
        from poc_env.tasks import get_task as _task_of

        for name in names:  # a learned policy is scored on the control level it learned
            trained = checkpoint_control(name)
            if trained is not None and trained != task.control:
                raise ConfigError(
                    "policies", name, f"a checkpoint trained at the task's control level "
                    f"({task.control}); this one was trained at '{trained}'",
                )  # fmt: skip
            origin, recipe, also = checkpoint_origin(name)
            if origin is None and recipe in ("shared", "central"):
                raise ConfigError(
                    "policies", name, f"a checkpoint trained on the task's compass observation "
                    f"({task.id}); this one was trained with the '{recipe}' recipe's "
                    "observation (raster and vector)",
                )  # fmt: skip
            if task.id in {_task_of(t).id for t in also}:  # trained side by side with it
                print(f"note: {name} was trained on {_task_of(origin or also[0]).id}; "
                      f"{task.id} is one of its --also-task tasks")  # fmt: skip
            elif origin is not None and _task_of(origin).id != task.id:
                seen = _task_of(origin).obs  # the policy computes its own observation
                how = "same control level and observation" if seen == task.obs else (
                    f"same control level; the policy reads its own '{seen}' observation, "
                    f"not the task's '{task.obs}'"
                )  # fmt: skip
                print(f"note: {name} was trained on {_task_of(origin).id}; flown here on "
                      f"{task.id} (a transfer: {how})")  # fmt: skip
    if args.task is not None:  # with a fleet-size task's fleet
        sc = task.load_scenario(parse_overrides(args.overrides or []))
    else:
        sc = load_scenario(scenario or "paper_6_2", parse_overrides(args.overrides or []))
    from poc_env.agents.mission.plan import check_map_option

    check_map_option(sc, args.map_file)
    ev = evaluate(
        sc,
        names,
        episodes=args.episodes,
        seed0=args.seed,
        workers=args.workers,
        map_file=args.map_file,
        progress=not args.quiet,
        random_priors=random_priors,
    )
    priors = ", a fresh random prior per seed" if random_priors else ""
    print(
        f"{label or sc.name}: {args.episodes} episodes per policy, seeds {args.seed}.."
        f"{args.seed + args.episodes - 1}{priors}"
    )
    summary = ev.summary_files(getattr(args, "baselines", []))  # what summarise rewrites
    print(summary["evaluate.txt"], end="")
    if stage is not None:
        files = [write_text_atomic(stage / "episodes.csv", ev.episodes_csv())]
        files += [write_text_atomic(stage / name, text) for name, text in summary.items()]
        if has_extra("plot"):  # the tables never wait on, nor fail for, the figure
            files.append(plot_curves(ev, stage / "posc_over_time.png", sc.episode.dt_s))
        else:
            print(skipped_for_extra("plot", "posc_over_time.png"))
        _wrote(tuple(files), stage, dest)
    return 0


def cmd_summarise(args: argparse.Namespace) -> int:
    """Rewrite an evaluation folder's summary files from its episodes.csv, flying nothing."""
    import csv

    from poc_env.agents.experiments.evaluate import read_episodes
    from poc_env.io import write_text_atomic

    folder = Path(args.results_dir)
    if not (folder / "episodes.csv").is_file():
        raise ConfigError("results_dir", args.results_dir, "a folder of poc-env evaluate --out "
                          "holding episodes.csv")  # fmt: skip
    out = Path(args.out) if args.out else folder
    _check_out("out", out, "folder")
    old: dict[str, str] = {}  # the folder's evaluate.csv, for an older file's detection times
    paired_baselines: list[str] = []
    unreadable = (OSError, UnicodeDecodeError, csv.Error, KeyError)
    with contextlib.suppress(*unreadable), (folder / "evaluate.csv").open(encoding="utf-8") as f:
        old = {r["policy"]: r["time_to_detection_min"] for r in csv.DictReader(f)}
    with contextlib.suppress(*unreadable), (folder / "paired.csv").open(encoding="utf-8") as f:
        paired_baselines = list(dict.fromkeys(r["baseline"] for r in csv.DictReader(f)))
    ttd = {p: float(v) if v else None for p, v in old.items()} if old else None
    ev = read_episodes(folder / "episodes.csv", ttd)
    given = [b.strip() for b in (args.baseline or "").split(",") if b.strip()]
    baselines = given or [b for b in paired_baselines if b in ev.policies]
    _check_baselines(baselines, list(ev.policies), "the folder's policies")
    if ev.time_to_detection_min is not None:  # an episodes.csv of an older evaluate
        source = "the folder's evaluate.csv" if old else "unknown (no evaluate.csv)"
        print(f"note: episodes.csv has no time_to_detection_s column: t_det is {source}")
    summary = ev.summary_files(baselines)
    print(summary["evaluate.txt"], end="")
    with _output_folder("out", out) as stage:
        files = [write_text_atomic(stage / name, text) for name, text in summary.items()]
        _wrote(tuple(files), stage, out)
    return 0


def cmd_curve(args: argparse.Namespace) -> int:
    from poc_env.agents.rl.curve import plot_training_curve

    _check_int("until", args.until, 1, 2**53)
    _check_out("out", args.out, "file", ".png")
    print(f"wrote {plot_training_curve(args.run_dir, args.out, args.until)}")
    return 0


def cmd_experiment(args: argparse.Namespace) -> int:
    from poc_env.agents.experiments.paper import cmd

    _check_int("workers", args.workers, 1, limits.MAX_WORKERS)
    _check_out("out", args.out, "folder")
    with _ray(args):
        return cmd(args)


def cmd_train(args: argparse.Namespace) -> int:
    """Train (or resume) an RL policy; every option comes from
    ``poc_env.agents.rl.args.TrainArgs``."""
    from poc_env.agents.rl.args import parse_train_args
    from poc_env.agents.rl.train import train

    targs = parse_train_args(args.train_options)
    if targs.from_card is not None:
        from poc_env.agents.rl.args import load_card

        step = load_card(targs.from_card).get("model_step")
        shipped = "" if step is None else f"; the shipped model is its run's step {step:,}"
        print(f"recipe of {targs.from_card}'s card (options given here replace it{shipped})")
    _check_int("n_envs", targs.n_envs, 1, limits.N_ENVS_MAX)
    _check_out("run_dir", targs.run_dir, "folder")
    try:
        run = train(targs)
    except KeyboardInterrupt:
        return 130
    model = run / ("checkpoint" if targs.engine == "rllib" else "model.zip")
    print(f"wrote {model} (run folder {run})")
    return 0


def cmd_plan(args: argparse.Namespace) -> int:
    """The plan as plan.json (and ``--plot`` PNG): both written, or neither."""
    from poc_env.io import atomic_path

    _check_plan_args(args)
    if getattr(args, "fleet_sizes", None) is not None:
        return _plan_fleet_sizes(args)
    if args.plot:  # asked for: checked before the planning, not after
        require_extra("plot", "poc-env plan --plot", *EXTRA_MODULES["plot"])
    out = Path(args.out)
    if not args.plot:
        _say(_plan(args, out, None), out.parent)
        return 0
    with atomic_path(args.plot) as plot_tmp:  # published after plan.json, or not at all
        lines = _plan(args, out, plot_tmp, shown=(out, Path(args.plot)))
    _say(lines, out.parent)  # once both are in place
    return 0


def cmd_replan(args: argparse.Namespace) -> int:
    """The next sortie (:mod:`poc_env.agents.planning.replan`)."""
    from poc_env.agents.planning.replan import cli_main

    _check_int("seed", args.seed, 0, limits.MAX_SEED)
    _check_gain_per_hour(args)  # before the sweep and the planning, as plan checks it
    _check_out("out", args.out, "file")
    check_distinct({"out": args.out}, _inputs_of(args))
    return cli_main(args)


def _check_plan_args(args: argparse.Namespace) -> None:
    _check_int("seed", args.seed, 0, limits.MAX_SEED)
    _check_int("uavs", args.uavs, 1, 64)
    _check_int("popsize", args.popsize, 4, limits.POPSIZE_MAX)
    _check_int("maxiter", args.maxiter, 1, limits.MAXITER_MAX)
    _check_gain_per_hour(args)
    _check_out("out", args.out, "file")
    _check_out("plot", args.plot, "file", ".png")
    check_distinct({"out": args.out, "plot": args.plot}, _inputs_of(args))
    _check_crs_options(args)


def _inputs_of(args: argparse.Namespace) -> dict[str, str | list | None]:
    """The input files a command line names (for :func:`poc_env.io.check_distinct`), by
    option."""
    return {n: getattr(args, d) for n, d in _INPUTS.items() if getattr(args, d, None) is not None}


#: The options that name input files (option -> its ``args`` attribute): every command's, and
#: ``scenario import``'s layers.
_INPUTS = {"scenario": "scenario", "map": "map_file", "regions": "regions", "plan": "plan",
           "tracks": "tracks", "area": "area", "prior": "prior", "airfields": "airfields",
           "no_fly": "no_fly", "dem": "dem", "particles": "particles"}  # fmt: skip


def _check_inputs(args: argparse.Namespace) -> None:
    """Refuse, before the command runs, an input file that exists but cannot be read as one
    (:func:`poc_env.io.check_input_file`): a FIFO or a device (a read would block: ``replan
    --tracks`` on a FIFO never ended), or no permission; named by its option. A missing path is
    left to the command, and so is a folder (a built-in scenario's or region plan's name may
    be a folder's in the working directory)."""
    from poc_env.io import check_input_file

    for field in _INPUTS.values():  # named as the rest of the command line names them
        value = getattr(args, field, None)
        for v in value if isinstance(value, list) else [value]:
            if isinstance(v, str) and v:
                check_input_file(field, v, "a file poc-env can read", strict=False)


def _plan(
    args: argparse.Namespace,
    out: Path,
    plot: Path | None,
    shown: tuple[Path, Path | None] | None = None,
) -> list[str]:
    """Optimise the plan; draw it to ``plot`` (if any), then write plan.json to ``out``.

    Returns the ``wrote`` lines for the caller to say once the files are in place; ``shown``:
    the names they give for ``out`` and ``plot`` (where they will be once published).
    """
    from poc_env.agents.mission.plan import map_source, with_scenario_file, write_plan
    from poc_env.agents.planning.planner import make_plan, plan_table, plot_plan

    sc, prior = _plan_inputs(args)
    planner = getattr(args, "planner", "de")
    plan = make_plan(
        sc,
        prior=prior,
        map_source=map_source(sc, args.map_file),
        optimizer=args.optimizer or "adaptive_de",
        seed=args.seed,
        popsize=args.popsize,
        maxiter=args.maxiter,
        progress=not args.quiet,
        origin_deg=args.origin,
        projection=args.projection,
        zone=args.utm_zone,
        preset=args.preset or "paper",
        planner=planner,
        speed=getattr(args, "speed", None),
        refine=getattr(args, "refine", None),
        effort=getattr(args, "effort", None),
        gain_per_hour=getattr(args, "gain_per_hour", None),
    )
    _spill_bound(args, plan, sc, prior)
    print(plan_table(plan))
    _plan_notes(args, [("", plan)], sc)
    if plot is not None:
        plot_plan(plan, sc, prior, plot)
    write_plan(with_scenario_file(plan, args.scenario), out)
    shown_out, shown_plot = shown or (out, plot)
    return [f"wrote {shown_out}"] + ([f"wrote {shown_plot}"] if plot is not None else [])


def _plan_inputs(args: argparse.Namespace) -> tuple:
    """The scenario (its fleet ``--uavs`` UAVs, if given) and prior of a ``plan`` command
    line, after refusing the options that do not go together: ``--uavs`` (or
    ``--fleet-sizes``) with ``--overrides fleet...``, the optimiser's options with the
    allocation planner."""
    from poc_env.agents.mission.plan import check_map_option
    from poc_env.config import load_scenario, parse_overrides
    from poc_env.theory.probability_map import build_prior

    overrides = parse_overrides(args.overrides or [])
    sizes = getattr(args, "fleet_sizes", None)
    for name, value in (("uavs", args.uavs), ("fleet_sizes", sizes)):
        if value is not None and any(k.split(".")[0] == "fleet" for k in overrides):
            option = "--" + name.replace("_", "-")
            raise ConfigError(
                name, value, f"either {option} or --overrides fleet..., not both ({option} "
                "replaces the fleet)",
            )  # fmt: skip
    planner = getattr(args, "planner", "de")
    if planner == "allocation":  # the optimiser's options do not apply to it
        for name in ("optimizer", "preset", "popsize", "maxiter"):
            if getattr(args, name, None) is not None:
                raise ConfigError(
                    name, getattr(args, name), "only with --planner de (the allocation "
                    "planner has no optimiser: leave it out)",
                )  # fmt: skip
    sc = load_scenario(args.scenario, overrides)
    if args.uavs is not None:
        sc = sc.with_uavs(args.uavs)
    check_map_option(sc, args.map_file)
    return sc, build_prior(sc.map, args.map_file)


def _spill_bound(args: argparse.Namespace, plan: dict, sc, prior) -> None:
    """``--spill-bound``: the spill-charged bound (docs/PLANNER.md, i24-spill; a linear
    program) recorded in ``plan`` as ``bound_spill``."""
    if getattr(args, "spill_bound", False) and plan.get("bound_rule"):
        from poc_env.agents.planning.geography import probability
        from poc_env.theory.spill_bound import spill_bound

        plan["bound_spill"] = probability(spill_bound(sc, prior).upper)


def _plan_notes(args: argparse.Namespace, plans: list[tuple[str, dict]], sc) -> None:
    """Print what the plans' table leaves out: per plan (``(label, plan)``, the label put
    before its line) the effort level's skipped or stopped polish; once, the scenario's
    warnings (a moving target, a coarse lattice)."""
    from poc_env.agents.planning.planner import lattice_warning, moving_target_warning

    for label, plan in plans:
        skipped = effort_skip_note(plan, getattr(args, "effort", None))
        if skipped is not None:
            print(f"{label}{skipped}")
    for warning in (moving_target_warning(sc), lattice_warning(sc)):
        if warning is not None:
            say_warning(warning)


#: The most UAVs a fleet size of ``plan --fleet-sizes`` may have (``--uavs``'s and
#: :func:`~poc_env.agents.planning.allocation.plan_fleets`'s limit).
MAX_FLEET = 64


def fleet_sizes(text: str) -> list[int]:
    """``plan --fleet-sizes``'s ``N[,N...]``: the fleet sizes, each in [1, :data:`MAX_FLEET`],
    strictly increasing (a size given twice or out of order is a typo, not a request).

    Raises
    ------
    ConfigError
        Naming ``fleet_sizes[i]`` (a bad entry) or ``fleet_sizes`` (the order).
    """
    tokens = [t.strip() for t in str(text).split(",")]
    sizes = []
    for i, t in enumerate(tokens):
        value: int | str = t  # not a whole number: named by as_int with what is allowed
        with contextlib.suppress(ValueError):
            value = int(t)
        sizes.append(as_int(f"fleet_sizes[{i}]", value, 1, MAX_FLEET))
    if any(b <= a for a, b in itertools.pairwise(sizes)):
        raise ConfigError(
            "fleet_sizes", text, f"fleet sizes in increasing order, each in [1, {MAX_FLEET}], "
            "comma-separated (e.g. 6,12,24)",
        )  # fmt: skip
    return sizes


def fleet_plan_path(out: str | os.PathLike[str], n: int) -> Path:
    """Where ``plan --fleet-sizes`` writes the plan of ``n`` UAVs: beside ``out``, its name
    with ``_n<n>`` before the suffix (``out/plan.json`` -> ``out/plan_n12.json``).

    Raises
    ------
    ConfigError
        Naming ``out`` if the name would not be a plain file name in ``out``'s folder.
    """
    out = Path(out)
    name = f"{out.stem}_n{as_int('uavs', n, 1, MAX_FLEET)}{out.suffix}"
    if not out.name or Path(name).name != name or name in (".", ".."):
        raise ConfigError("out", os.fspath(out), "a file name (plan.json): --fleet-sizes "
                          "writes NAME_nN.json beside it for each size")  # fmt: skip
    return out.parent / name


def _plan_fleet_sizes(args: argparse.Namespace) -> int:
    """``plan --fleet-sizes``: the allocation plans of each fleet size, each planned on the
    one before (:func:`~poc_env.agents.planning.allocation.plan_fleets`: POS_C non-decreasing
    in the fleet), one plan file per size beside ``--out`` (:func:`fleet_plan_path`), all
    written or none, and one table of the sizes."""
    from poc_env.agents.mission.plan import map_source, with_scenario_file, write_plan
    from poc_env.agents.planning.allocation import REFINE, SPEED, plan_fleets
    from poc_env.agents.planning.geography import check_terrain, scenario_crs
    from poc_env.agents.planning.planner import plan_options

    sizes = fleet_sizes(args.fleet_sizes)
    how = "--fleet-sizes plans each size on the one before"
    if args.uavs is not None:
        raise ConfigError("uavs", args.uavs, "either --uavs or --fleet-sizes, not both")
    if getattr(args, "planner", "de") != "allocation":
        raise ConfigError(
            "planner", args.planner, f"allocation with --fleet-sizes ({how}, with the "
            "allocation planner): add --planner allocation",
        )  # fmt: skip
    if args.effort == "thorough":
        raise ConfigError(
            "effort", args.effort, f"default or standard with --fleet-sizes ({how}; thorough "
            "keeps the better of its plan and the default plan, which takes no floor): plan "
            "each size with --uavs N --effort thorough",
        )  # fmt: skip
    if args.plot is not None:
        raise ConfigError("plot", args.plot, "no --plot with --fleet-sizes (one picture per "
                          "plan: plan a size with --uavs N --plot FILE)")  # fmt: skip
    paths = {n: fleet_plan_path(args.out, n) for n in sizes}
    for path in paths.values():  # a folder or a device of that name: refused before planning
        _check_out("out", path, "file")
    check_distinct({f"out (fleet size {n})": str(p) for n, p in paths.items()}, _inputs_of(args))
    sc, prior = _plan_inputs(args)
    crs = scenario_crs(sc, args.origin, args.projection, args.utm_zone)

    def said(plan: dict) -> None:  # progress: a large map takes minutes a size
        if not args.quiet:
            print(f"planned {len(plan['uavs'])} UAVs: POS_C {plan['posc']:.4f} "
                  f"({plan['runtime_s']:.1f} s)", flush=True)  # fmt: skip

    plans = plan_fleets(
        sc,
        sizes,
        prior=prior,
        each=said,
        map_source=map_source(sc, args.map_file),
        seed=args.seed,
        crs=crs,
        speed=SPEED if args.speed is None else args.speed,  # as make_plan plans one size
        refine=REFINE if args.refine is None else args.refine,
        options=plan_options(args.effort, args.gain_per_hour),
    )
    for n, plan in zip(sizes, plans, strict=True):
        plan.update(check_terrain(plan, sc.with_uavs(n), prior))  # orbits fitted (i24-orbitfit)
        _spill_bound(args, plan, sc.with_uavs(n), prior)
    print(fleet_table(plans))
    _plan_notes(args, [(f"{len(p['uavs'])} UAVs: ", p) for p in plans], sc)
    folder = Path(args.out).parent
    with _output_folder("out", folder) as stage:
        files = [
            write_plan(with_scenario_file(p, args.scenario), stage / paths[n].name)
            for n, p in zip(sizes, plans, strict=True)
        ]
        _wrote(files, stage, folder)
    return 0


def fleet_table(plans: list[dict]) -> str:
    """``plan --fleet-sizes``'s table: per plan its UAVs, planned POS_C, the rule-aware bound
    (``bound_rule``, :doc:`BOUND`) and POS_C's share of it, its UAVs without a route and its
    planning time."""
    head = (
        f"{'UAVs':>4} {'POS_C':>7} {'rule-aware bound':>16} {'POS_C/bound':>11} "
        f"{'without a route':>15} {'time/s':>7}"
    )
    lines = [head, "-" * len(head)]
    for p in plans:
        rule = p.get("bound_rule")
        bound, ratio = (f"{rule:.4f}", f"{p['posc'] / rule:.3f}") if rule else ("-", "-")
        idle = sum(1 for u in p["uavs"] if not u["waypoints_m"])
        lines.append(
            f"{len(p['uavs']):>4} {p['posc']:>7.4f} {bound:>16} {ratio:>11} {idle:>15} "
            f"{p['runtime_s']:>7.1f}"
        )
    lines.append("-" * len(head))
    lines.append(
        "each size planned on the one before (plan_fleets): its routes kept where they keep "
        "the fill's clearance, the UAVs added filled"
    )
    tol = 1e-12  # float rounding is no fall
    fell = [
        str(len(b["uavs"])) for a, b in itertools.pairwise(plans) if b["posc"] < a["posc"] - tol
    ]
    if fell:  # i24-chain: a route of the smaller fleet in conflict is flown anew
        from poc_env.agents.planning.allocation import FILL_WITHIN

        lines.append(
            f"POS_C falls at {', '.join(fell)} UAVs: routes of the smaller fleet within "
            f"{FILL_WITHIN:g} d_s of another at planned times were given anew (eq. 21 first)"
        )
    return "\n".join(lines)


def effort_skip_note(plan: dict, effort: str | None) -> str | None:
    """:func:`poc_env.agents.planning.planner.effort_skip_note` (``plan`` and ``replan`` print
    it)."""
    from poc_env.agents.planning.planner import effort_skip_note as note

    return note(plan, effort)


def cmd_export(args: argparse.Namespace) -> int:
    import functools

    from poc_env.agents.mission.export import export_plan

    if args.layer_by is not None and not args.separation_m:  # i24-dayaudit: silently no layers
        raise ConfigError(
            "layer_by", args.layer_by, "only with --separation-m S > 0, the layers' spacing "
            "(without it every UAV flies the plan's altitude): give both, or leave --layer-by out",
        )  # fmt: skip
    export = functools.partial(
        export_plan,
        projection=args.projection,
        zone=args.utm_zone,
        altitude_m=args.altitude_m,
        altitude_ref=args.altitude_ref,
        field_elevation_m=args.field_elevation_m,
        geofence=not args.no_geofence,
        allow_infeasible=args.allow_infeasible,
        max_mission_items=args.max_mission_items,
        separation_m=args.separation_m,
        layer_by=args.layer_by or "field",
    )
    if not Path(args.plan).is_file():  # the plan loader names what is wrong with it
        _wrote(export(args.plan, args.format, args.origin, args.out))
        return 0
    dest = Path(args.out) if args.out else Path(args.plan).parent
    _check_out("out", dest, "folder")
    with _output_folder("out", dest) as stage:
        written = export(args.plan, args.format, args.origin, stage)
    _wrote(written, stage, dest)  # once in place: a refused merge writes (and says) nothing
    return 0


def cmd_figures(args: argparse.Namespace) -> int:
    from poc_env.viz.figures import pattern_gallery

    _check_out("out", args.out, "folder")
    out = Path(args.out)
    with _output_folder("out", out) as stage:
        _wrote(pattern_gallery(stage), stage, out)
        survey_args = argparse.Namespace(
            scenario="paper_6_1", regions=None, map_file=None, overrides=None
        )
        name = "survey_paper_6_1"
        return _survey(survey_args, _mkdir(stage / name), out / name)


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


def cmd_demo(args: argparse.Namespace) -> int:
    """The main job on the built-in scenarios: survey, plan, and policies flown and scored."""
    _check_int("episodes", args.episodes, 1, limits.MAX_EPISODES)
    _check_int("workers", args.workers, 1, limits.MAX_WORKERS)
    _check_out("out", args.out, "folder")
    out = Path(args.out)
    with _output_folder("out", out) as stage:
        print("== §6.1.1 polygon survey (Table 4 analog) ==")
        _survey(
            argparse.Namespace(scenario="paper_6_1", regions=None, map_file=None, overrides=None),
            stage,
            out,
        )
        print("\n== §6.2 time-limited plan with adaptive DE (Table 6 analog) ==")
        plan_args = argparse.Namespace(
            scenario="paper_6_2",
            overrides=None,
            map_file=None,
            uavs=None,
            optimizer="adaptive_de",
            seed=0,
            popsize=None,
            maxiter=None,
            quiet=True,
            origin=None,
            projection="aeqd",
            utm_zone=None,
            preset="paper",
            planner="de",
        )
        plot = has_extra("plot")
        if not plot:
            print(skipped_for_extra("plot", "plan.png"))
        lines = _plan(
            plan_args,
            stage / "plan.json",
            stage / "plan.png" if plot else None,
            (out / "plan.json", out / "plan.png" if plot else None),
        )
        _say(lines, stage)  # staged: said once the folder is in place
        print("\n== policies flown in the environment, same seeds ==")
        # parsed by the real parser, so every option evaluate reads has its default
        eval_args = build_parser().parse_args(
            ["evaluate", "--scenario", "paper_6_2", "--episodes", str(args.episodes),
             "--seed", "1000", "--workers", str(args.workers), "--quiet"]
        )  # fmt: skip
        return _evaluate(eval_args, ["de_plan", "lawnmower", "random"], stage, out)


def _version() -> str:
    """The installed distribution's version (the package's own when run from a checkout)."""
    import importlib.metadata

    try:
        return importlib.metadata.version("poc-env")
    except importlib.metadata.PackageNotFoundError:
        from poc_env import __version__

        return __version__


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="poc-env",
        description="UAV-swarm search over a probability-of-containment map (Fan et al. 2024).",
        epilog=examples(
            "poc-env --version",
            "poc-env scenarios",
            "poc-env --max-memory-gb 4 plan --scenario small --out out/plan.json",
        )
        + "\n\nEach command's --help lists its options, their defaults and examples.",
    )
    parser.add_argument(
        "--max-memory-gb",
        type=float,
        default=None,
        help=f"memory guard: refuse maps, env batches and planner populations estimated above "
        f"this many GiB (default {limits.DEFAULT_MEMORY_GB:g}, or POC_ENV_MAX_MEMORY_GB)",
    )
    parser.add_argument(
        "--version", action="version", version=f"%(prog)s {_version()}", help="print the version"
    )
    sub = parser.add_subparsers(dest="command", required=True)
    from poc_env.agents.policies.registry import registered

    p = sub.add_parser(
        "scenarios", help="list the built-in scenarios", epilog=examples("poc-env scenarios")
    )
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser(
        "policies",
        help="list the registered policies (evaluate --policies)",
        epilog=examples("poc-env policies"),
    )
    p.set_defaults(func=cmd_policies)

    p = sub.add_parser(
        "tasks",
        help="list the registered benchmark tasks (poc_env.tasks)",
        epilog=examples("poc-env tasks"),
    )
    p.set_defaults(func=cmd_tasks)

    p = sub.add_parser(
        "record",
        help="record the fixed episodes of registered tasks (poc_env.recorded)",
        epilog=examples(
            "poc-env record --task poc_env/UAVSearch-Small-Heading-v1 --dir out/recorded",
            "poc-env record --all",
        ),
    )
    from poc_env.recorded import add_arguments as record_arguments

    record_arguments(p)
    p.set_defaults(func=cmd_record)

    p = sub.add_parser(
        "spec",
        help="check (or --write) docs/environment.md's tables generated from poc_env.spec",
        epilog=examples("poc-env spec", "poc-env spec --write"),
    )
    from poc_env.spec import add_arguments as spec_arguments

    spec_arguments(p)
    p.set_defaults(func=cmd_spec)

    p = sub.add_parser("scenario", help="scenario tools: import GIS layers as a scenario")
    scenario_sub = p.add_subparsers(dest="scenario_command", required=True)
    p = scenario_sub.add_parser(
        "import",
        help="GeoJSON/KML area, airfields and no-fly zones, GeoTIFF/CSV prior -> YAML",
        epilog=examples(
            "poc-env scenario import area.geojson --airfields fields.geojson --prior prior.csv "
            "--out my_area.yaml",
            "poc-env scenario import area.kml --airfields fields.kml --no-fly zones.kml "
            "--cell-km 2 --projection utm --base small --out my_area.yaml",
        ),
    )
    from poc_env.agents.mission.geoimport import add_scenario_import_arguments, cmd_scenario_import

    add_scenario_import_arguments(p)
    p.set_defaults(func=cmd_scenario_import)

    p = sub.add_parser(
        "survey",
        help="score a region plan (Table 4 / 5 analog) with the bound",
        epilog=examples(
            "poc-env survey --scenario paper_6_1 --out out/survey",
            "poc-env survey --optimise --plan-out out/survey_plan.json --origin -45.5,126.6",
            "poc-env survey --overrides sensor.sweep_width_km=4",
        ),
    )
    _add_scenario(p, "paper_6_1")
    p.add_argument("--regions", default=None, help="region plan: built-in name or YAML path")
    p.add_argument("--out", default=None, help="folder for survey.csv / .txt / .png")
    p.add_argument(
        "--optimise",
        action="store_true",
        help="choose each region's spacing and direction for the most POS within 0.85 T",
    )
    p.add_argument(
        "--plan-out",
        default=None,
        help="also write the survey as a plan.json (schema 2) for poc-env export",
    )
    p.add_argument(
        "--origin",
        default=None,
        help="LAT,LON of the map's (0, 0) recorded in --plan-out's crs (export then needs none)",
    )
    _add_projection(p)
    p.set_defaults(func=cmd_survey)

    p = sub.add_parser(
        "render",
        help="fly one episode and write it as an animated GIF",
        epilog=examples(
            "poc-env render --scenario small --policy greedy_bayes --out out/episode.gif",
            "poc-env render --scenario paper_6_2 --policy de_plan --every 5 --seed 3",
        ),
    )
    p.add_argument("--scenario", default="small", help="built-in name or YAML path")
    _add_overrides(p)
    p.add_argument(
        "--policy",
        default="lawnmower",
        help="a registered policy: " + ", ".join(registered()),
    )
    p.add_argument("--out", default="out/episode.gif")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--max-steps", type=int, default=None)
    p.add_argument("--every", type=int, default=1, help="draw a frame every N steps")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser(
        "evaluate",
        help="score policies on the same episodes",
        epilog=examples(
            "poc-env evaluate --scenario small --policies lawnmower,greedy_bayes --episodes 5 "
            "--out out/eval",
            "poc-env evaluate --task poc_env/UAVSearch-Paper62-Random-Heading-v0 --policies "
            "greedy_bayes,ppo:ppo_heading_paper_6_2 --episodes 20 --baseline greedy_bayes "
            "--workers 2",
            "poc-env evaluate --overrides sensor.sweep_width_km=4 episode.horizon_steps=50 "
            "--policies random,lawnmower",
        ),
    )
    _add_scenario(p, None)
    p.add_argument(
        "--task",
        default=None,
        metavar="TASK_ID",
        help="a registered task (poc-env tasks): its scenario, and held-out random priors for "
        "-Random- tasks; instead of --scenario (default scenario: paper_6_2)",
    )
    p.add_argument(
        "--policies",
        default="lawnmower,random",
        help="comma-separated registered policies: " + ", ".join(registered()),
    )
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--seed", type=int, default=1000, help="first episode seed")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument(
        "--random-priors",
        action="store_true",
        help="every seed flies a fresh random Gaussian-mixture prior "
        "(poc_env.agents.experiments.evaluate.episode_prior; a generator stream training "
        "never draws from); with --task, a -Random- task's own (a fixed-prior task refuses it)",
    )
    p.add_argument(
        "--baseline",
        default=None,
        metavar="POLICY[,POLICY...]",
        help="one or more of --policies: also print (and write paired.csv) every other "
        "policy's mean per-seed POSC difference to each, with its 95 %% interval and "
        "wins/ties/losses",
    )
    p.add_argument("--out", default=None, help="folder for evaluate.csv/.txt and the figure")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_ray(p)
    p.set_defaults(func=cmd_evaluate)

    p = sub.add_parser(
        "summarise",
        help="rewrite an evaluate folder's evaluate.csv/.txt (and paired.csv) from its "
        "episodes.csv, flying nothing",
        epilog=examples(
            "poc-env summarise results/learned",
            "poc-env summarise out/eval --baseline lawnmower --out out/eval_paired",
        ),
    )
    p.add_argument("results_dir", help="folder of poc-env evaluate --out (holds episodes.csv)")
    p.add_argument(
        "--baseline",
        default=None,
        metavar="POLICY[,POLICY...]",
        help="paired differences against these policies (default: the baselines of the "
        "folder's paired.csv, if any)",
    )
    p.add_argument(
        "--out", default=None, help="folder for the summary files (default: RESULTS_DIR)"
    )
    p.set_defaults(func=cmd_summarise)

    # train's options (and its --help) come from the TrainArgs dataclass: main() hands them to
    # poc_env.agents.rl.args.parse_train_args
    p = sub.add_parser(
        "train", help="train an RL policy (PPO) into a run folder, or --resume one", add_help=False
    )
    p.set_defaults(func=cmd_train)

    p = sub.add_parser(
        "plan",
        help="the §6.2 time-limited plan (Table 6 analog) as plan.json",
        epilog=examples(
            "poc-env plan --out out/plan.json --plot out/plan.png --origin -45.5,126.6",
            "poc-env plan --scenario small --planner allocation --out out/plan.json",
            "poc-env plan --scenario small --planner allocation --fleet-sizes 3,6,12 "
            "--out out/plan.json",
            "poc-env plan --overrides sensor.sweep_width_km=4 --uavs 4 --optimizer cmaes "
            "--maxiter 50",
        ),
    )
    _add_scenario(p, "paper_6_2")
    p.add_argument(
        "--uavs",
        type=int,
        default=None,
        help="number of UAVs (default: the scenario's fleet). The fleet's own take-off/landing "
        "pairs come first, one from each of its groups in turn, so N equal to the fleet's size is "
        "the fleet itself; UAVs beyond it take off from the airfields in turn and land there. To "
        "compare fleet sizes: one plan per size can plan a larger fleet a little less; "
        "--fleet-sizes plans each size on the one before, never less",
    )
    p.add_argument(
        "--optimizer",
        default=None,
        help="--planner de: adaptive_de (the default), classic_de, chaotic_abc, grouped_pso, "
        "scipy_de, cmaes",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--popsize",
        type=int,
        default=None,
        help=f"default: scenario planner NP; 4 to {limits.POPSIZE_MAX}",
    )
    p.add_argument(
        "--maxiter",
        type=int,
        default=None,
        help=f"default: scenario planner G; 1 to {limits.MAXITER_MAX}",
    )
    p.add_argument(
        "--preset",
        default=None,
        help="DE settings: paper (the scenario's, the paper's F0 0.2, CR 0.1; default) or "
        "tuned (same NP, G; F0 0.15, CR 0.9, measured in docs/PLANNER.md)",
    )
    p.add_argument(
        "--planner",
        default="de",
        choices=["de", "allocation"],
        help="de: the paper's optimiser plan; allocation: routes from the reach-aware "
        "optimal allocation (docs/PLANNER.md)",
    )
    p.add_argument(
        "--spill-bound",
        action="store_true",
        help="also the spill-charged rule-aware bound (bound_spill: the sensor's spill charged "
        "by its lateral law, docs/PLANNER.md; a linear program, seconds to minutes)",
    )
    p.add_argument(
        "--speed",
        default=None,
        help="allocation planner: max (out and on the route at v_max, home at v_c; default) or "
        "paper (eq. 17's v_c and v_s: for a sensor whose sweep width falls with speed)",
    )
    p.add_argument(
        "--refine",
        type=int,
        default=None,
        help="allocation planner: passes of the waypoint refinement (default 4; 0: the straight "
        "search lines only)",
    )
    p.add_argument(
        "--effort",
        default=None,
        help="allocation planner: default (seconds), standard (the default plan polished, "
        "within 2 s on paper_6_2; on a map of more than 80 cells a side within a work budget, "
        "about a minute of one core at 160 x 160 cells and 24 UAVs, with a note when the budget "
        "stopped it) or thorough (about 20 s on paper_6_2, minutes on 400-500 km maps: 12 min "
        "at 160 x 160 cells and 24 UAVs; more POS: docs/PLANNER.md, effort levels)",
    )
    _add_gain_per_hour(p)
    p.add_argument(
        "--fleet-sizes",
        default=None,
        metavar="N[,N...]",
        help="compare fleet sizes (--planner allocation; not with --uavs): each size, in "
        "increasing order, planned on the one before (plan_fleets: its routes that keep the "
        "fill's eq. 21 clearance kept, the UAVs added filled); one plan per size beside "
        "--out, named with _nN (plan_n6.json, plan_n12.json, ...: all written or none) and "
        "one table of POS_C, the rule-aware bound, UAVs without a route and time "
        "(docs/planning.md, 'Comparing fleet sizes')",
    )
    p.add_argument("--out", default="plan.json")
    p.add_argument("--plot", default=None, help="PNG of the plan (Fig. 21 analog)")
    p.add_argument(
        "--origin",
        default=None,
        help="LAT,LON of the map's (0, 0): the plan records its crs, so export needs no origin",
    )
    _add_projection(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_plan)

    p = sub.add_parser(
        "replan",
        help="the next sortie: eq. 14 along a plan's flights (or flown tracks), replanned",
        epilog=examples(
            "poc-env replan --plan out/p1.json --out out/p2.json",
            "poc-env replan --plan out/p1.json --plan out/p2.json --out out/p3.json",
            "poc-env replan --plan out/p1.json --tracks flown.geojson --planner de "
            "--out out/p2.json",
            "poc-env replan --plan out/p1.json --tracks uav1.gpx --tracks uav2.kml "
            "--out out/p2.json",
        ),
    )
    _add_scenario(p, None)
    p.add_argument(
        "--plan", required=True, action="append", help="each previous sortie's plan.json, in order"
    )
    p.add_argument(
        "--tracks",
        action="append",
        default=None,
        help="flown tracks (WGS 84): GeoJSON or KML LineStrings, GPX tracks; repeatable; they "
        "stand for the flights of every --plan given (give every sortie's logs)",
    )
    p.add_argument("--origin", default=None, help="LAT,LON of (0, 0) if the plan has no crs")
    p.add_argument(
        "--planner", default="allocation", choices=["allocation", "de"], help="the next sortie's"
    )
    p.add_argument("--seed", type=int, default=0, help="the planner's generator seed")
    p.add_argument(
        "--effort",
        default=None,
        help="allocation planner: default, standard or thorough, as plan's --effort (the next "
        "sortie's; docs/PLANNER.md, effort levels)",
    )
    _add_gain_per_hour(p)  # the next sortie's floor per flight hour, as plan's
    p.add_argument("--out", default="next_plan.json", help="the next sortie's plan.json")
    p.set_defaults(func=cmd_replan)

    from poc_env.agents.mission.formats import FORMATS

    p = sub.add_parser(
        "export",
        help="a plan.json as GeoJSON, KML, QGroundControl missions, ...",
        epilog=examples(
            "poc-env export out/plan.json --format kml",
            "poc-env export out/plan.json --format qgc --origin -45.5,126.6 --altitude-ref "
            "amsl --field-elevation-m 120 --out out/missions",
        ),
    )
    p.add_argument("plan", help="plan.json (schema 2; schema-1 files still load)")
    p.add_argument(
        "--format",
        required=True,
        metavar="{" + ",".join(FORMATS) + "}",  # checked by export_plan: a ConfigError names them
        help="; ".join(f"{f.name}: {f.summary}" for f in FORMATS.values()),
    )
    p.add_argument(
        "--origin",
        default=None,
        help="LAT,LON of the map's (0, 0), degrees (e.g. -45.5,126.6); needed unless the plan "
        "records its crs (plan --origin)",
    )
    p.add_argument("--out", default=None, help="folder (default: beside the plan)")
    _add_projection(p)
    p.add_argument("--altitude-m", type=float, default=None, help="flight altitude (default: plan)")
    p.add_argument(
        "--altitude-ref",
        default=None,
        help="home (relative to the take-off field; default) or amsl (above mean sea level); "
        "a plan with terrain is always amsl, from its DEM",
    )
    p.add_argument(
        "--field-elevation-m",
        type=float,
        default=None,
        help="airfield elevation above MSL (default 0; a plan with terrain takes it from its DEM)",
    )
    p.add_argument(
        "--no-geofence",
        action="store_true",
        help="QGC: leave the inclusion fence out (by default a mission leaving its own "
        "operating area or crossing a no-fly zone is refused)",
    )
    p.add_argument(
        "--allow-infeasible",
        action="store_true",
        help="QGC: write the missions of UAVs the plan marks infeasible (flight beyond the "
        "usable endurance, eq. 18), with a warning (by default refused, naming the UAVs)",
    )
    p.add_argument(
        "--max-mission-items",
        type=int,
        default=None,
        metavar="N",
        help="QGC: refuse a mission of more than N items, your autopilot's limit (by default "
        "a mission past 500 items, PX4's smallest boards, is warned: docs/EXPORT.md)",
    )
    p.add_argument(
        "--separation-m",
        type=float,
        default=0.0,
        metavar="S",
        help="vertical separation: UAV k' of each field (--layer-by) flies k' x S m above the "
        "plan's altitude, take-off to the landing approach (a climb spiral or descent orbit "
        "over terrain keeps the ground's altitudes; the layer widens its radius by k' S "
        "instead); 0: one altitude for all, else 1 to 1000 m (docs/EXPORT.md, 'Altitude "
        "layers')",
    )
    p.add_argument(
        "--layer-by",
        default=None,
        choices=("field", "fleet"),
        help="with --separation-m: field (the default), layers counted per take-off field, whose "
        "UAVs share take-off and homeward legs; fleet: every UAV its own layer",
    )
    p.set_defaults(func=cmd_export)

    p = sub.add_parser(
        "curve",
        help="plot a training run's POSC curve (TensorBoard logs) as PNG",
        epilog=examples("poc-env curve runs/small --out out/curve.png --until 20000"),
    )
    p.add_argument("run_dir", help="run folder of poc-env train")
    p.add_argument("--out", default="training_curve.png")
    p.add_argument("--until", type=int, default=None, help="last timestep to plot")
    p.set_defaults(func=cmd_curve)

    p = sub.add_parser(
        "experiment",
        help="reproduce a §6 experiment of the paper (or all)",
        epilog=examples(
            "poc-env experiment table6 --quick --out out/table6",
            "poc-env experiment all --workers 2 --preset tuned",
        ),
    )
    from poc_env.agents.experiments.paper import add_arguments as add_experiment_arguments

    add_experiment_arguments(p)
    _add_ray(p)
    p.set_defaults(func=cmd_experiment)

    p = sub.add_parser(
        "bench",
        help="speed benchmarks (one core; medians of several runs)",
        epilog=examples(
            "poc-env bench env --envs 1 64 --runs 3",
            "poc-env bench campaign --cases 6500 --seed 72",
        )
        + "\n\nEach benchmark's own --help (poc-env bench plan --help) lists its options.",
    )
    p.add_argument(
        "what",
        choices=list(BENCHMARKS),
        help="env: agent-steps/s; plan: DE plan wall time; train: PPO transitions/s; campaign: "
        "hostile-input cases and their outcomes (needs hypothesis, the dev extra); baselines: "
        "the baseline table of every registered task; suite: env-steps/s per control level and "
        "PPO transitions/s in SB3 and RLlib; learning: held-out learning curves of training "
        "runs over seeds and the transitions to reach a planner; generalise: policies on "
        "held-out geometries and comms-limited beliefs; peers: our envs against MPE2, VMAS and "
        "DSSE (the peers extra), interleaved, with ratios",
    )
    p.add_argument("rest", nargs=argparse.REMAINDER, help="options of the benchmark (--help)")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser(
        "figures",
        help="regenerate the README's figures",
        epilog=examples("poc-env figures --out results/img"),
    )
    p.add_argument("--out", default="results/img")
    p.set_defaults(func=cmd_figures)

    p = sub.add_parser(
        "demo",
        help="run the main job on the built-in scenarios",
        epilog=examples("poc-env demo --out out/demo --episodes 2 --workers 1"),
    )
    p.add_argument("--out", default="out/demo")
    p.add_argument("--episodes", type=int, default=5)
    p.add_argument("--workers", type=int, default=2)
    p.set_defaults(func=cmd_demo)
    use_everywhere(p for _, p in walk(parser))  # defaults shown, examples kept as written
    return parser


def parse_command_line(argv: Sequence[str]) -> argparse.Namespace:
    """``argv`` (without the program name) parsed as :func:`main` parses it: ``train``'s options
    left in ``train_options`` for :func:`poc_env.agents.rl.args.parse_train_args`, ``bench``'s
    in ``rest`` for the benchmark's own parser. A malformed line exits with status 2."""
    parser = build_parser()
    argv = list(argv)
    for opt in _NEGATIVE_VALUE_OPTIONS:  # "--origin -45,7" -> "--origin=-45,7"
        while opt in argv[:-1]:
            i = argv.index(opt)
            argv[i : i + 2] = [f"{opt}={argv[i + 1]}"]
    args, rest = parser.parse_known_args(argv)
    if args.command == "train":
        args.train_options = rest
    elif rest:
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    import signal

    from poc_env import STARTING_INTERRUPTED

    # from here on Ctrl-C is a KeyboardInterrupt this function reports (during the imports
    # before it, poc_env's own handler did: poc_env/__init__.py)
    with contextlib.suppress(ValueError):  # main() called outside the main thread: no signals
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:  # the parser reads the configuration, whose first import loads the compiled kernels
        args = parse_command_line(sys.argv[1:] if argv is None else argv)
    except KeyboardInterrupt:
        print(STARTING_INTERRUPTED, file=sys.stderr)
        return 130
    try:
        try:
            _check_inputs(args)
            with limits.memory_limit_gb(args.max_memory_gb), warnings.catch_warnings():
                warnings.showwarning = _show_warning  # this call's; restored after it
                return int(args.func(args) or 0)
        except ModuleNotFoundError as err:
            extra = _EXTRA_OF.get((err.name or "").split(".")[0])
            if extra is None:
                raise
            raise MissingExtraError(extra, f"poc-env {args.command}") from err
    except PocEnvError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: one line, no traceback; staged outputs never placed
        print(
            f"interrupted: poc-env {args.command} stopped before its end; its outputs not yet "
            "in place were not written",
            file=sys.stderr,
        )
        return 130  # 128 + SIGINT, as shells report a process the signal ended
    except BrokenPipeError:  # `poc-env tasks | head -3`: the reader had what it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no error at exit
        return 0
    except OSError as err:  # a path the system refused where no check named it first
        if err.filename is None:
            raise
        name = os.fsdecode(err.filename)
        refused = ConfigError(_field_of_path(args, name), name, f"a path poc-env can use "
                              f"({err.strerror or err})")  # fmt: skip
        print(f"error: {refused}", file=sys.stderr)
        return 2


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning a command raises, as the command line says the rest: ``warning: <text>`` on
    stderr, without Python's file, line and source (``terrain.py:673: UserWarning: ...
    return [``)."""
    say_warning(message, file)


def _field_of_path(args: argparse.Namespace, path: str) -> str:
    """The option of ``args`` whose value holds ``path`` (the file an OSError names): its
    whole value, a part of it (``ppo:PATH``, ``map.prior.file=PATH``) or a folder above it;
    within ``train``'s and ``bench``'s own options, the option before the value. ``path``
    when no option holds it (a file named inside a YAML scenario, say)."""

    def holds(value: object) -> int:  # 3: the value itself, 2: part of it, 1: a folder above
        if not isinstance(value, str) or not value:
            return 0
        return 3 if value == path else 2 if path in value else int(
            path.startswith(value.rstrip(os.sep) + os.sep))  # fmt: skip

    found: list[tuple[int, str]] = []
    for key, value in vars(args).items():
        if key in ("train_options", "rest") and isinstance(value, list):
            for i, item in enumerate(value):
                before = value[i - 1] if i > 0 else ""
                option, eq, inline = item.partition("=")
                if option.startswith("--") and eq and holds(inline):  # --resume=PATH
                    found.append((holds(inline), option[2:].replace("-", "_")))
                elif holds(item) and before.startswith("--"):
                    found.append((holds(item), before[2:].replace("-", "_")))
        elif isinstance(value, list):
            found += [(holds(v), key) for v in value if holds(v)]
        elif holds(value):
            found.append((holds(value), key))
    return max(found)[1] if found else "path"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
