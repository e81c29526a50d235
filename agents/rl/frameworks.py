"""Adapters of the registered tasks for third-party RL frameworks (see docs/FRAMEWORKS.md).

:func:`torchrl_env` is a registered task as a TorchRL environment: the task's PettingZoo
parallel env (:func:`poc_env.tasks.make_parallel`, so every framework sees the same MDP) behind
TorchRL's own ``PettingZooWrapper``, with the two settings our tasks need because UAVs finish
at different times (one lands while the others fly on):

- ``use_mask=True``: each group gets a ``"mask"`` entry (False for an agent that has finished;
  its observation and reward are zeros and its action is ignored by the env);
- ``done_on_any=False``: the root ``done`` is the *all* of the agents' dones, so the env is
  reset when the last UAV finishes. TorchRL's default for parallel envs (``any``) would reset
  the episode as soon as the first UAV lands and cut the other UAVs' flights short.

The UAVs form one group, ``"uav"``: observations ``(n_uavs, 63)`` (the compass Box), actions
``(n_uavs, 3)`` for ``Increments`` and ``(n_uavs, 2)`` for ``Heading``/``Waypoint``, rewards
and dones ``(n_uavs, 1)``, and every (numeric) info under ``("uav", "info", key)``.
``return_state=True`` adds the env's ``state()`` (POC raster + every agent's vector) as
``"state"`` for centralised critics (MAPPO).

Needs the ``torchrl`` extra (torchrl, tensordict, torch); it is imported when called.
"""

from __future__ import annotations

from typing import Any

from poc_env.errors import MissingExtraError

#: The group TorchRL gives our agents (``uav_0``, ``uav_1``, ... share the ``uav`` prefix).
GROUP = "uav"


def _import_torchrl_wrapper() -> Any:
    try:
        from torchrl.envs.libs.pettingzoo import PettingZooWrapper
    except ModuleNotFoundError as exc:
        if (exc.name or "").partition(".")[0] not in ("torchrl", "tensordict", "torch"):
            raise
        raise MissingExtraError("torchrl", "poc_env.agents.rl.frameworks.torchrl_env") from exc
    return PettingZooWrapper


def torchrl_env(
    task: str,
    *,
    seed: int | None = None,
    return_state: bool = False,
    device: str = "cpu",
    **overrides: Any,
) -> Any:
    """The task ``task`` as a TorchRL ``PettingZooWrapper`` (see the module docstring).

    ``seed`` seeds the first reset (later resets continue the env's generator);
    ``overrides`` are keyword arguments of :func:`poc_env.tasks.make_parallel`
    (``overrides={"episode.horizon_steps": 20}``, ``max_cycles=...``).
    """
    from poc_env import tasks

    wrapper = _import_torchrl_wrapper()
    pz_env = tasks.make_parallel(task, **overrides)
    return wrapper(
        pz_env,
        use_mask=True,
        done_on_any=False,
        return_state=return_state,
        seed=seed,
        device=device,
    )
