"""The moving-target bound on a uniform drift and on gridded fields: its values and its time.

    python -m poc_env.agents.benchmarks.moving_bound [--scenario paper_6_2] [--runs 3]

One core (``OMP_NUM_THREADS=1``, set before numpy is imported). The scenario's prior (the
belief at an environment reset, seed ``--seed``) and ``target.model: drift`` with diffusion
``--diffusion`` (m^2/s), in four motions of the same mean current ``--current`` (km/h, east):

* ``uniform``: the uniform current;
* ``stationary``: a gridded field, the current plus a swirl of ``--swirl`` m/s at the map's
  edge (:func:`swirl`), one frame;
* ``varying``: the same swirl turning by 0.7 rad every ``--frame-min`` minutes (frames over the
  whole episode, linear between them): a different predict operator every step;
* ``reversal``: the uniform current with the adjoint computed as before gridded fields were
  covered (the filter run at ``-v``), for the time ratio and the 1e-12 agreement.

Per motion: ``<motion>_upper`` (the bound :func:`poc_env.theory.moving_bound.moving_bound`
reports), ``<motion>_pos`` (the model POS of the effort found) and ``<motion>_s`` (wall time,
the median of ``--runs`` runs made interleaved, motion by motion within each run, after a
warm-up). ``main(argv)`` returns ``{figure: value, ...}``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from poc_env.config import Scenario, load_scenario  # noqa: E402
from poc_env.helptext import HelpFormatter, examples  # noqa: E402

MOTIONS = ("uniform", "stationary", "varying", "reversal")


def build_parser() -> argparse.ArgumentParser:
    """This benchmark's command line (``--help``: options, defaults, examples)."""
    p = argparse.ArgumentParser(
        prog="poc-env bench moving-bound",
        description=__doc__.split("\n")[0],
        formatter_class=HelpFormatter,
        epilog=examples(
            "poc-env bench moving-bound --runs 3",
            "poc-env bench moving-bound --scenario small --swirl 2 --runs 1 --steps 20",
        ),
    )
    p.add_argument("--scenario", default="paper_6_2", help="built-in name or YAML path")
    p.add_argument("--current", type=float, default=25.0, help="mean current east, km/h")
    p.add_argument("--diffusion", type=float, default=50.0, help="D, m^2/s")
    p.add_argument("--swirl", type=float, default=3.0, help="swirl speed at the edge, m/s")
    p.add_argument("--frame-min", type=float, default=30.0, help="minutes between frames")
    p.add_argument("--seed", type=int, default=1000, help="the reset's seed")
    p.add_argument("--runs", type=int, default=3, help="timed runs per motion (median)")
    p.add_argument(
        "--steps", type=int, default=None, help="episode steps (default: the scenario's)"
    )
    return p


def swirl(shape: tuple[int, int], speed: float, frames: int) -> np.ndarray:
    """A swirl on ``shape`` (ny, nx) cells, ``(frames, 2, ny, nx)`` m/s: rotation about the
    map's centre, ``speed`` at the edge, turning by 0.7 rad from frame to frame."""
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    y, x = (y - (ny - 1) / 2) / (ny / 2), (x - (nx - 1) / 2) / (nx / 2)
    out = []
    for k in range(frames):
        a = 0.7 * k
        u = -y * math.cos(a) + x * math.sin(a)
        v = x * math.cos(a) + y * math.sin(a)
        out.append(speed * np.stack([u, v]))
    return np.array(out)


def scenarios(args: argparse.Namespace, where: Path) -> dict[str, Scenario]:
    """The scenario of each motion (the gridded fields written as ``.npy`` in ``where``)."""
    base = load_scenario(args.scenario)
    if args.steps is not None:
        base = load_scenario(base, {"episode.horizon_steps": args.steps})
    over = {
        "target.model": "drift",
        "target.current_kmh": [args.current, 0.0],
        "target.diffusion_m2_s": args.diffusion,
    }
    shape = (base.map.ny, base.map.nx)
    span = base.horizon_steps * base.episode.dt_s
    dt = 60.0 * args.frame_min
    n = math.ceil(span / dt) + 1
    np.save(where / "stationary.npy", swirl(shape, args.swirl, 1))
    np.save(where / "varying.npy", swirl(shape, args.swirl, n))
    still = {"target.field_file": str(where / "stationary.npy")}
    varying = {"target.field_file": str(where / "varying.npy"), "target.field_dt_s": dt}
    sc = load_scenario(base, over)
    return {
        "uniform": sc,
        "stationary": load_scenario(sc, still),
        "varying": load_scenario(sc, varying),
        "reversal": sc,
    }


