"""One episode of a policy flown in the PettingZoo environment, its eq. 20 steps counted.

The airspace tests and scripts (``tests/conftest.py``'s ``fly`` fixture,
``tests/mission/airspace_figures.py``, ``tests/mission/nofly_ab.py``) all ask the same
question of a flight: how many UAV-steps broke the no-fly rule or left the operating area
(the environment's ``violation_no_fly`` / ``violation_out_of_bounds`` infos, eq. 20) or came
within d_s of another UAV (``violation_collision``, eq. 21), how
many UAVs landed and what POS the episode reached. :func:`fly` is that loop, once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Flight:
    """What one flown episode gives the airspace checks."""

    #: UAV-steps with ``violation_no_fly`` (eq. 20), summed over the UAVs and steps
    nofly_steps: int
    #: UAV-steps with ``violation_out_of_bounds``, summed likewise
    oob_steps: int
    #: UAVs landed at the episode's end
    landed: int
    #: POS at the episode's end (``posc``)
    posc: float
    #: UAV-steps with ``violation_collision`` (eq. 21), summed likewise (i24-deconflict)
    collision_steps: int = 0


def fly(scenario: Any, policy: Any, seed: int = 0, prior: Any = None) -> Flight:
    """Fly ``policy`` (``reset(env, seed)`` / ``predict(obs)``) for one episode of a fresh
    ``parallel_env(scenario)`` reset with ``seed`` (and ``prior``, if given, as the reset's
    ``options["prior"]``) and count its eq. 20 steps."""
    from poc_env.agents.experiments.evaluate import play
    from poc_env.envs.parallel import UAVSearchParallelEnv

    env = UAVSearchParallelEnv(scenario=scenario)
    counts = [0, 0, 0]

    def count(info) -> None:
        counts[0] += sum(int(i["violation_no_fly"]) for i in info.values())
        counts[1] += sum(int(i["violation_out_of_bounds"]) for i in info.values())
        counts[2] += sum(int(i["violation_collision"]) for i in info.values())

    play(env, policy, seed, prior, count)
    nofly, oob, collision = counts
    st = env.sim_state
    flight = Flight(nofly, oob, int(st.landed[0].sum()), float(st.posc[0]), collision)
    env.close()
    return flight
