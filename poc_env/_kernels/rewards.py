"""Compiled end of a step: the reward terms and total, the episode end and the info values.

One call per step of the single environment's fast path (:class:`poc_env.sim.single.
SingleStep`) after the core's kernels: the reward terms of :func:`poc_env.sim.rewards.
reward_terms` and their total (:func:`~poc_env.sim.rewards.total_reward`), the episode end of
:func:`poc_env.sim.core.terminal`, :func:`~poc_env.sim.core.truncated` and
:func:`~poc_env.sim.core.episode_over`, and every per-agent info value of
:func:`poc_env.sim.engine.info_parts` but the adjacency rows, grouped by Python type
(:data:`FLOAT_INFOS`, :data:`BOOL_INFOS`, :data:`INT_INFOS`) so that one ``tolist()`` per
group gives Python floats, bools and ints. The numpy functions are the reference;
``tests/sim/test_single.py`` pins this kernel to them bit for bit, sums in numpy's order
(:func:`numpy_sum`: the pairwise summation of ``np.add.reduce``) included.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")

#: Rows of the core step's ``flags`` (the swarm kernels' ``OVERTIME, OOB, ...``: this module
#: may not import them; a test pins them equal).
OVERTIME, OOB, COLLISION, COMMS_OK, LANDED, CRASHED = range(6)

#: The per-agent float info keys, in the order of ``finfo``'s last axis.
FLOAT_INFOS = (
    "pos", "pos_team", "posc", "reward_pos", "reward_time", "reward_violation",
    "reward_overtime", "reward_crash", "flight_time_s", "time_to_detection_s",
)  # fmt: skip
#: The per-agent bool info keys, in the order of ``binfo``'s last axis.
BOOL_INFOS = (
    "violation_out_of_bounds", "violation_no_fly", "violation_collision", "violation_threat",
    "violation_comms", "violation_overtime", "shielded", "landed", "crashed", "target_detected",
    "connected",
)  # fmt: skip
#: The per-agent int info keys, in the order of ``iinfo``'s last axis.
INT_INFOS = ("topology", "violations")
#: ``coef``'s entries: the signed reward coefficients as ``reward_terms`` applies them, then dt.
COEFFICIENTS = ("alpha", "-beta", "-violation_penalty", "-overtime_penalty", "-crash_penalty", "dt")


@_jit
def _block(a, lo, n):
    """numpy's pairwise summation of ``a[lo:lo + n]`` for ``n <= 128`` (one block of
    ``pairwise_sum`` in ``np.add.reduce``): a plain loop from 0.0 below 8 values, else eight
    accumulators, combined as ``((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))``, then the
    remainder one by one."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    stop = n - n % 8
    while i < stop:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@_jit
def _half(n):
    """Where numpy's pairwise summation splits ``n > 128`` values: half, down to a multiple
    of 8."""
    n2 = n // 2
    return n2 - n2 % 8


@_jit
def numpy_sum(row):
    """``row.sum()`` of a 1-d float64 array as numpy computes it: :func:`_block` up to 128
    values, else the sum of the two halves' sums (:func:`_half`), each summed the same way
    (the recursion of numpy's ``pairwise_sum``, walked with an explicit stack: numba compiles
    no recursive function here)."""
    n = row.shape[0]
    if n <= 128:  # numpy adds the blocks' sum to its identity 0.0 (a sum of -0.0s is 0.0)
        return 0.0 + _block(row, 0, n)
    los = np.empty(64, dtype=np.int64)
    ns = np.empty(64, dtype=np.int64)
    stage = np.empty(64, dtype=np.int64)  # 0: new, 1: left half pending, 2: right half pending
    left = np.empty(64)
    top = 0
    los[0], ns[0], stage[0] = 0, n, 0
    ret = 0.0
    returned = False
    while top >= 0:
        lo, m = los[top], ns[top]
        if returned:
            returned = False
            if stage[top] == 1:  # the left half's sum: now the right half
                left[top] = ret
                stage[top] = 2
                h = _half(m)
                top += 1
                los[top], ns[top], stage[top] = lo + h, m - h, 0
            else:
                ret = left[top] + ret
                returned = True
                top -= 1
            continue
        if m <= 128:
            ret = _block(row, lo, m)
            returned = True
            top -= 1
            continue
        stage[top] = 1
        top += 1
        los[top], ns[top], stage[top] = lo, _half(m), 0
    return 0.0 + ret