def reversal_operators(motion, velocity, dt, h, s, shape, side=None):
    """The adjoint used before gridded fields were covered (uniform drift only): the filter at
    ``+v`` forward, at ``-v`` backward."""
    from poc_env.theory import motion as motion_mod

    vel = np.asarray(velocity, dtype=float).reshape(1, 2)

    def op(sign: float):
        def apply(t: int, x: np.ndarray) -> np.ndarray:
            y = np.array(x, dtype=float).reshape(1, *shape)
            if motion.moves:
                motion_mod.predict(motion, y, sign * vel, 0.0, dt, h, s)
            return y.ravel()

        return apply

    return op(1.0), op(-1.0)


def one(name: str, sc: Scenario, belief: np.ndarray, velocity: np.ndarray, s: int):
    """The bound of one motion, and its wall time."""
    import poc_env.theory.moving_bound as mb

    ops = mb.predict_operators
    if name == "reversal":
        mb.predict_operators = reversal_operators  # type: ignore[assignment]
    try:
        t0 = time.perf_counter()
        res = mb.moving_bound(sc, belief, velocity, s)
        return res, time.perf_counter() - t0
    finally:
        mb.predict_operators = ops


def _line(name: str, value: float, note: str = "") -> None:
    print(f"{name:22s} {value:12.6g}  {note}".rstrip(), flush=True)


def main(argv: list[str] | None = None) -> dict[str, float]:
    from poc_env.agents.benchmarks import check_counts
    from poc_env.errors import as_number, check_positive

    args = build_parser().parse_args(argv)
    check_counts(args, runs=1, steps=1, seed=0)
    check_positive("frame_min", args.frame_min)  # the frames' interval divides
    as_number("swirl", args.swirl)  # finite (a NaN was found in a temporary file's velocities)
    from poc_env.envs.parallel import UAVSearchParallelEnv

    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        scs = scenarios(args, Path(tmp))
        env = UAVSearchParallelEnv(scenario=scs["uniform"])
        env.reset(seed=args.seed)
        st = env.sim_state
        assert st.drift is not None
        belief, velocity, s = st.belief[0].copy(), st.drift[0].copy(), env.params.s
        ny, nx = belief.shape
        print(
            f"# {scs['uniform'].name}: {nx} x {ny} fine cells, {scs['uniform'].horizon_steps} "
            f"steps; current {args.current:g} km/h east, D {args.diffusion:g} m^2/s, swirl "
            f"{args.swirl:g} m/s, frames {args.frame_min:g} min apart; one core; medians of "
            f"{args.runs} interleaved runs",
            flush=True,
        )
        one("uniform", scs["uniform"], belief, velocity, s)  # warm-up (JIT, imports)
        times: dict[str, list[float]] = {m: [] for m in MOTIONS}
        results = {}
        for _ in range(args.runs):
            for m in MOTIONS:
                results[m], dt = one(m, scs[m], belief, velocity, s)
                times[m].append(dt)
    for m in MOTIONS:
        r = results[m]
        out[f"{m}_upper"] = float(r.upper)
        out[f"{m}_pos"] = float(r.pos)
        out[f"{m}_s"] = statistics.median(times[m])
        _line(f"{m}_upper", r.upper, f"the bound (kappa {r.kappa:g}, slack {r.slack:.4f})")
        _line(f"{m}_pos", r.pos, "model POS of the effort found")
        _line(f"{m}_s", out[f"{m}_s"], "s, wall time of the bound")
    out["reversal_diff"] = abs(out["uniform_upper"] - out["reversal_upper"])
    _line("reversal_diff", out["reversal_diff"], "|uniform - reversal| bound (one path now)")
    out["time_ratio"] = out["uniform_s"] / out["reversal_s"]
    _line("time_ratio", out["time_ratio"], "uniform (sparse adjoint) / reversal time")
    return out


if __name__ == "__main__":
    from poc_env.agents.benchmarks import run_main

    run_main(main)
