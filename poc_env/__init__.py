"""poc-env: UAV-swarm search over a probability-of-containment map (Fan et al., Drones 2024)."""

from poc_env.config import Scenario, load_scenario

__version__ = "0.1.0"

__all__ = ["Scenario", "__version__", "load_scenario"]