@_jit
def end_step(events, state, coef, horizon, detection_ends, team_credit, out):
    """The reward terms, reward, episode end and info values of a step, for ``E`` envs of ``N``
    UAVs.

    ``events`` (read): ``(found (E, N), team (E,), time_term (E, N), flags (6, E, N), no_fly,
    threat, shielded (E, N), detected_now, connected (E,))``, the core step's
    :class:`~poc_env.sim.core.Events` (``flags``: its rows :data:`OVERTIME` ...);
    ``state`` (read, after the step): ``(posc, elapsed, detected, detect_step, topology,
    violations, landed, crashed, step_count)``; ``coef``: :data:`COEFFICIENTS`; ``horizon``:
    ``episode.horizon_steps``; ``detection_ends``: ``episode.detection_ends_episode``;
    ``team_credit``: ``reward.credit == "team"``. ``out`` (written): ``(terms (5, E, N),
    reward (E, N), terminated (E, N), truncated (E, N), over (E,), finfo (E, N, 10),
    binfo (E, N, 11), iinfo (E, N, 2))``.

    Each term is ``coefficient * value`` as :func:`~poc_env.sim.rewards.reward_terms` computes
    it (the team's time term the numpy sum of the row divided by ``N``); the reward is
    ``0.0 + pos + time + violation + overtime + crash`` in that order (Python's ``sum``).
    """
    found, team, time_term, flags, nofly, threat, shielded, _, connected = events
    overtime, oob, collision = flags[OVERTIME], flags[OOB], flags[COLLISION]
    comms_ok, crashed_now = flags[COMMS_OK], flags[CRASHED]
    posc, elapsed, detected, detect_step, topology, violations, landed, crashed, step_count = state
    terms, reward, terminated, truncated, over, finfo, binfo, iinfo = out
    alpha, nbeta, nvp, nop, ncp, dt = coef[0], coef[1], coef[2], coef[3], coef[4], coef[5]
    n_env, n = found.shape
    for e in range(n_env):
        time_team = numpy_sum(time_term[e]) / n if team_credit else 0.0
        at_horizon = step_count[e] >= horizon
        all_done = True
        ttd = detect_step[e] * dt if detected[e] else -1.0
        for i in range(n):
            if team_credit:
                t_pos = alpha * team[e]
                t_time = nbeta * time_team
            else:
                t_pos = alpha * found[e, i]
                t_time = nbeta * (time_term[e, i] / n)
            comms_bad = not comms_ok[e, i]
            violation = (oob[e, i] or nofly[e, i] or collision[e, i] or threat[e, i]) or comms_bad
            t_violation = nvp * (1.0 if violation else 0.0)
            t_overtime = nop * (1.0 if overtime[e, i] else 0.0)
            t_crash = ncp * (1.0 if crashed_now[e, i] else 0.0)
            terms[0, e, i] = t_pos
            terms[1, e, i] = t_time
            terms[2, e, i] = t_violation
            terms[3, e, i] = t_overtime
            terms[4, e, i] = t_crash
            reward[e, i] = ((((0.0 + t_pos) + t_time) + t_violation) + t_overtime) + t_crash
            done = landed[e, i] or crashed[e, i]
            if detection_ends:
                done = done or detected[e]
            terminated[e, i] = done
            truncated[e, i] = at_horizon and not done
            all_done = all_done and done
            f = finfo[e, i]
            f[0] = found[e, i]
            f[1] = team[e]
            f[2] = posc[e]
            f[3] = t_pos
            f[4] = t_time
            f[5] = t_violation
            f[6] = t_overtime
            f[7] = t_crash
            f[8] = elapsed[e, i]
            f[9] = ttd
            b = binfo[e, i]
            b[0] = oob[e, i]
            b[1] = nofly[e, i]
            b[2] = collision[e, i]
            b[3] = threat[e, i]
            b[4] = comms_bad
            b[5] = overtime[e, i]
            b[6] = shielded[e, i]
            b[7] = landed[e, i]
            b[8] = crashed[e, i]
            b[9] = detected[e]
            b[10] = connected[e]
            iinfo[e, i, 0] = topology[e]
            iinfo[e, i, 1] = violations[e, i]
        over[e] = at_horizon or all_done
