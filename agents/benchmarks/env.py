"""Agent-steps per second of the batched core (1, 64, 256 envs) and of MPE2 simple_spread.

    poc-env bench env [--scenario paper_6_2] [--envs 1 64 256] [--runs 5]

One line per figure, each the median of ``--runs`` timed runs, on one core
(``OMP_NUM_THREADS=1``, ``NUMBA_NUM_THREADS=1``, set before numpy is imported). A warm-up run
per configuration keeps JIT compilation out of the figures.

The core (:func:`poc_env.sim.core.step`) is timed with seeded random actions in level flight
(pitch action 0). Each timed stretch starts from :func:`~poc_env.sim.core.initial` with the
UAVs moved to seeded random positions over the search area: flown from their airfields with
random turns (up to 180 degrees per step) they would stay near the airfields, outside the grid,
where sensing costs nothing -- the figures would flatter the core. Steps per stretch stay below
the endurance horizon, so every UAV flies in every timed step. ``initial`` and the state copies
are not timed.

The single-env figures are the core with ``n_envs = 1`` and, when ``poc_env.parallel_env``
exists, the PettingZoo parallel env over the same core (its dicts, observations and rewards
included; same start over the search area). When ``mpe2`` is importable
(``pip install -e .[bench]``), ``simple_spread_v3.parallel_env(N=6)`` is timed in the same run
with seeded random discrete actions (episodes of ``max_cycles`` steps, resets not timed), and
the ratios of the single-env figures to it are printed. Every peer (MPE2, VMAS, DSSE),
interleaved: ``poc-env bench peers`` (:mod:`poc_env.agents.benchmarks.peers`).

Peak memory per env (``--memory``, at each ``--envs`` of at least 16): the state's bytes per env
and the peak of the Python-side allocations (numpy arrays, via :mod:`tracemalloc`; numba's own
scratch inside the kernels is not seen) over a step of the episode engine with its observations
(``--obs-type``, default the tasks' ``compass``) and infos, beyond the state, per env.

``main(argv)`` returns ``{figure: agent-steps/s, ...}``; ``--set KEY=VALUE`` applies scenario
overrides (e.g. ``sensor.samples_per_cell=2``); ``--uavs N`` flies N UAVs spread over the
scenario's airfields (:meth:`~poc_env.config.Scenario.with_uavs`).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import copy  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from poc_env.config import load_scenario  # noqa: E402
from poc_env.helptext import HelpFormatter, examples  # noqa: E402
from poc_env.sim import core as sim  # noqa: E402

STEPS = 100  # steps per timed stretch (below paper_6_2's 180-step endurance)
AGENT_STEPS_PER_RUN = 40_000  # each timed run repeats stretches until it has about this many


def _start_state(params: sim.Params, n_envs: int, seed: int) -> tuple[sim.State, list]:
    rngs = [np.random.default_rng(seed + k) for k in range(n_envs)]
    state = sim.initial(params, rngs)
    x0, y0, x1, y1 = params.grid.bounds
    place = np.random.default_rng(seed)
    state.pos[..., 0] = place.uniform(x0, x1, state.pos.shape[:2])
    state.pos[..., 1] = place.uniform(y0, y1, state.pos.shape[:2])
    state.heading = place.uniform(-np.pi, np.pi, state.heading.shape)
    return state, rngs


def _actions(params: sim.Params, n_envs: int, seed: int) -> np.ndarray:
    acts = np.random.default_rng(seed).uniform(-1.0, 1.0, (STEPS, n_envs, params.n_agents, 3))
    acts[..., 2] = 0.0  # level flight
    return acts


def bench_core(
    params: sim.Params,
    n_envs: int,
    runs: int,
    seed: int = 0,
    *,
    over_area: bool = True,
    agent_steps: int = AGENT_STEPS_PER_RUN,
) -> float:
    """Median agent-steps/s of :func:`poc_env.sim.core.step` over ``runs`` timed runs of about
    ``agent_steps`` each. ``over_area`` False: the UAVs start where :func:`~poc_env.sim.core.
    initial` puts them (their airfields), as a vector env's reset does."""
    if over_area:
        state0, rngs0 = _start_state(params, n_envs, seed)
    else:
        rngs0 = [np.random.default_rng(seed + k) for k in range(n_envs)]
        state0 = sim.initial(params, rngs0)
    acts = _actions(params, n_envs, seed + 1)
    stretches = max(1, round(agent_steps / (STEPS * n_envs * params.n_agents)))

    def one_run(n_stretches: int) -> float:
        elapsed = 0.0
        for _ in range(n_stretches):
            state, rngs = copy.deepcopy((state0, rngs0))
            t = time.perf_counter()
            for k in range(STEPS):
                sim.step(params, state, acts[k], rngs)
            elapsed += time.perf_counter() - t
        return n_stretches * STEPS * n_envs * params.n_agents / elapsed

    one_run(1)  # warm-up: JIT compilation (or cache load) and caches
    return statistics.median(one_run(stretches) for _ in range(runs))


