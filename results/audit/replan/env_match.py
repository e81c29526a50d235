"""Does replan's eq. 14 match the environment's on the same paths?

Usage: python results/audit/replan/env_match.py SCENARIO [SEED]
Flies ``allocation_plan`` in the PettingZoo environment (episode SEED, the scenario's prior),
records every UAV's position after each step, then sweeps those per-UAV paths with
``replan.searched_belief`` (what ``poc-env replan --tracks`` does) and compares: the POS
found and the belief, cell by cell, against the environment's own ``posc`` and belief.
Also prints what replan finds sweeping the plan's routes (``--plan`` alone).
"""

import sys

import numpy as np

from poc_env.agents.planning.replan import check_paths, plan_paths, searched_belief
from poc_env.agents.policies.registry import make_policy
from poc_env.envs.parallel import UAVSearchParallelEnv
from poc_env.theory.probability_map import Grid, build_prior

name = sys.argv[1]
seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
env = UAVSearchParallelEnv(scenario=name)
sc = env.scenario
prior = build_prior(sc.map)
obs, _ = env.reset(seed=seed, options={"prior": prior})
pol = make_policy("allocation_plan")
pol.reset(env, seed)
track = [env.sim_state.pos[0, :, :2].copy()]
while env.agents:
    actions, _ = pol.predict(obs)
    obs, _, _, _, infos = env.step(actions)
    track.append(env.sim_state.pos[0, :, :2].copy())
st = env.sim_state
pts = np.stack(track)  # (T+1, N, 2)
paths = [pts[:, i] for i in range(pts.shape[1])]
paths = check_paths(sc, paths, [f"uav{i}" for i in range(len(paths))])
belief, found = searched_belief(sc, prior, paths)
grid = Grid.from_config(sc.map)
env_belief = grid.coarsen(st.belief[0], sc.sensor.samples_per_cell)
print(f"{name} seed {seed}: {len(track) - 1} steps of {env.params.dt:g} s, {len(paths)} UAVs")
print(f"  env posc                      {float(st.posc[0]):.6f}")
print(f"  replan on the env's own paths {found:.6f}  (diff {found - float(st.posc[0]):+.2e})")
print(
    f"  max |belief diff| per cell    {np.abs(belief - env_belief).max():.2e} "
    f"(prior max {prior.max():.2e})"
)
_, planned = searched_belief(sc, prior, plan_paths(pol.plan))
print(f"  replan on the plan's routes   {planned:.6f}  (plan posc {pol.plan['posc']:.6f})")
