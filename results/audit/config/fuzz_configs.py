"""Seeded fuzzer of scenario configs far from the paper's values (config-audit).

Draws scenario overrides across their documented ranges and past them (grid shapes, cell
sizes, fleets, airfields, speeds, turn limits, time steps, comms against the safety distance,
horizons, sweep widths, priors, drift currents, reward options, control levels and
observation types) and runs every drawn config through the whole user path:

1. ``load_scenario("small", overrides)``: a ``ConfigError`` naming the field, the value and
   what is allowed is a *refusal* (nothing built, nothing written); any other exception is a
   defect.
2. the PettingZoo parallel env, random actions to the episode's end (at most ``--max-steps``
   steps), checking every step: observations and rewards finite and inside their spaces, POSC
   in [0, 1], eq. 14's belief a probability (entries >= 0, sum <= the initial mass) whose
   mass (belief + POSC + mass that drifted out) is kept, and the episode ending by its
   horizon; the AEC env for a few steps; ``pettingzoo.test.parallel_api_test`` on every
   ``--api-every``-th loaded case.
3. (``--heavy`` share of the loaded cases) the ``allocation`` planner (refine 0) and the ``de``
   planner (NP 8, G 3): plan POS values finite and in [0, 1], the allocation plan's POS_C at
   most its rule-aware bound; ``evaluate`` of one episode of ``greedy_bayes``,
   ``greedy_rectangles`` and ``lawnmower``: POSC finite in [0, 1] and at most the reach-aware
   bound (static targets; both bounds with :data:`BOUND_SLACK`); the
   allocation plan exported as GeoJSON and QGC (a refusal must leave the folder empty).

4. (``--cli`` share of all cases) the command line: ``poc-env plan --planner allocation
   --refine 0 --overrides ...`` and ``poc-env export --format geojson``: exit 0 with the files,
   or exit 2 with ``error: FIELD: got ...; allowed: ...``, no traceback and nothing written; a
   config ``load_scenario`` refuses must be refused by the command too.

Each case runs under a time limit (``--case-timeout``); a case past it is a ``hang``.

Usage (one thread, in the background)::

    OMP_NUM_THREADS=1 nice -n 10 .venv/bin/python results/audit/config/fuzz_configs.py \
        --seed 1 --cases 300 --out results/audit/config/fuzz_seed1.jsonl

Writes one JSON line per case (its overrides, outcome, stage and detail) and prints the counts
per outcome. Outcomes: ``refused`` (a clear ConfigError at load), ``ok`` (everything ran and
every check held), ``refused_later`` (a clear ConfigError from a planner, evaluate or export
on a config that loaded), ``unclear`` (a poc-env error without ``allowed``), ``traceback``,
``wrong`` (a check failed), ``hang``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from poc_env.agents.testing.campaign import CaseTimeout, time_limit
from poc_env.errors import ConfigError, PocEnvError


class Wrong(AssertionError):
    """A check on a config that loaded failed."""


def check(ok: bool, what: str) -> None:
    if not ok:
        raise Wrong(what)


# --------------------------------------------------------------------------- the draws

#: the base scenario ``small``: 40 x 40 km in 5 km cells, airfield A at (20, -5)
BASE = "small"


def draw_grid(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["1xN", "Nx1", "1x1", "200x200", "tiny_cell", "huge_cell", "odd"])
    if kind == "1xN":
        c = float(rng.choice([0.5, 5.0, 20.0]))
        return {"map.cell_km": c, "map.width_km": c, "map.height_km": c * int(rng.integers(2, 40))}
    if kind == "Nx1":
        c = float(rng.choice([0.5, 5.0, 20.0]))
        return {"map.cell_km": c, "map.height_km": c, "map.width_km": c * int(rng.integers(2, 40))}
    if kind == "1x1":
        c = float(rng.choice([0.01, 1.0, 40.0, 400.0]))
        return {"map.cell_km": c, "map.width_km": c, "map.height_km": c}
    if kind == "200x200":
        c = float(rng.choice([0.2, 1.0, 2.0]))
        return {"map.cell_km": c, "map.width_km": 200 * c, "map.height_km": 200 * c}
    if kind == "tiny_cell":
        c = float(rng.choice([0.01, 0.005, 1e-9]))
        return {"map.cell_km": c, "map.width_km": 8 * c, "map.height_km": 8 * c}
    if kind == "huge_cell":
        c = float(rng.choice([500.0, 1000.0, 2000.0, 2500.0]))
        return {"map.cell_km": c, "map.width_km": c, "map.height_km": c}
    return {"map.cell_km": 3.0, "map.width_km": 40.0}  # not a multiple: refused


def draw_fleet(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["one", "24", "64", "65", "zero", "crowd", "many_fields", "far_field"])
    if kind == "one":
        return {"fleet": [{"takeoff": "A", "count": 1}]}
    if kind == "24":
        return {"fleet": [{"takeoff": "A", "count": 24}]}
    if kind == "64":
        return {"fleet": [{"takeoff": "A", "count": 64}]}
    if kind == "65":
        return {"fleet": [{"takeoff": "A", "count": 65}]}
    if kind == "zero":
        return {"fleet": [{"takeoff": "A", "count": 0}]}
    if kind == "crowd":  # more UAVs than fit the safety distance around the field
        return {
            "fleet": [{"takeoff": "A", "count": int(rng.integers(6, 30))}],
            "constraints.safety_distance_km": float(rng.choice([5.0, 50.0, 500.0])),
        }
    if kind == "many_fields":
        k = int(rng.integers(2, 12))
        fields = [
            {"name": f"F{i}", "position_km": [float(x) for x in rng.uniform(-50, 90, 2)]}
            for i in range(k)
        ]
        fleet = [{"takeoff": f"F{i}", "count": int(rng.integers(1, 4)),
                  "landing": f"F{int(rng.integers(0, k))}"} for i in range(k)]  # fmt: skip
        return {"airfields": fields, "fleet": fleet}
    # an airfield far from the map (maybe beyond any reach)
    d = float(rng.choice([200.0, 1000.0, 5000.0]))
    return {"airfields": [{"name": "A", "position_km": [d, d]}]}


def draw_speeds(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["vmin=vmax", "slow", "fast", "turn0", "turn_tiny", "turn_huge", "accel"])
    if kind == "vmin=vmax":
        v = float(rng.choice([150.0, 180.0, 220.0]))
        return {f"uav.{k}": v for k in ("min_speed_kmh", "max_speed_kmh", "cruise_speed_kmh",
                                        "search_speed_kmh")}  # fmt: skip
    if kind == "slow":
        return {f"uav.{k}": v for k, v in (("min_speed_kmh", 1e-3), ("max_speed_kmh", 1.0),
                ("cruise_speed_kmh", 0.5), ("search_speed_kmh", 0.5))}  # fmt: skip
    if kind == "fast":
        return {f"uav.{k}": v for k, v in (("min_speed_kmh", 1000.0), ("max_speed_kmh", 1500.0),
                ("cruise_speed_kmh", 1500.0), ("search_speed_kmh", 1200.0))}  # fmt: skip
    if kind == "turn0":
        return {"uav.max_turn_rate_deg_s": 0.0}
    if kind == "turn_tiny":
        return {"uav.max_turn_rate_deg_s": 1e-9}
    if kind == "turn_huge":
        return {"uav.max_turn_rate_deg_s": float(rng.choice([180.0, 3600.0, 1e6]))}
    return {"uav.max_accel_mps2": float(rng.choice([1e-9, 100.0, 1e4]))}


def draw_time(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["dt_big", "dt_tiny", "horizon1", "horizon2", "endurance", "dt_over"])
    if kind == "dt_big":
        return {"episode.dt_s": float(rng.choice([600.0, 1800.0, 3600.0]))}
    if kind == "dt_tiny":
        return {"episode.dt_s": float(rng.choice([1e-3, 0.1])), "episode.horizon_steps": 50}
    if kind == "horizon1":
        return {"episode.horizon_steps": 1}
    if kind == "horizon2":
        return {"episode.horizon_steps": 2}
    if kind == "endurance":
        return {"uav.endurance_h": float(rng.choice([0.01, 0.05, 240.0]))}
    return {"episode.dt_s": 7200.0}


def draw_comms(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["below_safety", "tiny", "neighbours", "links_fail", "comms_belief"])
    if kind == "below_safety":
        return {"comms.range_km": 0.5, "constraints.safety_distance_km": 2.0}
    if kind == "tiny":
        return {"comms.range_km": 1e-6}
    if kind == "neighbours":
        return {"comms.min_neighbours": int(rng.choice([5, 63, 64]))}
    if kind == "links_fail":
        return {"comms.link_failure_prob": 1.0, "comms.belief_sharing": "comms"}
    return {"comms.belief_sharing": "comms", "comms.range_km": float(rng.choice([1e-3, 1.0]))}


def draw_sensor(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["wide", "max", "tiny", "law", "samples", "cutoff", "over"])
    if kind == "wide":
        return {"sensor.sweep_width_km": float(rng.choice([100.0, 400.0]))}
    if kind == "max":
        return {"sensor.sweep_width_km": 1000.0}
    if kind == "tiny":
        return {"sensor.sweep_width_km": float(rng.choice([1e-6, 1e-3]))}
    if kind == "law":
        return {"sensor.law": str(rng.choice(["exponential", "definite_range"])),
                "sensor.sweep_width_km": float(rng.choice([0.01, 5.0, 200.0]))}  # fmt: skip
    if kind == "samples":
        return {"sensor.samples_per_cell": int(rng.choice([1, 16, 17]))}
    if kind == "cutoff":
        return {"sensor.cutoff_sweep_widths": float(rng.choice([0.5, 100.0]))}
    return {"sensor.sweep_width_km": 5000.0}


def draw_prior(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["point", "one_cell", "zero", "nan", "background_only", "outside", "neg"])
    if kind == "point":
        return {"map.prior.components": [{"mean_km": [12.0, 25.0], "sigma_km": [1e-6, 1e-6]}],
                "map.prior.background": 0.0}  # fmt: skip
    if kind == "background_only":
        return {"map.prior.components": [], "map.prior.background": 1.0}
    if kind == "outside":  # all of the mixture far off the map
        return {"map.prior.components": [{"mean_km": [5000.0, 5000.0], "sigma_km": [1.0, 1.0]}],
                "map.prior.background": 0.0}  # fmt: skip
    return {"__prior_file__": str(kind)}  # written once the grid is known


def draw_motion(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["zero", "strong", "random", "diffusion", "too_fast"])
    out: dict[str, Any] = {"target.model": "drift"}
    if kind == "zero":
        out.update({"target.current_kmh": [0.0, 0.0], "target.diffusion_m2_s": 0.0})
    elif kind == "strong":
        out.update({"target.current_kmh": [float(rng.choice([50.0, 90.0])), 0.0],
                    "target.diffusion_m2_s": 50.0})  # fmt: skip
    elif kind == "random":
        out.update({"target.random_current_kmh": 100.0})
    elif kind == "diffusion":
        out.update({"target.diffusion_m2_s": float(rng.choice([1e4, 1e7]))})
    else:
        out.update({"target.current_kmh": [399.0, 0.0]})
    return out


def draw_reward(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["individual", "zero", "huge", "beta", "terminate", "shield", "detect"])
    if kind == "individual":
        return {"reward.credit": "individual"}
    if kind == "zero":
        return {f"reward.{k}": 0.0 for k in ("alpha", "violation_penalty", "overtime_penalty",
                                             "crash_penalty")}  # fmt: skip
    if kind == "huge":
        return {f"reward.{k}": 1e9 for k in ("alpha", "beta", "violation_penalty",
                                             "overtime_penalty", "crash_penalty")}  # fmt: skip
    if kind == "beta":
        return {"reward.beta": 1.0, "reward.credit": "individual"}
    if kind == "terminate":
        return {"constraints.violation": "terminate"}
    if kind == "shield":
        return {"constraints.violation": "shield"}
    return {"episode.detection_ends_episode": True}


def draw_area(rng: np.random.Generator) -> dict[str, Any]:
    kind = rng.choice(["margin0", "landing_tiny", "landing_huge", "usable"])
    if kind == "margin0":
        return {"episode.boundary_margin_km": 0.0}
    if kind == "landing_tiny":
        return {"episode.landing_radius_km": 1e-6}
    if kind == "landing_huge":
        return {"episode.landing_radius_km": 2000.0}
    return {"uav.usable_fraction": float(rng.choice([0.01, 1.0]))}


AXES = {
    "grid": draw_grid,
    "fleet": draw_fleet,
    "speeds": draw_speeds,
    "time": draw_time,
    "comms": draw_comms,
    "sensor": draw_sensor,
    "prior": draw_prior,
    "motion": draw_motion,
    "reward": draw_reward,
    "area": draw_area,
}

ENV_KW = [
    {"obs_type": "compass", "control": "heading"},
    {"obs_type": "set", "control": "heading_clip"},
    {"obs_type": "flat", "control": "increments"},
    {"obs_type": "dict", "control": "waypoint"},
    {"obs_type": "compass", "control": "increments"},
]


def draw_case(rng: np.random.Generator) -> tuple[dict[str, Any], dict[str, Any], list[str]]:
    """(overrides, env keyword arguments, the axes drawn) of one case: 1 to 6 axes; half the
    cases cut the episode at 40 steps, the others keep the scenario's horizon (endurance / dt,
    so that landings and endurance ends are reached); a fifth draw a random prior at reset,
    a tenth random airfields."""
    k = int(rng.integers(1, 7))
    axes = sorted(rng.choice(sorted(AXES), size=k, replace=False).tolist())
    overrides: dict[str, Any] = {"episode.horizon_steps": 40} if rng.random() < 0.5 else {}
    for a in axes:
        overrides.update(AXES[a](rng))
    env_kw = dict(ENV_KW[int(rng.integers(len(ENV_KW)))])
    if rng.random() < 0.2:
        env_kw["random_prior"] = True
    if rng.random() < 0.1:
        env_kw["random_airfields"] = True
    return overrides, env_kw, axes


def write_prior_file(overrides: dict[str, Any], folder: Path, rng: np.random.Generator) -> None:
    """Replace ``__prior_file__`` by a ``map.prior`` of ``kind: file`` on the drawn grid."""
    kind = overrides.pop("__prior_file__", None)
    if kind is None:
        return
    cell = float(overrides.get("map.cell_km", 5.0))
    nx = max(1, round(float(overrides.get("map.width_km", 40.0)) / cell))
    ny = max(1, round(float(overrides.get("map.height_km", 40.0)) / cell))
    if nx * ny > 4_000_000:
        nx = ny = 8
    grid = np.zeros((ny, nx))
    if kind == "one_cell":
        grid[int(rng.integers(ny)), int(rng.integers(nx))] = 1.0
    elif kind == "nan":
        grid[:] = 1.0
        grid[0, 0] = np.nan
    elif kind == "neg":
        grid[:] = 1.0
        grid[-1, -1] = -0.5
    path = folder / f"prior_{kind}.npy"
    np.save(path, grid)
    overrides["map.prior"] = {"kind": "file", "file": str(path)}


# --------------------------------------------------------------------------- the checks


def check_env(sc: Any, env_kw: dict[str, Any], seed: int, max_steps: int, api: bool) -> int:
    """Random actions to the end of an episode; every step's invariants. Returns steps run."""
    import poc_env

    env = poc_env.parallel_env(sc, **env_kw)
    obs, infos = env.reset(seed=seed)
    check(set(obs) == set(env.possible_agents), "reset: an agent without an observation")
    rng = np.random.default_rng(seed)
    horizon = sc.horizon_steps
    st = env.sim_state
    m0 = float(st.initial_mass[0])
    check(math.isfinite(m0) and 0.0 < m0 <= 1.0 + 1e-9, f"initial mass {m0!r}")
    steps = 0

    def check_obs(o: dict[str, Any], when: str) -> None:
        for a, ob in o.items():
            space = env.observation_space(a)
            leaves = ob.values() if isinstance(ob, dict) else [ob]
            for x in leaves:
                check(bool(np.all(np.isfinite(x))), f"{when}: observation of {a} not finite")
            check(space.contains(ob), f"{when}: observation of {a} outside its space")

    check_obs(obs, "reset")
    while env.agents and steps < max_steps:
        actions = {
            a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents
        }
        obs, rew, _, _, infos = env.step(actions)
        steps += 1
        check_obs(obs, f"step {steps}")
        for a, r in rew.items():
            check(math.isfinite(r), f"step {steps}: reward of {a} = {r!r}")
        posc = float(st.posc[0])
        check(math.isfinite(posc) and -1e-12 <= posc <= 1.0 + 1e-9, f"step {steps}: POSC {posc!r}")
        b = st.belief[0]
        check(bool(np.all(np.isfinite(b))), f"step {steps}: belief not finite")
        check(float(b.min()) >= 0.0, f"step {steps}: belief entry {float(b.min())!r} < 0")
        check(float(b.sum()) <= m0 + 1e-9, f"step {steps}: belief sum {float(b.sum())!r} > {m0}")
        out = 0.0 if st.mass_out is None else float(st.mass_out[0])
        mass = posc + float(b.sum()) + out
        check(abs(mass - m0) < 1e-9, f"step {steps}: mass {mass!r}, initial {m0!r}")
        for a in rew:
            for key in ("pos", "posc"):
                v = infos.get(a, {}).get(key)
                if v is not None:
                    check(math.isfinite(float(v)) and -1e-12 <= float(v) <= 1 + 1e-9,
                          f"step {steps}: info {key} of {a} = {v!r}")  # fmt: skip
    if horizon <= max_steps:
        check(not env.agents, f"episode still running after its horizon {horizon} ({steps} steps)")
    env.close()
    # the AEC view, a few steps
    aec = poc_env.env(sc, **env_kw)
    aec.reset(seed=seed)
    for _, agent in zip(range(3 * len(aec.possible_agents)), aec.agent_iter()):
        _, r, te, tr, _ = aec.last()
        check(math.isfinite(float(r)), f"AEC reward of {agent} = {r!r}")
        act = rng.uniform(-1, 1, aec.action_space(agent).shape).astype(np.float32)
        aec.step(None if te or tr else act)
    aec.close()
    if api:
        from pettingzoo.test import parallel_api_test

        parallel_api_test(poc_env.parallel_env(sc, **env_kw), num_cycles=5)
    return steps


