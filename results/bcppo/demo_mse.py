"""How far policies are from the teacher where the teacher flew: the BC losses
(:func:`poc_env.agents.rl.bc.bc_losses`) of each model on a run's ``bc_demos.npz``.

    python results/bcppo/demo_mse.py runs-bcppo/c1_s1/bc_demos.npz MODEL.zip [MODEL.zip ...]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from poc_env.agents.rl.bc import bc_losses, load_demos
from poc_env.agents.rl.checkpoint import load_policy


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("demos", type=Path, help="a run's bc_demos.npz")
    ap.add_argument("models", nargs="+", help="PPO .zip files (or run folders)")
    a = ap.parse_args(argv)
    demos = load_demos(a.demos)
    for m in a.models:
        print(m, {k: round(v, 5) for k, v in bc_losses(load_policy(m), demos).items()})


if __name__ == "__main__":
    main()
