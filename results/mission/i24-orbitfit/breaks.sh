#!/bin/bash
# i24-orbitfit: each test's feature broken once (in the worktree, restored by git checkout after
# each), the tests run: each break must fail. Run from the worktree root with nothing uncommitted
# in agents/.
set -u
run() {  # name, file, python replacement (old -> new)
  python3 - "$2" "$3" "$4" <<'PY'
import sys
p, old, new = sys.argv[1:]
s = open(p).read()
assert old in s, old
open(p, "w").write(s.replace(old, new, 1))
PY
  OMP_NUM_THREADS=1 nice -n 10 .venv/bin/pytest -q tests/mission/test_orbit_fit.py 2>&1 | tail -1 | sed "s/^/$1: /"
  git checkout -q -- agents
}
run "no trim (fit_orbits returns the plan)" agents/planning/geography.py \
  '    with profiles_once():  # each unchanged UAV' '    return plan
    with profiles_once():  # each unchanged UAV'
run "POS not re-scored" agents/planning/geography.py \
  '    out["posc"] = float(sum(pos))' '    pos = [u["pos"] for u in plan["uavs"]]'
run "orbit time charged for a flight already over" agents/mission/terrain.py \
  '        if not charge or over:' '        if not charge:'
run "whole waypoints only (no last-leg bisection), POS compared to the kept route" agents/planning/geography.py \
  '            for _ in range(BISECT_STEPS):' '            for _ in range(0):'
