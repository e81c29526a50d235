"""Time model (eq. 17-18) against hand-computed flights."""

import numpy as np
import pytest

from poc_env.theory.timing import (
    flight_lengths,
    flight_time_from_lengths,
    flight_time_s,
    is_feasible,
    overtime_s,
)

VB, VS = 220 / 3.6, 180 / 3.6  # the paper's v_b and v_s in m/s


def test_eq17_transit_at_cruise_search_at_search_speed():
    takeoff, landing = (0.0, 0.0), (30e3, 0.0)
    wps = np.array([[0.0, 40e3], [30e3, 40e3]])  # 40 km out, 30 km search leg, 40 km back
    assert flight_lengths(takeoff, wps, landing) == pytest.approx((80e3, 30e3))
    t = flight_time_s(takeoff, wps, landing, VB, VS)
    assert t == pytest.approx(80e3 / VB + 30e3 / VS)
    assert t / 3600 == pytest.approx(80 / 220 + 30 / 180)


def test_eq17_vectorised_form_agrees():
    t = flight_time_from_lengths(np.array([80e3, 0.0]), np.array([30e3, 90e3]), VB, VS)
    np.testing.assert_allclose(t, [80e3 / VB + 30e3 / VS, 90e3 / VS])


def test_no_waypoints_is_a_straight_transit():
    assert flight_time_s((0, 0), np.empty((0, 2)), (22e3, 0), VB, VS) == pytest.approx(22e3 / VB)


def test_eq18_feasibility_and_overtime():
    t_lim = 0.85 * 3 * 3600
    assert is_feasible(t_lim, 3 * 3600)
    assert not is_feasible(t_lim + 1.0, 3 * 3600)
    np.testing.assert_allclose(overtime_s([t_lim - 5, t_lim + 7], 3 * 3600), [0.0, 7.0])
