"""Our envs against their peers, interleaved in one run: ``poc-env bench peers``.

    poc-env bench peers [--rounds 5] [--out results/peers] [--only KEY ...] [--sb3]
                        [--heading-envs 64] [--small-envs 256] [--vmas-envs 256] [--smoke]
                        [--sb3-cpu-time]

Every contender of :data:`CONTENDERS` is timed once per round, the rounds interleaved (the
order rotates by one each round), on one thread (``OMP_NUM_THREADS=1`` and friends set before
numpy is imported, ``torch.set_num_threads(1)``); a contender's figure is the median of its
rounds, a ratio is the ratio of two medians (with the range of the per-round ratios):

- ours: the single PettingZoo ``parallel_env("paper_6_2")`` (dict observations, the UAVs moved
  over the search area; :func:`~poc_env.agents.benchmarks.env.bench_pettingzoo`),
  ``gymnasium.make_vec`` on ``UAVSearch-Paper62-Heading-v0`` and ``UAVSearch-Small-Heading-v0``
  (seeded random actions from a seeded reset, autoresets included;
  :func:`~poc_env.agents.benchmarks.suite.bench_vector`) and the batched core
  (:func:`~poc_env.agents.benchmarks.env.bench_core`) on Small from its reset state (the start
  ``make_vec`` has) and with the UAVs over the search area;
- peers (the ``peers`` extra, each pinned): MPE2 ``simple_spread_v3.parallel_env(N=6)`` and DSSE's
  ``DroneSwarmSearch`` (grid 40, 6 drones), random discrete actions, resets not timed
  (:func:`~poc_env.agents.benchmarks.env.bench_discrete_parallel`); VMAS's ``discovery``
  scenario (6 agents, ``--vmas-envs`` envs, CPU, continuous random actions in
  ``[-u_range, u_range]``, no resets: VMAS envs run on without a horizon);
- with ``--sb3`` (slow: PPO runs): SB3 PPO agent transitions/s through ``poc-env train --task``
  on :data:`SB3_TASK` against SB3 PPO with the same settings (``TrainArgs``: hyper-parameters,
  MLP, ``n_envs`` swarms) on MPE2 ``simple_spread_v3`` N=6 through SuperSuit (one warm-up
  iteration, then ``sb3_iterations`` timed ones, one torch thread; ``--sb3-cpu-time``: timed
  by the process's CPU time, steadier than wall time on a loaded machine).

A peer whose package is not importable is reported as ``not installed`` (its row and every
ratio that needs it), never a traceback. :data:`TARGETS` are the ratios issue 26 asks for;
each is printed with its target. Writes ``peers.csv`` (one row per contender and per ratio,
with the load average before and after) and ``peers.md`` into ``--out`` as one set
(:func:`~poc_env.agents.benchmarks.write_table_set`). ``main(argv)`` returns the rows.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import importlib.metadata  # noqa: E402
import importlib.util  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from poc_env.agents.benchmarks import env as env_bench  # noqa: E402
from poc_env.agents.benchmarks import suite  # noqa: E402
from poc_env.agents.benchmarks.breakdown import SB3_TASK, heading_task  # noqa: E402
from poc_env.errors import ConfigError  # noqa: E402

NOT_INSTALLED = "not installed"
INSTALL_HINT = "pip install -e .[peers]"
N_UAVS = 6  # agents of paper_6_2 and of every peer


@dataclass(frozen=True)
class Settings:
    """Sizes of one ``bench peers`` run (``--smoke`` shrinks them for the test suite)."""

    heading_envs: int = 64
    small_envs: int = 256
    vmas_envs: int = 256
    vector_steps: int = suite.STEPS  # joint steps per make_vec stretch
    vmas_steps: int = 50  # joint steps per VMAS stretch
    agent_steps: int = env_bench.AGENT_STEPS_PER_RUN  # per single-env / core round
    peer_cycles: int = 100  # episode length of MPE2 and DSSE
    sb3_iterations: int = 2  # timed PPO iterations of each SB3 contender (after a warm-up one)
    sb3_n_steps: int | None = None  # PPO n_steps / batch_size (None: TrainArgs' defaults)
    sb3_batch_size: int | None = None
    sb3_n_envs: int | None = None  # swarms (MPE2 worlds) side by side (None: TrainArgs')
    sb3_cpu_time: bool = False  # time the SB3 pair by the process's CPU time, not wall time


@dataclass(frozen=True)
class Contender:
    """One timed configuration: ``run(settings, seed)`` is one round's agent-steps/s."""

    key: str
    label: str
    agents: int  # agents per env (env-steps/s = agent-steps/s / agents)
    envs: Callable[[Settings], int]  # envs stepped at once
    run: Callable[[Settings, int], float]
    package: str | None = None  # the peer's distribution (None: ours)
    module: str | None = None  # what must import for it to run