def bench_pettingzoo(
    scenario: str,
    overrides: dict,
    runs: int,
    seed: int = 0,
    agent_steps: int = AGENT_STEPS_PER_RUN,
) -> float | None:
    """Median agent-steps/s of our PettingZoo parallel env (``poc_env.parallel_env``), or None.

    Same start as the core (UAVs moved over the search area after ``reset``), so the figure
    adds the env's dict conversions, observations and rewards to the core with n_envs = 1.
    """
    try:
        import poc_env
    except ImportError:
        return None
    if not hasattr(poc_env, "parallel_env"):
        return None
    env = poc_env.parallel_env(scenario, **overrides)
    rng = np.random.default_rng(seed)
    n = len(env.possible_agents)
    stretches = max(1, round(agent_steps / (4 * STEPS * n)))

    def one_run(n_stretches: int) -> float:
        elapsed, count = 0.0, 0
        for _ in range(n_stretches):
            env.reset(seed=int(rng.integers(2**31)))
            st = env.sim_state
            x0, y0, x1, y1 = env.params.grid.bounds
            st.pos[..., 0] = rng.uniform(x0, x1, st.pos.shape[:2])
            st.pos[..., 1] = rng.uniform(y0, y1, st.pos.shape[:2])
            st.heading = rng.uniform(-np.pi, np.pi, st.heading.shape)
            acts = rng.uniform(-1.0, 1.0, (STEPS, n, 3))
            acts[..., 2] = 0.0
            plan = [dict(zip(env.possible_agents, row)) for row in acts]
            t = time.perf_counter()
            for actions in plan:
                if not env.agents:
                    break
                env.step({a: actions[a] for a in env.agents})
                count += len(env.agents)
            elapsed += time.perf_counter() - t
        return count / elapsed

    one_run(1)
    return statistics.median(one_run(stretches) for _ in range(runs))


def bench_mpe(
    n_agents: int,
    runs: int,
    seed: int = 0,
    max_cycles: int = 100,
    agent_steps: int = AGENT_STEPS_PER_RUN,
) -> float | None:
    """Median agent-steps/s of MPE2 ``simple_spread_v3.parallel_env(N=n_agents)``, or None."""
    try:
        from mpe2 import simple_spread_v3
    except ImportError:
        return None
    env = simple_spread_v3.parallel_env(N=n_agents, max_cycles=max_cycles)
    return bench_discrete_parallel(env, runs, seed, max_cycles, agent_steps)


def bench_discrete_parallel(
    env: Any,
    runs: int,
    seed: int = 0,
    max_cycles: int = 100,
    agent_steps: int = AGENT_STEPS_PER_RUN,
) -> float:
    """Median agent-steps/s of a PettingZoo parallel ``env`` with ``Discrete`` actions (MPE2,
    DSSE): seeded uniform random actions, episodes of up to ``max_cycles`` steps, each from a
    seeded ``reset`` (resets and drawing the actions not timed)."""
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    n_actions = env.action_space(env.agents[0]).n
    n_agents = len(env.possible_agents)
    episodes = max(1, round(agent_steps / (4 * max_cycles * n_agents)))

    def one_run(n_episodes: int) -> float:
        elapsed, count = 0.0, 0
        for _ in range(n_episodes):
            env.reset(seed=int(rng.integers(2**31)))
            plan = [
                {a: int(x) for a, x in zip(env.agents, row)}
                for row in rng.integers(0, n_actions, (max_cycles, len(env.agents)))
            ]
            t = time.perf_counter()
            for actions in plan:
                if not env.agents:
                    break
                env.step(actions)
                count += len(actions)
            elapsed += time.perf_counter() - t
        return count / elapsed

    one_run(1)
    return statistics.median(one_run(episodes) for _ in range(runs))


