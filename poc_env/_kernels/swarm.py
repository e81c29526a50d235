"""Compiled swarm geometry: pairwise distances, eq. 20-21 and 24, and the simulator step.

The pairwise distances of the UAVs, the boundary (eq. 20) and separation (eq. 21) checks
(:mod:`poc_env.sim.constraints`), the in-range graph, the two-neighbour rule (eq. 24) and the
auto topology (:mod:`poc_env.sim.comms`), and the bookkeeping of the simulator step after
sensing (:mod:`poc_env.sim.core`), which applies these same kernels to the new positions.
They share one file because the step calls them (the cache rule, :mod:`poc_env._kernels`:
a kernel module imports nothing of the project).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_jit = njit(cache=True, error_model="numpy")

# ------------------------------------------------------------------------- constraints (eq. 20-21)


@_jit
def _outside(x, y, x0, y0, x1, y1):
    """Point (x, y) lies outside the rectangle [x0, x1] x [y0, y1] (eq. 20, ``Omega_b``)."""
    return x < x0 or x > x1 or y < y0 or y > y1


@_jit
def outside_boundary(p, x0, y0, x1, y1, out):
    """:func:`_outside` of every point ``p (P, 2)`` into ``out (P,)``."""
    for k in range(p.shape[0]):
        out[k] = _outside(p[k, 0], p[k, 1], x0, y0, x1, y1)


@_jit
def pairwise_distances(p, out):
    """Distances ``out (B, n, n)`` of the points ``p (B, n, d)``: sqrt(0 + dx0^2 + dx1^2 ...)."""
    n_b, n, d = p.shape
    for b in range(n_b):
        for i in range(n):
            for j in range(n):
                d2 = 0.0
                for k in range(d):
                    c = p[b, i, k] - p[b, j, k]
                    d2 += c * c
                out[b, i, j] = math.sqrt(d2)


@_jit
def separation(dist, d_s, act, use_act, pairs, per_agent):
    """Eq. 21 on distances ``dist (B, n, n)``: ``pairs`` closer than ``d_s`` between distinct
    (and, with ``use_act``, active) UAVs; ``per_agent (B, n)`` has at least one such pair."""
    n_b, n = dist.shape[0], dist.shape[1]
    for b in range(n_b):
        for i in range(n):
            hit = False
            for j in range(n):
                v = i != j and dist[b, i, j] < d_s
                if use_act:
                    v = v and act[b, i] and act[b, j]
                pairs[b, i, j] = v
                hit = hit or v
            per_agent[b, i] = hit


# -------------------------------------------------------------------------- communication (eq. 24)


@_jit
def in_range(dist, range_m, act, out):
    """Eq. 24 adjacency ``out (B, n, n)``: distinct active UAVs with ``dist <= range_m``."""
    n_b, n = out.shape[0], out.shape[1]
    for b in range(n_b):
        for i in range(n):
            ai = act[b, i]
            for j in range(n):
                out[b, i, j] = ai and act[b, j] and i != j and dist[b, i, j] <= range_m


@_jit
def two_neighbour(adj, min_neighbours, act, use_act, out):
    """The §3.2.4 rule per UAV into ``out (B, n)``, see :func:`two_neighbour_ok`."""
    n_b, n = adj.shape[0], adj.shape[1]
    for b in range(n_b):
        need = min_neighbours
        if use_act:
            n_act = 0
            for i in range(n):
                if act[b, i]:
                    n_act += 1
            need = min(min_neighbours, n_act - 1)
        for i in range(n):
            count = 0
            for j in range(n):
                if adj[b, i, j]:
                    count += 1
            out[b, i] = (use_act and not act[b, i]) or count >= need


@_jit
def auto_topology(av, dist, use_dist, act, k_nearest, links, n_comp):
    """:func:`auto_topology` of each env into ``links (E, n, n)`` and ``n_comp (E,)``.

    A pair is available when ``av`` says so, both UAVs are active and they are distinct; it
    weighs ``dist`` (or 1 without ``use_dist``), an unavailable pair ``inf``. Prim's algorithm
    as in the docstring of :func:`auto_topology`: each round takes the unvisited UAV of
    smallest key (the first on ties), or starts a new component at the first unvisited UAV
    when no key is finite; then every UAV's ``k_nearest`` lightest available links (the first
    on ties).
    """
    n_env, n = av.shape[0], av.shape[1]
    w = np.empty((n, n))
    key = np.empty(n)
    parent = np.zeros(n, dtype=np.intp)
    visited = np.empty(n, dtype=np.bool_)
    chosen = np.empty(n, dtype=np.bool_)
    for e in range(n_env):
        for i in range(n):
            for j in range(n):
                links[e, i, j] = False
                if av[e, i, j] and act[e, i] and act[e, j] and i != j:
                    w[i, j] = dist[e, i, j] if use_dist else 1.0
                else:
                    w[i, j] = np.inf
            visited[i] = not act[e, i]
            key[i] = np.inf
            parent[i] = 0
        comps = 0
        for _ in range(n):
            j = -1
            best = np.inf
            remaining = False
            for i in range(n):
                if not visited[i]:
                    remaining = True
                    if key[i] < best:
                        best = key[i]
                        j = i
            if not remaining:
                break
            if j >= 0:  # grow the current tree along its lightest edge
                links[e, parent[j], j] = True
            else:  # no finite key: a new component at the first unvisited UAV
                comps += 1
                for i in range(n):
                    if not visited[i]:
                        j = i
                        break
            visited[j] = True
            for i in range(n):
                if not visited[i] and w[j, i] < key[i]:
                    key[i] = w[j, i]
                    parent[i] = j
        n_comp[e] = comps
        for i in range(n):
            for j in range(n):
                chosen[j] = False
            for _ in range(k_nearest):
                m = -1
                best = np.inf
                for j in range(n):
                    if not chosen[j] and w[i, j] < best:
                        best = w[i, j]
                        m = j
                if m < 0:
                    break
                chosen[m] = True
                links[e, i, m] = True
        for i in range(n):
            for j in range(i + 1, n):
                v = links[e, i, j] or links[e, j, i]
                links[e, i, j] = v
                links[e, j, i] = v


@_jit
def auto_links(dist, range_m, flying, k_nearest, links, n_comp):
    """:func:`comms.auto_topology` on :func:`comms.in_range` of ``dist`` among the flying."""
    adj = np.empty(links.shape, dtype=np.bool_)
    in_range(dist, range_m, flying, adj)
    auto_topology(adj, dist, True, flying, k_nearest, links, n_comp)


# ------------------------------------------------------------------------------ the simulator step

#: Rows of the bool ``flags`` array that :func:`step` fills (one array: fewer arguments).
OVERTIME, OOB, COLLISION, COMMS_OK, LANDED, CRASHED = range(6)
N_FLAGS = 6

#: The scalar constants of :func:`step`, in the order of its ``constants`` array
#: (:func:`step_constants` builds it once per scenario).
STEP_CONSTANTS = (
    "dt_s",  # the time step
    "usable_s",  # usable endurance 0.85 T (eq. 18)
    "time_share",  # dt / usable: the time term of a moving UAV
    "endurance_s",  # T
    "x0", "y0", "x1", "y1",  # the operating area (eq. 20)
    "safety_distance_m",  # d_s (eq. 21)
    "range_m",  # communication range (eq. 24)
    "min_neighbours",  # the two-neighbour rule's count (eq. 24), an integer
    "landing_radius_m",
    "landing_max_altitude_m",
    "landing_max_speed_mps",
    "terminate",  # 1.0: an unsafe step crashes the UAV (constraints.violation "terminate")
)  # fmt: skip


def step_constants(**values: float) -> np.ndarray:
    """The float64 array of :func:`step`'s scalar constants from their names
    (:data:`STEP_CONSTANTS`, every one and no other)."""
    if set(values) != set(STEP_CONSTANTS):
        raise TypeError(f"step_constants needs exactly {STEP_CONSTANTS}, got {sorted(values)}")
    out = np.array([float(values[name]) for name in STEP_CONSTANTS], dtype=np.float64)
    out.flags.writeable = False
    return out


@_jit
def step(state, sensed, events, landing, constants):
    """Steps 3-5 of :func:`poc_env.sim.core.step` after sensing, in place on the state arrays.

    ``state`` (read and updated): ``(agent_pos, posc, pos, speed, exponent, threshold,
    step_count, detected, detect_step, elapsed, left_home, landed, crashed, flying,
    violations)``, ``pos`` the new positions; ``sensed`` (read): ``(found, moving, nofly,
    threat)``, what each UAV found this step, who moved, and the no-fly and threat flags;
    ``events`` (written): ``(team, detected_now, time_term, flags, dist)``; ``landing (N, 2)``;
    ``constants``: :func:`step_constants`.

    What each UAV found (``agent_pos``), the team's POS (``team``, eq. 12 summed over the UAVs
    in agent order) and POSC (eq. 13);
    detection of the hidden target; the time model (eq. 17-18); the boundary (eq. 20),
    separation (eq. 21) and two-neighbour (eq. 24) checks through the same kernels
    :mod:`~poc_env.sim.constraints` and :mod:`~poc_env.sim.comms` call; violation counts;
    landing and crashes; the step counter. ``dist`` receives the pairwise distances of the new
    positions (for the topology update).
    """
    (
        agent_pos, posc, pos, speed, exponent, threshold, step_count, detected, detect_step,
        elapsed, left_home, landed, crashed, flying, violations,
    ) = state  # fmt: skip
    found, moving, nofly, threat = sensed
    team, detected_now, time_term, flags, dist = events
    dt = constants[0]
    usable = constants[1]
    time_share = constants[2]
    endurance = constants[3]
    x0, y0, x1, y1 = constants[4], constants[5], constants[6], constants[7]
    d_s = constants[8]
    range_m = constants[9]
    min_neighbours = int(constants[10])
    landing_radius = constants[11]
    landing_max_alt = constants[12]
    landing_max_speed = constants[13]
    terminate = constants[14] != 0.0
    n_env, n = moving.shape
    pairwise_distances(pos[:, :, :2], dist)
    pairs = np.empty((n_env, n, n), dtype=np.bool_)
    separation(dist, d_s, moving, True, pairs, flags[COLLISION])
    in_range(dist, range_m, moving, pairs)
    two_neighbour(pairs, min_neighbours, moving, True, flags[COMMS_OK])
    for e in range(n_env):
        total = 0.0
        for i in range(n):
            total += found[e, i]
        team[e] = total
        posc[e] += total
        now = not detected[e] and exponent[e] >= threshold[e]
        detected_now[e] = now
        if now:
            detected[e] = True
            detect_step[e] = step_count[e] + 1
        step_count[e] += 1
        for i in range(n):
            agent_pos[e, i] += found[e, i]
            mv = moving[e, i]
            elapsed[e, i] = elapsed[e, i] + (dt if mv else 0.0)
            flags[OVERTIME, e, i] = mv and elapsed[e, i] > usable
            time_term[e, i] = time_share if mv else 0.0
            x, y, z = pos[e, i, 0], pos[e, i, 1], pos[e, i, 2]
            oob = mv and _outside(x, y, x0, y0, x1, y1)
            flags[OOB, e, i] = oob
            collision = mv and flags[COLLISION, e, i]
            flags[COLLISION, e, i] = collision
            comms_ok = flags[COMMS_OK, e, i] or not mv
            flags[COMMS_OK, e, i] = comms_ok
            unsafe = oob or nofly[e, i] or collision or threat[e, i]
            if mv and (unsafe or not comms_ok):
                violations[e, i] += 1
            home = math.hypot(x - landing[i, 0], y - landing[i, 1])
            if mv and home > landing_radius:
                left_home[e, i] = True
            land = (
                mv
                and left_home[e, i]
                and home <= landing_radius
                and z <= landing_max_alt
                and speed[e, i] <= landing_max_speed
            )
            crash = mv and not land and (z <= 0.0 or elapsed[e, i] >= endurance)
            if terminate:
                crash = crash or (mv and not land and unsafe)
            flags[LANDED, e, i] = land
            flags[CRASHED, e, i] = crash
            if land:
                landed[e, i] = True
            if crash:
                crashed[e, i] = True
            if land or crash:
                flying[e, i] = False


@_jit
def all_finite(a):
    """Whether every entry of the float array ``a`` (any shape, C order) is finite: the
    PettingZoo env's check of its actions (``np.isfinite(a).all()`` in one pass)."""
    for v in a.flat:  # noqa: SIM110 (a loop numba compiles, stopping at the first)
        if not math.isfinite(v):
            return False
    return True