#: The newest ``UAVSearch-<scenario>-Heading`` task id (:func:`breakdown.heading_task`).
_heading_task = heading_task


def _small_scenario() -> str:
    from poc_env import tasks

    return tasks.get_task(_heading_task("Small")).scenario


def _task_agents(scenario: str) -> int:
    """UAVs of the ``scenario`` family's tasks (``"Small"``: 3)."""
    from poc_env import tasks

    return _core_params(tasks.get_task(_heading_task(scenario)).scenario).n_agents


def _core_params(scenario: str):
    from poc_env.config import load_scenario
    from poc_env.sim import core as sim

    return sim.make_params(load_scenario(scenario))


def _single(s: Settings, seed: int) -> float:
    rate = env_bench.bench_pettingzoo("paper_6_2", {}, 1, seed, s.agent_steps)
    assert rate is not None
    return rate


def _vector(scenario: str, envs: Callable[[Settings], int]) -> Callable[[Settings, int], float]:
    def run(s: Settings, seed: int) -> float:
        tid = _heading_task(scenario)
        return _task_agents(scenario) * suite.bench_vector(tid, envs(s), 1, seed, s.vector_steps)

    return run


def _core(over_area: bool) -> Callable[[Settings, int], float]:
    def run(s: Settings, seed: int) -> float:
        params = _core_params(_small_scenario())
        return env_bench.bench_core(
            params, s.small_envs, 1, seed, over_area=over_area, agent_steps=s.agent_steps
        )

    return run


def _mpe(s: Settings, seed: int) -> float:
    rate = env_bench.bench_mpe(N_UAVS, 1, seed, s.peer_cycles, s.agent_steps)
    if rate is None:
        raise ImportError("mpe2")
    return rate


def _dsse(s: Settings, seed: int) -> float:
    import contextlib
    import io

    from DSSE import DroneSwarmSearch

    with contextlib.redirect_stdout(io.StringIO()):  # it prints its pre-render time
        env = DroneSwarmSearch(
            grid_size=40,
            render_mode="ansi",
            render_grid=False,
            render_gradient=False,
            vector=(1, 1),
            timestep_limit=s.peer_cycles,
            person_amount=1,
            dispersion_inc=0.05,
            person_initial_position=(20, 20),
            drone_amount=N_UAVS,
            drone_speed=10,
            probability_of_detection=0.9,
            pre_render_time=0,
        )
    return env_bench.bench_discrete_parallel(env, 1, seed, s.peer_cycles, s.agent_steps)


def _vmas(s: Settings, seed: int) -> float:
    import torch
    import vmas

    torch.set_num_threads(1)
    e = s.vmas_envs
    env = vmas.make_env(
        "discovery", num_envs=e, device="cpu", continuous_actions=True, seed=seed, n_agents=N_UAVS
    )
    env.reset()
    rng = np.random.default_rng(seed)
    size = (s.vmas_steps, e, 2)
    acts = [
        torch.from_numpy(rng.uniform(-a.u_range, a.u_range, size).astype(np.float32))
        for a in env.agents
    ]
    rates = []
    for r in range(2):  # the first stretch is the warm-up
        t0 = time.perf_counter()
        for k in range(s.vmas_steps):
            env.step([a[k] for a in acts])
        if r:
            rates.append(s.vmas_steps * e * N_UAVS / (time.perf_counter() - t0))
    return statistics.median(rates)