#: The moving-target overrides of ``--motion``: the Drift tasks' (poc_env.spec.MOTION_OVERRIDES).
MOTION_SET: dict[str, dict[str, Any]] = {
    "drift": {"target.random_current_kmh": 25.0, "target.diffusion_m2_s": 50.0},
    "diffusion": {"target.diffusion_m2_s": 50.0},
    "leeway": {
        "target.random_current_kmh": 25.0,
        "target.wind_kmh": [40.0, 20.0],
        "target.diffusion_m2_s": 50.0,
    },
}


def bench_motion(args: argparse.Namespace, overrides: dict, static: sim.Params) -> dict:
    """Static vs moving target in the batched core, timed run by run in turn (one thread):
    the medians in env-steps/s (and agent-steps/s) and the filter's share of a moving step,
    ``1 - moving rate / static rate``, the median over the pairs of runs."""
    moving = sim.make_params(
        load_scenario(
            args.scenario, {**overrides, "target.model": args.motion, **MOTION_SET[args.motion]}
        )
    )
    out: dict[str, float] = {}
    for e in args.envs:
        rates: dict[str, list[float]] = {"static": [], args.motion: []}
        for _ in range(args.runs):  # interleaved
            rates["static"].append(bench_core(static, e, 1))
            rates[args.motion].append(bench_core(moving, e, 1))
        a = statistics.median(rates["static"])
        b = statistics.median(rates[args.motion])
        # the share from each pair's ratio (the two runs of a pair see the same machine load)
        share = 1.0 - statistics.median(
            m / s for s, m in zip(rates["static"], rates[args.motion], strict=True)
        )
        out[f"core_{e}env_static"], out[f"core_{e}env_{args.motion}"] = a, b
        out[f"filter_share_{e}env"] = share
        n = static.n_agents
        out[f"core_{e}env_static_env_steps"] = a / n
        out[f"core_{e}env_{args.motion}_env_steps"] = b / n
        print(
            f"core {args.scenario} n_envs={e:<4d}: static {a / n:10,.0f}, {args.motion} "
            f"{b / n:10,.0f} env-steps/s ({a:10,.0f} / {b:10,.0f} agent-steps/s); the filter "
            f"takes {100 * share:.1f} % of the step",
            flush=True,
        )
    return out


def _state_bytes(state: sim.State) -> int:
    return sum(v.nbytes for v in vars(state).values() if isinstance(v, np.ndarray))


def peak_memory(scenario: str, overrides: dict, n_envs: int, obs_type: str) -> tuple[float, float]:
    """(state bytes per env, peak step bytes per env): :func:`tracemalloc`'s peak over one step
    of the episode engine (core, observation of kind ``obs_type``, infos) beyond the state."""
    import tracemalloc

    from poc_env.sim.engine import make_engine

    seeds = list(range(n_envs))
    eng = make_engine(
        n_envs, scenario=scenario, obs_type=obs_type, overrides=overrides, seeds=seeds
    )
    eng.reset()
    acts = np.zeros((n_envs, eng.params.n_agents, 3))
    eng.step(acts)  # warm-up: compilation and caches outside the figure
    state = _state_bytes(eng.current)
    tracemalloc.start()
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    tr = eng.step(acts)
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    del tr
    return state / n_envs, peak / n_envs


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    ap = argparse.ArgumentParser(
        prog="poc-env bench env",
        description=__doc__.splitlines()[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench env --envs 1 64 --runs 3",
            "poc-env bench env --scenario small --set sensor.samples_per_cell=2 --no-mpe",
            "poc-env bench env --motion drift --envs 64 --no-memory",
            "poc-env bench env --scenario wide_400 --uavs 24 --envs 1 16 --no-mpe",
        ),
    )
    ap.add_argument("--scenario", default="paper_6_2")
    ap.add_argument(
        "--uavs",
        type=int,
        default=None,
        help="fleet size, 1 to 64, over the fleet's own take-off/landing pairs round-robin "
        "(Scenario.with_uavs; default: the scenario's fleet)",
    )
    ap.add_argument("--envs", type=int, nargs="+", default=[1, 64, 256])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--no-mpe", action="store_true", help="skip MPE2 simple_spread")
    ap.add_argument("--no-memory", action="store_true", help="skip the peak memory per env")
    ap.add_argument("--obs-type", default="compass", help="observation of the memory figure")
    ap.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="scenario overrides, e.g. sensor.samples_per_cell=2 sensor.cutoff_sweep_widths=3",
    )
    ap.add_argument(
        "--motion",
        choices=("drift", "diffusion", "leeway"),
        default=None,
        help="also time a moving target (the Drift tasks' current and diffusion, or that "
        "model), interleaved with the static one, and print the filter's share of the step",
    )
    return ap