#: a flown or planned POS may pass a bound by the sample lattice's 1.2 % under the
#: inverse-cube law (poc_env.theory.bound's module docstring); anything more is a defect
BOUND_SLACK = 1.02


def check_plans(sc: Any, folder: Path) -> None:
    """The allocation and DE planners, evaluate of one episode, and an export."""
    from poc_env.agents.experiments.evaluate import evaluate
    from poc_env.agents.mission.export import export_plan
    from poc_env.agents.mission.plan import write_plan
    from poc_env.agents.planning.planner import make_plan
    from poc_env.config import save_scenario

    yaml_path = save_scenario(sc, folder / "scenario.yaml")
    plans = {}
    for planner, kw in (("allocation", {"refine": 0}), ("de", {"popsize": 8, "maxiter": 3})):
        plan = make_plan(sc, planner=planner, seed=0, **kw)
        for key in ("posc", "upper_bound"):
            v = plan.get(key)
            check(v is not None and math.isfinite(v) and -1e-12 <= v <= 1 + 1e-9,
                  f"{planner} plan {key} = {v!r}")  # fmt: skip
        for u in plan["uavs"]:
            for key in ("pos", "poc", "pod"):
                v = u[key]
                check(math.isfinite(v) and -1e-12 <= v <= 1 + 1e-9,
                      f"{planner} plan uav {u['id']} {key} = {v!r}")  # fmt: skip
        plans[planner] = plan
    rule = plans["allocation"].get("bound_rule")
    if rule is not None and not sc.target.moves:  # a plan that beats the certified bound
        posc = plans["allocation"]["posc"]
        check(posc <= BOUND_SLACK * rule + 1e-9, f"allocation POS_C {posc!r} > rule bound {rule!r}")
    ev = evaluate(sc, ["greedy_bayes", "greedy_rectangles", "lawnmower"], episodes=1, seed0=5000)
    for e in ev.episodes:
        for key in ("posc", "bound", "bound_reach", "bound_rule"):
            v = getattr(e, key)
            check(v is None or (math.isfinite(v) and -1e-12 <= v <= 1 + 1e-9),
                  f"evaluate {e.policy} {key} = {v!r}")  # fmt: skip
        if not sc.target.moves and e.bound_reach is not None:  # flown above the bound
            check(e.posc <= BOUND_SLACK * e.bound_reach + 1e-9,
                  f"{e.policy} POSC {e.posc!r} > reach bound {e.bound_reach!r}")  # fmt: skip
    plan = {**plans["allocation"], "scenario_file": str(yaml_path.resolve())}
    plan_path = write_plan(plan, folder / "plan.json")
    for fmt in ("geojson", "qgc"):
        out = folder / f"export_{fmt}"
        out.mkdir()
        try:
            export_plan(plan_path, fmt, (45.0, 7.0), out)
        except ConfigError:
            check(not any(out.iterdir()), f"export {fmt}: refused but wrote {list(out.iterdir())}")
            raise


