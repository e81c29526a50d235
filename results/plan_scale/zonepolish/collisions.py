"""Where a zone_ab case's flown eq. 21 collision steps happen: ``collisions.py SEED FAMILY``
plans the case (``tests/planning/zone_ab.py``'s ``scenario``) at the default and ``standard``
efforts, flies each once and prints every step with a collision: the step, the UAVs, their
distances to the zones and to their take-off fields (km). From the repository root, one
thread: ``OMP_NUM_THREADS=1 .venv/bin/python results/plan_scale/zonepolish/collisions.py 7
paper``."""

import sys
from pathlib import Path

import numpy as np
import shapely

ROOT = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(ROOT / "tests" / "planning"), str(ROOT / "tests" / "mission")]

import zone_ab  # noqa: E402

from poc_env.agents.experiments.evaluate import play  # noqa: E402
from poc_env.agents.planning.allocation import make_allocation_plan  # noqa: E402
from poc_env.agents.planning.options import PlanOptions  # noqa: E402
from poc_env.envs.parallel import UAVSearchParallelEnv  # noqa: E402
from poc_env.sim.routing import clearance_m  # noqa: E402


def steps(sc, plan, seed: int, prior) -> list[tuple]:
    """(step, UAVs, km to the zones, km to their fields) of every step with a collision."""
    zones = shapely.union_all([shapely.Polygon(z) for z in sc.map.no_fly_zones_m])
    fields = np.asarray(sc.takeoff_m, dtype=float)
    env = UAVSearchParallelEnv(scenario=sc)
    out: list[tuple] = []

    def each(info) -> None:
        hit = [k for k, i in enumerate(info.values()) if i["violation_collision"]]
        if hit:
            xy = env.sim_state.pos[0, :, :2]
            dz = [round(float(zones.distance(shapely.Point(xy[k]))) / 1e3, 1) for k in hit]
            df = [round(float(np.hypot(*(xy[k] - fields[k]))) / 1e3, 1) for k in hit]
            out.append((int(env.sim_state.step[0]), hit, dz, df))

    play(env, zone_ab._Fly(plan), seed, prior, each)
    return out


def main() -> None:
    seed, family = int(sys.argv[1]), sys.argv[2]
    sc, prior = zone_ab.scenario(seed, family)
    print("c", clearance_m(sc), "ds", sc.constraints.safety_distance_m, "dt", sc.episode.dt_s)
    for effort in ("default", "standard"):
        plan = make_allocation_plan(sc, prior=prior, options=PlanOptions.preset(effort))
        got = steps(sc, plan, seed, prior)
        print(effort, len(got))
        for row in got:
            print("  step", row)


if __name__ == "__main__":
    main()
