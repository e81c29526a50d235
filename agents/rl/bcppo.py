"""The teacher kept in the loss during PPO (``poc-env train --bc-coef C``; issue 28).

BC-regularised PPO (the DAPG recipe of Rajeswaran et al. 2018, "Learning Complex Dexterous
Manipulation with Deep RL and Demonstrations", with PPO's clipped objective in place of the
natural gradient): after the warm start (:mod:`poc_env.agents.rl.bc`), every PPO minibatch
update minimises

    PPO's loss + C_t x actor_loss(policy, demo obs, demo labels)

where ``actor_loss`` is the warm start's own fit (:func:`poc_env.agents.rl.bc.actor_loss`:
the mean squared error of the policy's Gaussian mean to the teacher's labels) on a minibatch
of the warm start's demonstrations (the teacher's own states and actions: no relabelling of
the learner's states, so none of DAgger's off-route label problem), and

    C_t = C x 0.5 ** (t / half_life)     (``--bc-coef-half-life``; 0: C_t = C)

with ``t`` the run's PPO transitions at the update (SB3's ``num_timesteps``), so the schedule
does not depend on ``--total-timesteps``. Only the actor is pulled toward the teacher: the
value head estimates the learner's returns (PPO's value loss), not the teacher's.

How (:class:`BCPPO`): SB3's ``PPO.train`` is run unchanged; for the duration of the update the
optimiser's ``zero_grad`` is wrapped so that, right after it clears the gradients of a
minibatch step, the BC term's gradient is accumulated (``(C_t x bc_loss).backward()``). SB3's
own ``loss.backward()`` then adds PPO's, and its gradient clipping and optimiser step act on
the sum: the gradient of ``PPO loss + C_t x BC loss``, everything else of SB3's update as is.
The BC minibatch has PPO's ``batch_size`` rows, drawn with replacement by a generator of
``SeedSequence(seed, spawn_key=(*BCPPO_KEY, n_updates))`` (``n_updates``: SB3's update count
at the start of the update, saved in every checkpoint), so a resumed run draws what the
uninterrupted run would have; nothing is drawn from the global generators. TensorBoard /
progress: ``train/bc_loss`` (the mean BC actor loss of the update's minibatches, before each
step) and ``train/bc_coef`` (``C_t``).

``--bc-coef-filter`` (filtered BC, the self-imitation criterion of Oh et al. 2018, "Self-
Imitation Learning"): only the minibatch rows whose discounted return in the demonstrations
(the teacher's return from that state, :class:`~poc_env.agents.rl.bc.Demos` ``returns``)
exceeds the critic's current value of the state count, a weighted mean
(:func:`~poc_env.agents.rl.bc.actor_loss` with a 0/1 weight): where the policy already
expects to do better than the teacher did, the term leaves it free. ``train/bc_filter_kept``
logs the share of rows kept.

The demonstrations are written to the run folder by the warm start (``bc_demos.npz``,
:func:`poc_env.agents.rl.bc.save_demos`) and read back from it both by the fresh run and by
``--resume`` (:func:`attach`), so a resumed run continues with the same buffer. A run with
``--bc-coef 0`` (the default) is plain PPO, bit for bit as before: no :class:`BCPPO`, no file.
"""

from __future__ import annotations

import typing
from typing import TYPE_CHECKING, Any

import numpy as np
from stable_baselines3 import PPO

from poc_env.agents.rl.bc import actor_loss

if TYPE_CHECKING:
    from poc_env.agents.rl.bc import Demos

#: Spawn key prefix of the BC term's minibatch draws (three words: no other stream uses it).
BCPPO_KEY = (0xBC, 3)


def bc_coef_at(coef: float, half_life: int, t: int) -> float:
    """``C_t = coef x 0.5 ** (t / half_life)`` (``half_life`` 0: ``coef``), ``t`` transitions."""
    if half_life <= 0:
        return float(coef)
    return float(coef) * 0.5 ** (float(t) / float(half_life))


class BCPPO(PPO):
    """SB3 PPO whose every minibatch update also descends ``C_t`` x the BC actor loss on the
    demonstrations (module docstring). Made by :func:`attach` from a PPO model (fresh or
    restored), never pickled with its demonstrations (a saved BCPPO loads as plain PPO)."""

    bc_coef: float
    bc_half_life: int
    bc_seed: int
    bc_filter: bool
    bc_obs: Any
    bc_labels: Any
    bc_returns: Any

    def _excluded_save_params(self) -> list[str]:
        return [*super()._excluded_save_params(), "bc_obs", "bc_labels", "bc_returns"]

    def train(self) -> None:
        import torch as th

        c = bc_coef_at(self.bc_coef, self.bc_half_life, self.num_timesteps)
        seq = np.random.SeedSequence(self.bc_seed, spawn_key=(*BCPPO_KEY, int(self._n_updates)))
        rng = np.random.default_rng(seq)
        m = int(self.bc_obs.shape[0])
        opt = self.policy.optimizer
        zero_grad = opt.zero_grad
        losses: list[float] = []
        kept: list[float] = []

        def zero_grad_then_bc(*a: Any, **kw: Any) -> None:
            zero_grad(*a, **kw)
            idx = th.as_tensor(rng.integers(0, m, size=self.batch_size))
            w = None
            if self.bc_filter:  # the teacher's return from the state beats the critic's value
                with th.no_grad():
                    v = self.policy.predict_values(self.bc_obs[idx]).squeeze(-1)
                w = (self.bc_returns[idx] > v).to(v.dtype)
                kept.append(float(w.mean()))
            if c > 0.0:
                loss = actor_loss(self.policy, self.bc_obs[idx], self.bc_labels[idx], w)
                (c * loss).backward()
            else:  # C_t = 0: logged only, the gradient is PPO's alone
                with th.no_grad():
                    loss = actor_loss(self.policy, self.bc_obs[idx], self.bc_labels[idx], w)
            losses.append(float(loss.detach()))

        opt.zero_grad = zero_grad_then_bc  # type: ignore[method-assign]
        try:
            super().train()
        finally:
            del opt.zero_grad  # the optimiser's own method again
        self.logger.record("train/bc_coef", c)
        if losses:
            self.logger.record("train/bc_loss", float(np.mean(losses)))
        if kept:
            self.logger.record("train/bc_filter_kept", float(np.mean(kept)))


def attach(
    model: PPO, demos: Demos, coef: float, half_life: int, seed: int, filtered: bool = False
) -> BCPPO:
    """``model`` (a PPO, fresh or restored from a checkpoint) turned into a :class:`BCPPO`
    that imitates ``demos`` with ``coef`` and ``half_life`` (module docstring), its minibatch
    draws from ``seed``'s stream; ``filtered``: only the rows whose return beats the critic's
    value (``--bc-coef-filter``). Returns the same object."""
    import torch as th

    model.__class__ = BCPPO  # adds behaviour only; every PPO attribute stays as it is
    bc = typing.cast(BCPPO, model)
    bc.bc_coef = float(coef)
    bc.bc_half_life = int(half_life)
    bc.bc_seed = int(seed)
    bc.bc_obs = th.as_tensor(demos.obs)
    bc.bc_labels = th.as_tensor(demos.labels)
    bc.bc_returns = th.as_tensor(demos.returns)
    bc.bc_filter = bool(filtered)
    return bc