def cli_overrides(overrides: dict[str, Any]) -> list[str]:
    """The overrides as the command line's ``--overrides KEY=VALUE`` items (YAML flow)."""
    import yaml

    return [f"{k}={yaml.safe_dump(v, default_flow_style=True, width=10**6).strip()}"
            .removesuffix("\n...") for k, v in overrides.items()]  # fmt: skip


def check_cli(overrides: dict[str, Any], folder: Path) -> str:
    """``poc-env plan --planner allocation --refine 0`` then ``poc-env export --format
    geojson`` with the case's ``--overrides``: exit 0 with the files, or exit 2 with one
    ``error: FIELD: got ...; allowed: ...`` line, no traceback and nothing written.
    Returns ``ok`` or ``refused``."""
    import subprocess

    exe = str(Path(sys.executable).with_name("poc-env"))
    out = folder / "cli" / "plan.json"
    cmd = [exe, "plan", "--scenario", BASE, "--planner", "allocation", "--refine", "0",
           "--quiet", "--origin", "45.0,7.0", "--out", str(out),
           "--overrides", *cli_overrides(overrides)]  # fmt: skip
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
    if r.returncode != 0:
        check("Traceback" not in r.stderr, f"CLI plan: a traceback: {r.stderr[-800:]}")
        check(r.returncode == 2 and "allowed:" in r.stderr and r.stderr.startswith("error: "),
              f"CLI plan exit {r.returncode}: {r.stderr[-800:]}")  # fmt: skip
        check(not out.exists(), "CLI plan refused but wrote plan.json")
        return "refused"
    check(out.is_file(), "CLI plan exit 0 without plan.json")
    plan = json.loads(out.read_text())
    check(0.0 <= plan["posc"] <= 1.0, f"CLI plan POS_C {plan['posc']!r}")
    exp = folder / "cli" / "export"
    r = subprocess.run([exe, "export", str(out), "--format", "geojson", "--out", str(exp)],
                       capture_output=True, text=True, timeout=600, check=False)  # fmt: skip
    if r.returncode != 0:
        check("Traceback" not in r.stderr, f"CLI export: a traceback: {r.stderr[-800:]}")
        check(r.returncode == 2 and "allowed:" in r.stderr,
              f"CLI export exit {r.returncode}: {r.stderr[-800:]}")  # fmt: skip
        check(not exp.exists() or not any(exp.iterdir()), "CLI export refused but wrote files")
        return "refused"
    check(any(exp.glob("*.geojson")), "CLI export exit 0 without a .geojson")
    return "ok"


