import sys
from pathlib import Path
from poc_env.agents.rl.bc import bc_losses, load_demos
from poc_env.agents.rl.checkpoint import load_policy
d = load_demos(Path(sys.argv[1]))
for m in sys.argv[2:]:
    print(m, {k: round(v, 5) for k, v in bc_losses(load_policy(m), d).items()})