def _sb3_args(s: Settings, seed: int):
    """The PPO settings both SB3 contenders share: ``poc-env train --task SB3_TASK``'s
    :class:`~poc_env.agents.rl.args.TrainArgs` (the shipped hyper-parameters and MLP), sized
    by ``s``."""
    import dataclasses

    from poc_env.agents.rl.args import TrainArgs

    args = TrainArgs(task=SB3_TASK, seed=seed, progress=False)
    return dataclasses.replace(
        args,
        n_steps=args.n_steps if s.sb3_n_steps is None else s.sb3_n_steps,
        batch_size=args.batch_size if s.sb3_batch_size is None else s.sb3_batch_size,
        n_envs=args.n_envs if s.sb3_n_envs is None else s.sb3_n_envs,
    )


def _sb3_rate(args, env, seed: int, iterations: int, cpu_time: bool = False) -> float:
    """Agent transitions/s of SB3 PPO (:func:`poc_env.agents.rl.train.make_model`: the policy,
    network and hyper-parameters of ``args``) on the VecEnv ``env``, one torch thread: one
    warm-up iteration, then ``iterations`` timed ones (rollouts and updates). SB3 counts a
    transition per slot; a slot is one agent in both contenders. ``cpu_time``: timed by the
    process's CPU time (``time.process_time``) instead of wall time."""
    import torch as th

    from poc_env.agents.rl.train import make_model, seed_everything

    th.set_num_threads(1)
    seed_everything(seed)
    model = make_model(args, env, None)
    rollout = args.n_steps * env.num_envs
    model.learn(rollout)
    clock = time.process_time if cpu_time else time.perf_counter
    t0 = clock()
    model.learn(iterations * rollout, reset_num_timesteps=False)
    rate = iterations * rollout / (clock() - t0)
    env.close()
    return rate


def _sb3_task(s: Settings, seed: int) -> float:
    """SB3 PPO through ``poc-env train --task SB3_TASK``'s env (:func:`~poc_env.agents.rl.
    train.make_env`: the batched SwarmVecEnv, one slot per UAV, shared policy)."""
    from poc_env.agents.rl.train import make_env
    from poc_env.tasks import get_task

    args = _sb3_args(s, seed)
    env = make_env(args, get_task(SB3_TASK).load_scenario())
    return _sb3_rate(args, env, seed, s.sb3_iterations, s.sb3_cpu_time)


def _sb3_mpe(s: Settings, seed: int) -> float:
    """SB3 PPO with the same settings on MPE2 ``simple_spread_v3`` N=6 (continuous actions:
    the same Gaussian policy) through SuperSuit, the way PettingZoo's SB3 tutorial trains it:
    ``pettingzoo_env_to_vec_env_v1`` (one slot per agent, shared policy) and
    ``concat_vec_envs_v1`` (``n_envs`` worlds, in this process)."""
    import supersuit as ss
    from mpe2 import simple_spread_v3

    args = _sb3_args(s, seed)
    par = simple_spread_v3.parallel_env(N=N_UAVS, max_cycles=s.peer_cycles, continuous_actions=True)
    par.reset(seed=seed)
    env = ss.concat_vec_envs_v1(
        ss.pettingzoo_env_to_vec_env_v1(par),
        args.n_envs,
        num_cpus=0,
        base_class="stable_baselines3",
    )

    def seed_all(seed: int | None = None) -> list[int | None]:
        """VecEnv.seed, which PPO(seed=...) calls and SuperSuit's wrapper lacks: seeds the
        worlds through a reset of the wrapped ConcatVecEnv (world ``i`` gets ``seed + i``)."""
        env.venv.reset(seed=seed)
        return [seed] * env.num_envs

    env.seed = seed_all  # type: ignore[method-assign]
    return _sb3_rate(args, env, seed, s.sb3_iterations, s.sb3_cpu_time)


#: Contenders timed only with ``--sb3`` (or named in ``--only``): a PPO run each, slow.
SB3_KEYS = ("sb3_task", "sb3_mpe2")