def run_case(
    case: dict[str, Any], folder: Path, max_steps: int, api: bool, heavy: bool, cli: bool
) -> tuple[str, str, str]:
    """(outcome, stage, detail) of one case."""
    from poc_env.config import load_scenario

    stage = "load"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                sc = load_scenario(BASE, case["overrides"])
            except ConfigError as err:
                text = str(err)
                ok = "allowed" in text and bool(err.field)
                if ok and cli:  # the command line must refuse it the same way
                    stage = "cli"
                    check(check_cli(case["overrides"], folder) == "refused",
                          "CLI plan ran a config load_scenario refuses")  # fmt: skip
                return ("refused" if ok else "unclear"), "load", text
            stage = "env"
            check_env(sc, case["env_kw"], case["seed"], max_steps, api)
            if heavy:
                stage = "plans"
                check_plans(sc, folder)
            if cli:
                stage = "cli"
                check_cli(case["overrides"], folder)
    except CaseTimeout as err:
        return "hang", stage, str(err)
    except Wrong as err:
        return "wrong", stage, str(err)
    except PocEnvError as err:
        text = str(err)
        if stage == "load":
            return "unclear", stage, text
        return ("refused_later" if "allowed" in text else "unclear"), stage, text
    except Exception:
        return "traceback", stage, traceback.format_exc(limit=-4)
    return "ok", stage, ""


