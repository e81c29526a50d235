"""poc-env: UAV-swarm search over a probability-of-containment map (Fan et al., Drones 2024)."""

from __future__ import annotations

import os as _os
import sys as _sys
from typing import TYPE_CHECKING, Any

#: What the ``poc-env`` command prints when Ctrl-C ends it before it has started.
STARTING_INTERRUPTED = "interrupted: poc-env stopped while starting; nothing was written"


def _interrupted_while_starting(signum: int, frame: Any) -> None:
    """SIGINT while the ``poc-env`` command imports its packages: one line and exit status 130,
    as a later Ctrl-C ends (``poc_env.cli.main``), not Python's traceback. A SystemExit raised
    in an import propagates out of it and ends the interpreter quietly."""
    print(STARTING_INTERRUPTED, file=_sys.stderr)
    raise SystemExit(130)


if _os.path.basename(_sys.argv[0] if _sys.argv else "").removesuffix(".exe") == "poc-env":
    # the command line only (its script is named poc-env): in Python, `import poc_env` keeps
    # the interpreter's own Ctrl-C; main() puts Python's handler back once it runs
    import signal as _signal

    _signal.signal(_signal.SIGINT, _interrupted_while_starting)

if TYPE_CHECKING:
    from poc_env.config import Scenario, load_scenario

__version__ = "0.1.0"

ENV_ID = "poc_env/UAVSearch-v0"


def parallel_env(scenario="paper_6_2", render_mode=None, **overrides):
    """The PettingZoo parallel environment (``poc_env.envs.parallel.UAVSearchParallelEnv``)."""
    from poc_env.envs.parallel import UAVSearchParallelEnv

    return UAVSearchParallelEnv(scenario=scenario, render_mode=render_mode, **overrides)


def env(scenario="paper_6_2", render_mode=None, **overrides):
    """The PettingZoo AEC environment (the parallel env through ``parallel_to_aec``)."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(parallel_env(scenario, render_mode, **overrides))


def _register() -> None:
    """Register ``poc_env/UAVSearch-v0`` with gymnasium and PettingZoo (when available)."""
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        gymnasium.register(
            ENV_ID,
            entry_point="poc_env.envs.gymnasium_env:UAVSearchGym",
            vector_entry_point="poc_env.envs.gym_vector:SwarmGymVectorEnv",
        )
    from poc_env.tasks import register_tasks

    register_tasks()  # the benchmark tasks (poc_env.tasks), Gymnasium and PettingZoo
    try:
        from pettingzoo.env_registry.registration import _get_registry, register
    except ImportError:  # PettingZoo < 1.27 has no registry
        return
    for kind, entry in (("parallel", "parallel_env"), ("aec", "env")):
        if ENV_ID not in _get_registry(kind):
            register(kind, ENV_ID, entry_point=f"poc_env.uav_search_v0:{entry}")


_register()


def __getattr__(name: str) -> Any:
    """``poc_env.Scenario`` and ``poc_env.load_scenario`` load the configuration (and its
    compiled kernels) when first used, not when the package is imported: ``poc-env`` starts
    without them, so its Ctrl-C handler is in place before the slow imports (cli-audit)."""
    if name in ("Scenario", "load_scenario"):
        from poc_env import config

        return getattr(config, name)
    raise AttributeError(f"module 'poc_env' has no attribute {name!r}")


__all__ = ["ENV_ID", "Scenario", "__version__", "env", "load_scenario", "parallel_env"]
