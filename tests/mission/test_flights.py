"""poc_env.agents.testing.flights.fly: the eq. 20 counts the airspace checks rely on."""

from __future__ import annotations

import numpy as np

from poc_env.agents.testing.flights import fly
from poc_env.config import load_scenario

# `small`'s UAVs take off at (20, -5) km heading north: held straight, they cross this zone
ZONE = {"map.no_fly_zones_km": [[[15, 10], [25, 10], [25, 30], [15, 30]]]}


class _Straight:
    """Holds heading, speed and pitch: zero eq. 19 increments for every UAV."""

    def reset(self, env, seed):
        self.agents = list(env.possible_agents)

    def predict(self, obs):
        return {a: np.zeros(3, dtype=np.float32) for a in obs}, None


def test_a_straight_flight_through_a_zone_counts_its_no_fly_steps():
    sc = load_scenario("small", ZONE)
    f = fly(sc, _Straight())
    assert f.nofly_steps > 0
    clear = fly(load_scenario("small"), _Straight())
    assert clear.nofly_steps == 0
    # the same flight without the zone: out of the area at the same steps, same POS up to it
    assert f.oob_steps == clear.oob_steps > 0
    assert 0.0 <= f.posc <= 1.0 and f.landed == clear.landed == 0