#: Every contender, by key (a test registers a stand-in peer here).
CONTENDERS: dict[str, Contender] = {
    c.key: c
    for c in (
        Contender("single", 'parallel_env("paper_6_2"), 1 env', N_UAVS, lambda s: 1, _single),
        Contender(
            "make_vec_paper62",
            "make_vec Paper62-Heading",
            N_UAVS,
            lambda s: s.heading_envs,
            _vector("Paper62", lambda s: s.heading_envs),
        ),
        Contender(
            "make_vec_small",
            "make_vec Small-Heading",
            3,
            lambda s: s.small_envs,
            _vector("Small", lambda s: s.small_envs),
        ),
        Contender(
            "core_small_reset",
            "core Small, from reset",
            3,
            lambda s: s.small_envs,
            _core(over_area=False),
        ),
        Contender(
            "core_small_area",
            "core Small, UAVs over the area",
            3,
            lambda s: s.small_envs,
            _core(over_area=True),
        ),
        Contender("mpe2", "MPE2 simple_spread_v3 N=6", N_UAVS, lambda s: 1, _mpe, "mpe2", "mpe2"),
        Contender(
            "vmas",
            "VMAS discovery, CPU",
            N_UAVS,
            lambda s: s.vmas_envs,
            _vmas,
            "vmas",
            "vmas",
        ),
        Contender(
            "dsse", "DSSE DroneSwarmSearch grid 40", N_UAVS, lambda s: 1, _dsse, "dsse", "DSSE"
        ),
        Contender(
            "sb3_task",
            f"SB3 PPO, train --task {SB3_TASK}",
            N_UAVS,
            lambda s: _sb3_args(s, 0).n_envs,
            _sb3_task,
            "stable-baselines3",
            "stable_baselines3",
        ),
        Contender(
            "sb3_mpe2",
            "SB3 PPO, MPE2 simple_spread_v3 N=6 (SuperSuit)",
            N_UAVS,
            lambda s: _sb3_args(s, 0).n_envs,
            _sb3_mpe,
            "mpe2",
            "mpe2",
        ),
    )
}

#: Issue 26's targets: (numerator, denominator, at least), ratios of env-steps/s.
TARGETS: list[tuple[str, str, float]] = [
    ("make_vec_paper62", "vmas", 3.0),
    ("single", "dsse", 1.0),
    ("single", "mpe2", 10.0),
    ("make_vec_small", "core_small_reset", 0.6),
    ("make_vec_small", "core_small_area", 0.6),
    ("sb3_task", "sb3_mpe2", 3.0),  # PPO agent transitions/s, the same settings
]


def installed(c: Contender) -> bool:
    """Whether ``c`` can run (ours always; a peer when its module imports)."""
    return c.module is None or importlib.util.find_spec(c.module) is not None


def version(c: Contender) -> str:
    if c.package is None:
        return "this tree"
    try:
        return importlib.metadata.version(c.package)
    except importlib.metadata.PackageNotFoundError:
        return ""


def measure(keys: list[str], s: Settings, rounds: int) -> dict[str, list[float]]:
    """Agent-steps/s of each runnable contender per round, interleaved (rotating order)."""
    runnable = [k for k in keys if installed(CONTENDERS[k])]
    rates: dict[str, list[float]] = {k: [] for k in runnable}
    broken: set[str] = set()  # a peer found but failing to import (e.g. a missing dependency)
    for r in range(rounds):
        shift = r % len(runnable) if runnable else 0
        for k in runnable[shift:] + runnable[:shift]:
            if k in broken:
                continue
            try:
                rates[k].append(CONTENDERS[k].run(s, r))
            except ImportError as exc:
                if CONTENDERS[k].module is None:
                    raise
                print(f"{k}: {NOT_INSTALLED} ({exc})", flush=True)
                broken.add(k)
    return {k: v for k, v in rates.items() if k not in broken}


def speed_rows(keys: list[str], s: Settings, rates: dict[str, list[float]]) -> list[dict]:
    rows = []
    for k in keys:
        c = CONTENDERS[k]
        row: dict[str, Any] = {
            "kind": "speed",
            "key": k,
            "what": c.label,
            "version": version(c),
            "agents": c.agents,
            "envs": c.envs(s),
            "status": "ok" if k in rates else NOT_INSTALLED,
            "env_steps_per_s": "",
            "agent_steps_per_s": "",
            "per_round": "",
            "ratio": "",
            "target": "",
            "met": "",
        }
        if k in rates:
            agent = statistics.median(rates[k])
            row["agent_steps_per_s"] = round(agent, 1)
            row["env_steps_per_s"] = round(agent / c.agents, 1)
            row["per_round"] = " ".join(f"{x / c.agents:.0f}" for x in rates[k])
        rows.append(row)
    return rows