def main(argv: list[str] | None = None) -> dict[str, float]:
    """Run the benchmark; print one line per figure; return ``{name: agent-steps/s, ...}``."""
    from poc_env.agents.benchmarks import check_counts

    args = build_parser().parse_args(argv)
    check_counts(args, envs=1, runs=1)
    overrides = {}
    for item in args.set:
        key, _, value = item.partition("=")
        overrides[key] = yaml.safe_load(value)
    if args.uavs is not None:  # the fleet override of Scenario.with_uavs's spread
        fleet = load_scenario(args.scenario, overrides).with_uavs(args.uavs).fleet
        overrides["fleet"] = [{"takeoff": g.takeoff, "count": g.count} for g in fleet]
    params = sim.make_params(load_scenario(args.scenario, overrides))
    n = params.n_agents
    out: dict[str, float] = {}
    if args.motion is not None:
        return bench_motion(args, overrides, params)
    for e in args.envs:
        rate = bench_core(params, e, args.runs)
        out[f"core_{e}env"] = rate
        label = " ".join([args.scenario, *args.set])
        print(f"core {label} n_envs={e:<4d} N={n}: {rate:12,.0f} agent-steps/s", flush=True)
    if not args.no_memory:
        for e in (e for e in args.envs if e >= 16):
            state, peak = peak_memory(args.scenario, overrides, e, args.obs_type)
            out[f"state_bytes_per_env_{e}"] = state
            out[f"step_peak_bytes_per_env_{e}"] = peak
            print(
                f"memory {args.scenario} {args.obs_type} n_envs={e:<4d}: state "
                f"{state / 1024:8.1f} KiB/env, step peak {peak / 1024:8.1f} KiB/env",
                flush=True,
            )
    if 1 in args.envs:
        pz = bench_pettingzoo(args.scenario, overrides, args.runs)
        if pz is not None:
            out["pettingzoo_1env"] = pz
            label = " ".join([args.scenario, *args.set])
            print(f"pettingzoo parallel_env {label} N={n}: {pz:12,.0f} agent-steps/s", flush=True)
    if not args.no_mpe:
        mpe = bench_mpe(n, args.runs)
        if mpe is None:
            print("mpe2 simple_spread_v3: not installed (pip install -e .[bench])")
        else:
            out["mpe2_simple_spread"] = mpe
            print(f"mpe2 simple_spread_v3 parallel N={n}:   {mpe:12,.0f} agent-steps/s")
            if "core_1env" in out:
                out["ratio_core_1env_to_mpe2"] = out["core_1env"] / mpe
                print(f"ratio core n_envs=1 / mpe2: {out['ratio_core_1env_to_mpe2']:.2f}")
            if "pettingzoo_1env" in out:
                out["ratio_pettingzoo_to_mpe2"] = out["pettingzoo_1env"] / mpe
                print(f"ratio pettingzoo / mpe2: {out['ratio_pettingzoo_to_mpe2']:.2f}")
    return out


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