# ------------------------------------------------------------------- the single env's end of step
# The reward terms of :func:`poc_env.sim.rewards.reward_terms` and their total
# (:func:`~poc_env.sim.rewards.total_reward`), the episode end of :func:`poc_env.sim.core.terminal`,
# :func:`~poc_env.sim.core.truncated` and :func:`~poc_env.sim.core.episode_over`, and every
# per-agent info value of :func:`poc_env.sim.engine.info_parts` but the adjacency rows, grouped by
# Python type (:data:`FLOAT_INFOS`, :data:`BOOL_INFOS`, :data:`INT_INFOS`) so that one ``tolist()``
# per group gives Python floats, bools and ints: :func:`end_step`, called by :func:`step_end`
# after the bookkeeping and the topology in one call (one dispatch: the single environment's
# step, :class:`poc_env.sim.single.SingleStep`). The numpy functions are the reference;
# ``tests/sim/test_single.py`` pins these kernels to them bit for bit, sums in numpy's order
# (:func:`numpy_sum`: the pairwise summation of ``np.add.reduce``) included.

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


#: Rows of :func:`step_end`'s float64 ``(ROWS_F, E, N)`` array: what each UAV found, the time
#: term, the hidden target's ``log1p(-p_t)``, then the five reward terms and the reward.
FOUND, TIME_TERM, LOG_MISS, VALUES = 0, 1, 2, 3
ROWS_F = 9
#: Rows of its bool ``(ROWS_B, E, N)`` array: the :data:`N_FLAGS` flags, terminated and
#: truncated, the no-fly, threat and shielded flags.
FLAGS, ENDS, NOFLY, THREAT, SHIELDED = 0, 6, 8, 9, 10
ROWS_B = 11
#: Rows of its bool ``(ROWS_E, E)`` array: detected now, connected, episode over.
DETECTED_NOW, CONNECTED, OVER = 0, 1, 2
ROWS_E = 3


