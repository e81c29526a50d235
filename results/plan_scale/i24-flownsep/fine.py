"""i24-flownsep, a measured alternative not kept: the lanes' conflict check every dt / 4.

``python fine.py CASE N OUT.jsonl`` (flown.py's ``case`` arguments): flown.py's record of the
``allocation_plan`` flight when :func:`~poc_env.agents.planning.deconflict.in_lanes` checks its
candidates on a scenario whose ``episode.dt_s`` is a quarter of the real one (planned
positions every dt / 4, :data:`~poc_env.agents.planning.deconflict.SLACK_S`'s lags in those
steps), so two UAVs flying one route less than one dt apart in trail are seen (the big
scenario's UAVs 12 and 13: one box 24 s apart, 1.58 km at every whole step, 0.3 km flown).
The flight itself is the environment's, at the real dt.
"""

import dataclasses
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import flown

import poc_env.agents.planning.allocation as allocation

real = allocation.in_lanes


def fine(sc, routes, v, around):
    ep = dataclasses.replace(sc.episode, dt_s=sc.episode.dt_s / 4)
    return real(dataclasses.replace(sc, episode=ep), routes, v, around)


if __name__ == "__main__":
    allocation.in_lanes = fine
    flown.main(sys.argv)
