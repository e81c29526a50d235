"""The batched adapters' bookkeeping of a step, each in one pass.

:func:`slot_step` is the SB3 adapter's (:meth:`poc_env.envs.vector.SwarmVecEnv.step_wait`):
from the engine's step (each agent's reward, whether it finished, whether the horizon cut it
off, whether its env's episode is over) and which slots were active, the slots' rewards (0 for
placeholders), dones and truncations, which agents still fly on, which envs end, and each
agent's running return and length, as the numpy formulation of ``step_wait`` writes them
(``np.where(active, reward, 0.0)``, then ``returns += reward``, ``lengths += active``,
``reward.astype(np.float32)``: the same additions and roundings, element by element).
:func:`live_mean` is the centralised view's reward (:func:`poc_env.sim.engine.mean_over`,
``gymnasium.make_vec``'s): each row's mean over its live agents, summed in numpy's order for
rows of fewer than 8. A dozen numpy calls on ``(E, N)`` arrays cost more than the arithmetic
at these sizes; ``tests/envs/test_vector.py`` and ``tests/envs/test_engine.py`` pin the two to
numpy.

A kernel module: imports nothing of the project (the cache rule, :mod:`poc_env._kernels`).
"""

from __future__ import annotations

from numba import njit

_jit = njit(cache=True, error_model="numpy")

#: Bits of :func:`slot_step`'s result.
SOME_INACTIVE, SOME_DONE, SOME_STOPPED, SOME_ENV_ENDS = 1, 2, 4, 8


@_jit
def slot_step(
    active, reward, finished, truncated, over, returns, lengths,
    slot_reward, slot_done, slot_truncated, still, env_end,
):  # fmt: skip
    """One step's slot bookkeeping for ``E`` envs of ``N`` agents.

    Inputs: ``active (E, N)`` the slots with a live agent before the step, ``reward (E, N)``
    its reward, ``finished (E, N)`` whether its RL episode ended at the step (terminal, or
    the adapter's own reason), ``truncated (E, N)`` the horizon's cut, ``over (E,)`` the
    engine's episode end. Updated in place: ``returns (E, N)`` (+= the slot's reward) and
    ``lengths (E, N)`` (+= 1 for active slots). Written: ``slot_reward (E * N,)`` float32 (the
    reward of active slots, else 0), ``slot_done (E * N,)`` (the agent finished, or its env
    ended), ``slot_truncated (E * N,)`` (still flying and cut off), ``still (E, N)`` (active
    and not finished), ``env_end (E,)`` (the engine's end, or no agent still flying). Returns
    the or of :data:`SOME_INACTIVE` (some slot was not active), :data:`SOME_DONE`,
    :data:`SOME_STOPPED` (some agent does not fly on) and :data:`SOME_ENV_ENDS`."""
    n_env, n = active.shape
    flags = 0
    for e in range(n_env):
        going = False
        for i in range(n):
            k = e * n + i
            a = active[e, i]
            r = reward[e, i] if a else 0.0
            returns[e, i] += r
            if a:
                lengths[e, i] += 1
            else:
                flags |= SOME_INACTIVE
            slot_reward[k] = r
            s = a and not finished[e, i]
            still[e, i] = s
            going = going or s
            slot_truncated[k] = s and truncated[e, i]
        end = over[e] or not going
        env_end[e] = end
        if end:
            flags |= SOME_ENV_ENDS
        for i in range(n):
            k = e * n + i
            d = end or (active[e, i] and finished[e, i])
            slot_done[k] = d
            if d:
                flags |= SOME_DONE
            if not still[e, i]:
                flags |= SOME_STOPPED
    return flags


@_jit
def _row_mean(values, mask, e):
    """Row ``e``'s mean of ``values`` over its True ``mask`` entries (0 without any), for rows
    of fewer than 8: numpy's mean of those values to the bit (numpy adds fewer than 8 values one
    after the other, from 0.0), then divided by their count."""
    total = 0.0
    count = 0
    for i in range(values.shape[1]):
        if mask[e, i]:
            total = total + values[e, i]
            count += 1
    return total / count if count else 0.0


@_jit
def live_mean(values, mask, out):
    """``out (E,)``: each row's mean of ``values (E, N)`` over its True ``mask`` entries, 0
    for a row without any, for ``N < 8`` (:func:`_row_mean`)."""
    for e in range(values.shape[0]):
        out[e] = _row_mean(values, mask, e)


@_jit
def live_step(live, reward, terminated, truncated, over, mean, env_term, env_trunc, new_live):
    """``gymnasium.make_vec``'s bookkeeping of a whole batch's step for ``N < 8`` agents, as
    :meth:`poc_env.envs.gym_vector.SwarmGymVectorEnv._advance` writes it in numpy: ``mean
    (E,)`` each env's reward, the mean over the agents ``live (E, N)`` before the step
    (:func:`_row_mean`); ``env_trunc (E,)`` the episode is ``over`` and the horizon cut some
    agent off (``truncated (E, N)``), ``env_term`` over otherwise; ``new_live (E, N)`` live and
    neither ``terminated`` nor truncated (it may be ``live`` itself: each entry is read before
    it is written). Returns whether every agent was live."""
    every = True
    for e in range(live.shape[0]):
        mean[e] = _row_mean(reward, live, e)
        cut = False
        for i in range(live.shape[1]):
            alive = live[e, i]
            every = every and alive
            cut = cut or truncated[e, i]
            new_live[e, i] = alive and not (terminated[e, i] or truncated[e, i])
        env_trunc[e] = over[e] and cut
        env_term[e] = over[e] and not cut
    return every