@_jit
def step_end(
    agent_pos, posc, pos, speed, exponent, threshold, step_count, detected, detect_step,
    elapsed, left_home, landed, crashed, flying, violations, topology,
    moving, hit, team, dist, links, rows_f, rows_b, rows_e,
    landing, constants, range_m, k_nearest, coef, horizon, detection_ends, team_credit,
    finfo, binfo, iinfo,
):  # fmt: skip
    """The single environment's step after sensing, in one call: if ``hit``, the hidden
    target's exponent grown by the step's ``log1p(-p_t)`` (row :data:`LOG_MISS`: numpy's,
    computed by the caller, since numba's ``log1p`` may differ from numpy's in the last bit),
    ``exponent[e] += -log_miss[e].sum()`` with numpy's summation (:func:`numpy_sum`) as
    :func:`poc_env.sim.core.step` adds it; then :func:`step` (its ``state``, ``sensed`` and
    ``events`` the arrays of the same names, ``topology`` the state's), the auto topology of
    the new distances among the UAVs still flying (:func:`auto_links`) into ``links (E, N,
    N)`` and ``connected`` (one component), then :func:`end_step` with ``values`` (the terms,
    then the reward) and ``ends`` (terminated, truncated). The arrays of one shape and dtype
    come as the rows of one array each (``rows_f``: :data:`FOUND` ...; ``rows_b``:
    :data:`FLAGS` ...; ``rows_e``: :data:`DETECTED_NOW` ...): numba's dispatch costs about
    60 ns per array argument, and types a tuple of arrays more slowly still
    (:class:`poc_env.sim.single.SingleStep`, when the topology is the common ``auto`` one)."""
    found, time_term, log_miss = rows_f[FOUND], rows_f[TIME_TERM], rows_f[LOG_MISS]
    values = rows_f[VALUES:ROWS_F]
    flags, ends = rows_b[FLAGS:ENDS], rows_b[ENDS:NOFLY]
    nofly, threat, shielded = rows_b[NOFLY], rows_b[THREAT], rows_b[SHIELDED]
    detected_now, connected, over = rows_e[DETECTED_NOW], rows_e[CONNECTED], rows_e[OVER]
    if hit:
        for e in range(exponent.shape[0]):
            exponent[e] += -numpy_sum(log_miss[e])
    step(
        (
            agent_pos, posc, pos, speed, exponent, threshold, step_count, detected, detect_step,
            elapsed, left_home, landed, crashed, flying, violations,
        ),
        (found, moving, nofly, threat),
        (team, detected_now, time_term, flags, dist),
        landing,
        constants,
    )  # fmt: skip
    n_env = connected.shape[0]
    n_comp = np.empty(n_env, dtype=np.int64)
    auto_links(dist, range_m, flying, k_nearest, links, n_comp)
    for e in range(n_env):
        connected[e] = n_comp[e] <= 1
    end_step(
        (found, team, time_term, flags, nofly, threat, shielded, detected_now, connected),
        (posc, elapsed, detected, detect_step, topology, violations, landed, crashed, step_count),
        coef, horizon, detection_ends, team_credit,
        (values[:5], values[5], ends[0], ends[1], over, finfo, binfo, iinfo),
    )  # fmt: skip