def ratio_rows(keys: list[str], rates: dict[str, list[float]]) -> list[dict]:
    """One row per target whose two sides were asked for: the ratio of the medians of
    env-steps/s, the per-round ratios, and whether the target is met."""
    rows = []
    for num, den, target in TARGETS:
        if num not in keys or den not in keys:
            continue
        a, b = CONTENDERS[num], CONTENDERS[den]
        row: dict[str, Any] = {
            "kind": "ratio",
            "key": f"{num}/{den}",
            "what": f"{a.label} / {b.label}",
            "version": "",
            "agents": "",
            "envs": "",
            "status": "ok",
            "env_steps_per_s": "",
            "agent_steps_per_s": "",
            "per_round": "",
            "ratio": "",
            "target": target,
            "met": "",
        }
        if num not in rates or den not in rates:
            missing = [k for k in (num, den) if k not in rates]
            row["status"] = f"{NOT_INSTALLED}: {', '.join(missing)}"
        else:
            ea = [x / a.agents for x in rates[num]]
            eb = [x / b.agents for x in rates[den]]
            ratio = statistics.median(ea) / statistics.median(eb)
            row["ratio"] = round(ratio, 3)
            row["per_round"] = " ".join(f"{x / y:.2f}" for x, y in zip(ea, eb))
            row["met"] = "yes" if ratio >= target else "no"
        rows.append(row)
    return rows


