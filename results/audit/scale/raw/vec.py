import sys

sys.path.insert(0, "/work/wt/scale-audit/tests/envs")
from test_tasks import _run_both

from poc_env import spec

for tid, kw in [
    ("poc_env/UAVSearch-Wide-N24-Random-Set-Heading-v1", {}),
    ("poc_env/UAVSearch-Wide-N24-Random-Set-Increments-v0", {}),
    ("poc_env/UAVSearch-Wide-N12-Random-Set-Heading-v1", {"fleet": spec.fleet_of(32)}),
]:
    ends = _run_both(tid, 3, 30, seed=5, overrides={"episode.horizon_steps": 10}, **kw)
    print(tid, kw and "N=32", "equal; ends", ends, flush=True)