OUTCOMES = ("ok", "refused", "refused_later", "unclear", "traceback", "wrong", "hang")


def summarise(paths: list[str]) -> str:
    """A markdown table of the outcomes of fuzzer records (JSON lines files), one row each."""
    head = "| records | tried | " + " | ".join(OUTCOMES) + " | seconds |"
    rows = [head, "|" + "---|" * (len(OUTCOMES) + 3)]
    for path in paths:
        recs = [json.loads(line) for line in Path(path).read_text().splitlines() if line]
        c = Counter(r["outcome"] for r in recs)
        secs = sum(float(r.get("seconds", 0.0)) for r in recs)
        cells = " | ".join(str(c[o]) for o in OUTCOMES)
        rows.append(f"| {Path(path).name} | {len(recs)} | {cells} | {secs:.0f} |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--cases", type=int, default=200)
    p.add_argument("--out", default=None, help="JSON lines of the cases")
    p.add_argument("--max-steps", type=int, default=400)
    p.add_argument("--api-every", type=int, default=5)
    p.add_argument("--heavy", type=float, default=0.3, help="share of loaded cases planned")
    p.add_argument("--cli", type=float, default=0.1, help="share of cases run by poc-env")
    p.add_argument("--case-timeout", type=float, default=300.0)
    p.add_argument("--only", default=None, help="run only this case index (a re-run)")
    p.add_argument("--summarise", nargs="+", default=None, help="print records' counts only")
    args = p.parse_args(argv)
    if args.summarise:
        print(summarise(args.summarise))
        return 0
    rng = np.random.default_rng(args.seed)
    counts: Counter = Counter()
    loaded = 0
    out = open(args.out, "w", encoding="utf-8") if args.out else None  # noqa: SIM115
    for i in range(args.cases):
        overrides, env_kw, axes = draw_case(rng)
        case_rng = np.random.default_rng([args.seed, i])
        heavy = bool(case_rng.random() < args.heavy)
        cli = bool(case_rng.random() < args.cli)
        if args.only is not None and i != int(args.only):
            continue
        with tempfile.TemporaryDirectory(prefix="cfgfuzz_") as tmp:
            write_prior_file(overrides, Path(tmp), case_rng)
            case = {"overrides": overrides, "env_kw": env_kw, "seed": 5000 + i}
            api = loaded % args.api_every == 0
            t0 = time.perf_counter()
            with time_limit(args.case_timeout):
                try:
                    outcome, stage, detail = run_case(
                        case, Path(tmp), args.max_steps, api, heavy, cli
                    )
                except CaseTimeout as err:
                    outcome, stage, detail = "hang", "?", str(err)
            seconds = time.perf_counter() - t0
            shown = {k: (v if k != "map.prior" else {"kind": "file", "file": Path(v["file"]).name})
                     for k, v in overrides.items()}  # fmt: skip
        if outcome != "refused":
            loaded += 1
        counts[outcome] += 1
        rec = {"case": i, "axes": axes, "overrides": shown, "env_kw": env_kw, "heavy": heavy,
               "cli": cli, "outcome": outcome, "stage": stage, "seconds": round(seconds, 2),
               "detail": detail[-1500:]}  # fmt: skip
        if out:
            out.write(json.dumps(rec, default=str) + "\n")
            out.flush()
        if outcome not in ("refused", "ok", "refused_later"):
            print(f"case {i} {outcome} at {stage}: {axes} {shown} {env_kw}", flush=True)
            print(f"  {detail[-600:]}", flush=True)
    if out:
        out.close()
    print("counts:", dict(sorted(counts.items())), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