def markdown(rows: list[dict], s: Settings, rounds: int, load: tuple, command: str) -> str:
    lines = [
        "# Our envs against their peers (`poc-env bench peers`)",
        "",
        f"`{command}`: {rounds} interleaved rounds, one thread, medians; load average "
        f"(1 min) {load[0]:.2f} before, {load[1]:.2f} after.",
        "",
        "| contender | version | agents | envs | env-steps/s | agent-steps/s |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["kind"] != "speed":
            continue
        if r["status"] == NOT_INSTALLED:
            speed = f"{NOT_INSTALLED} (`{INSTALL_HINT}`)"
            lines.append(f"| {r['what']} | | {r['agents']} | {r['envs']} | {speed} | |")
            continue
        lines.append(
            f"| {r['what']} | {r['version']} | {r['agents']} | {r['envs']} | "
            f"{r['env_steps_per_s']:,.0f} | {r['agent_steps_per_s']:,.0f} |"
        )
    ratios = [r for r in rows if r["kind"] == "ratio"]
    if ratios:
        lines += [
            "",
            "| ratio of env-steps/s | median | per round | target | met |",
            "|---|---|---|---|---|",
        ]
        for r in ratios:
            if r["status"] != "ok":
                lines.append(f"| {r['what']} | {r['status']} | | {r['target']} | |")
                continue
            lines.append(
                f"| {r['what']} | {r['ratio']:.2f} | {r['per_round']} | "
                f">= {r['target']} | {r['met']} |"
            )
    return "\n".join(lines) + "\n"


def chosen_keys(only: list[str] | None, sb3: bool) -> list[str]:
    """The contenders to time: ``only`` as given, else every contender but the SB3 pair
    (:data:`SB3_KEYS`) unless ``sb3``."""
    if only is not None:
        return list(only)
    return [k for k in CONTENDERS if sb3 or k not in SB3_KEYS]


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    from poc_env.helptext import HelpFormatter, examples

    p = argparse.ArgumentParser(
        prog="poc-env bench peers",
        description=__doc__.split("\n")[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench peers --rounds 5 --out results/peers",
            "poc-env bench peers --only single mpe2 --rounds 3",
            "poc-env bench peers --smoke --rounds 1 --out /tmp/peers",
            "poc-env bench peers --only sb3_task sb3_mpe2 --rounds 3",
            "poc-env bench peers --breakdown make_vec_small --out /tmp/peers",
        ),
    )
    p.add_argument("--rounds", type=int, default=5, help="interleaved rounds (medians over them)")
    p.add_argument("--out", default="results/peers", help="folder for peers.csv and peers.md")
    p.add_argument(
        "--only",
        nargs="+",
        default=None,
        metavar="KEY",
        help="contenders to time (default: all): " + ", ".join(CONTENDERS),
    )
    p.add_argument(
        "--heading-envs",
        type=int,
        default=Settings.heading_envs,
        help="envs of make_vec Paper62-Heading",
    )
    p.add_argument(
        "--small-envs", type=int, default=Settings.small_envs, help="envs of make_vec Small"
    )
    p.add_argument(
        "--vmas-envs", type=int, default=Settings.vmas_envs, help="envs of VMAS discovery"
    )
    p.add_argument(
        "--sb3",
        action="store_true",
        help="also time SB3 PPO on "
        + SB3_TASK
        + " against MPE2 (slow: "
        + ", ".join(SB3_KEYS)
        + ")",
    )
    p.add_argument(
        "--sb3-cpu-time",
        action="store_true",
        help="time the SB3 pair by the process's CPU time (time.process_time) instead of wall "
        "time: steadier on a loaded machine (one thread each); the others keep wall time",
    )
    p.add_argument("--smoke", action="store_true", help="tiny sizes (the test suite's run)")
    p.add_argument(
        "--breakdown",
        default=None,
        metavar="KEY",
        help="instead of timing, print where one of our contenders' step goes (CPU time of "
        "its parts; agents/benchmarks/breakdown.py): make_vec_small, make_vec_paper62, "
        "single, sb3_task",
    )
    return p


def main(argv: list[str] | None = None) -> list[dict]:
    from poc_env.io import check_out

    p = build_parser()
    args = p.parse_args(argv)
    check_out("out", args.out, "folder")  # before the run, not after it
    if args.rounds < 1 or args.rounds > 1000:
        raise ConfigError("rounds", args.rounds, "an integer from 1 to 1000")
    for field in ("heading_envs", "small_envs", "vmas_envs"):
        v = getattr(args, field)
        if v < 1 or v > 4096:
            raise ConfigError(field, v, "an integer from 1 to 4096")
    if args.breakdown is not None:
        return _breakdown(args.breakdown, args.out, 40 if args.smoke else 400, args.smoke)
    keys = chosen_keys(args.only, args.sb3)
    for k in keys:
        if k not in CONTENDERS:
            raise ConfigError("only", k, "contender keys: " + ", ".join(CONTENDERS))
    from poc_env.agents.benchmarks import write_table_set

    s = Settings(args.heading_envs, args.small_envs, args.vmas_envs)
    if args.smoke:
        s = Settings(
            min(args.heading_envs, 2),
            min(args.small_envs, 2),
            min(args.vmas_envs, 2),
            vector_steps=5,
            vmas_steps=3,
            agent_steps=200,
            peer_cycles=10,
            sb3_iterations=1,
            sb3_n_steps=8,
            sb3_batch_size=16,
            sb3_n_envs=1,
        )
    if args.sb3_cpu_time:
        import dataclasses

        s = dataclasses.replace(s, sb3_cpu_time=True)
    load0 = os.getloadavg()[0]
    rates = measure(keys, s, args.rounds)
    load1 = os.getloadavg()[0]
    rows = speed_rows(keys, s, rates) + ratio_rows(keys, rates)
    for r in rows:
        r["load_before"], r["load_after"] = round(load0, 2), round(load1, 2)
    import sys

    command = "poc-env bench peers " + " ".join(sys.argv[1:] if argv is None else argv)
    text = markdown(rows, s, args.rounds, (load0, load1), command.strip())
    write_table_set(args.out, "peers", rows, text)
    print(text, end="", flush=True)
    return rows


def _breakdown(key: str, out: str, steps: int, smoke: bool) -> list[dict]:
    """``--breakdown KEY``: :func:`~poc_env.agents.benchmarks.breakdown.breakdown`'s rows,
    printed and written as ``breakdown_<KEY>.csv``/``.md`` into ``out``."""
    from poc_env.agents.benchmarks import breakdown, write_table_set

    load0 = os.getloadavg()[0]
    sizes = {"make_vec_small": Settings.small_envs, "make_vec_paper62": Settings.heading_envs}
    rows = breakdown.breakdown(key, steps, envs=2 if smoke else sizes.get(key))
    text = breakdown.markdown(key, rows, (load0, os.getloadavg()[0]))
    write_table_set(out, f"breakdown_{key}", rows, text)
    print(text, end="", flush=True)
    return rows


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
