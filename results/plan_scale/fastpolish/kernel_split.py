"""i24-fastpolish: the exposure kernel's time split (a measurement script, not a test): the
arguments of 1,233 calls of ``exposure_gains`` recorded from a polish (paper_6_2 prior 7, the
default plan, 2 passes with the grade and block moves, W/8-2W), replayed through the kernel and
through a copy of it without the gain's sum (no copy of the old legs' exposure, no scan):
what the candidates' step exposures cost alone. ``python kernel_split.py``; output in
kernel_split.log."""

import time

import numpy as np
from numba import njit

import poc_env.agents.planning.polish as pol
from poc_env._kernels import sensing as S
from poc_env.agents.experiments.evaluate import episode_prior
from poc_env.agents.planning.allocation import make_allocation_plan
from poc_env.config import load_scenario

calls = []
orig = S.exposure_gains


def rec(*a):
    if len(calls) < 4000:
        calls.append(tuple(x.copy() if isinstance(x, np.ndarray) else x for x in a))
    return orig(*a)


pol._sensing.exposure_gains = rec
sc = load_scenario("paper_6_2")
prior = episode_prior(sc, 7)
routes = [u["waypoints_m"] for u in make_allocation_plan(sc, prior=prior)["uavs"]]
pol.polish_for(sc, routes, prior, 2, moves=(*pol.KINDS, "block"), radii=(0.125, 0.25, 0.5, 1, 2))
pol._sensing.exposure_gains = orig
print(len(calls), "calls")


@njit(cache=False, error_model="numpy")
def legs_only(
    live, old_a, old_b, new_a, new_b, first, law, w, cutoff, reach, cell, h, base, work, out
):
    ny, nx = live.shape
    box_o = np.array([ny, 0, nx, 0])
    for o in range(old_a.shape[0]):
        S.leg_exposure(
            law,
            old_a[o, 0],
            old_a[o, 1],
            old_b[o, 0],
            old_b[o, 1],
            w,
            cutoff,
            reach,
            cell,
            h,
            -1.0,
            base,
            box_o,
        )
    box = np.empty(4, np.int64)
    for c in range(first.shape[0] - 1):
        box[:] = box_o
        for i in range(first[c], first[c + 1]):
            S.leg_exposure(
                law,
                new_a[i, 0],
                new_a[i, 1],
                new_b[i, 0],
                new_b[i, 1],
                w,
                cutoff,
                reach,
                cell,
                h,
                1.0,
                work,
                box,
            )
        out[c] = 0.0
    base[:] = 0.0
    work[:] = 0.0


def run(f):
    t = time.process_time()
    for a in calls:
        a = list(a)
        a[-1] = a[-1].copy()
        a[-2][:] = 0.0
        a[-3][:] = 0.0
        f(*a)
    return time.process_time() - t


run(legs_only)
for _ in range(2):
    print(
        "full", round(run(orig), 3), "legs only (no base copy, no scan)", round(run(legs_only), 3)
    )
