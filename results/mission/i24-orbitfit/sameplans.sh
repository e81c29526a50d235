#!/bin/bash
# i24-orbitfit: main's and the branch's `poc-env plan --planner allocation` on the dayaudit's
# terrain cases (inputs copied from /tmp/dayaudit, read-only there) give the same plan.json
# (runtime_s aside) where every UAV's orbits fit; then their exports are main's (the export
# code is main's but for plan_profiles' skip of UAVs already beyond 0.85 T, none here).
# Usage: sameplans.sh WORKDIR
set -u
W=$1
M=/work/main/.venv/bin/poc-env
B=${BRANCH_POC_ENV:-/work/wt/i24-orbitfit/.venv/bin/poc-env}
mkdir -p "$W" && cd "$W" || exit 1
cp -rn /tmp/dayaudit/in /tmp/dayaudit/s150.* /tmp/dayaudit/s150land.* /tmp/dayaudit/swall* /tmp/dayaudit/alps . 2>/dev/null
for c in s150:s150.yaml: s150land:s150land.yaml: alps:alps/alps.yaml:--overrides=uav.max_altitude_m=6000 swall:swall.yaml: swall2:swall2.yaml:; do
  IFS=: read -r name yaml over <<<"$c"
  for who in main branch; do
    P=$M; [ $who = branch ] && P=$B
    mkdir -p "$who"
    $P plan --scenario "$yaml" --planner allocation $over --quiet --out "$who/$name.json" >"$who/$name.plan.log" 2>&1
    echo "$name plan $who rc=$?"
  done
  python3 - "$name" <<'PY'
import json, sys
n = sys.argv[1]
try:
    a, b = (json.load(open(f"{w}/{n}.json")) for w in ("main", "branch"))
except FileNotFoundError as e:
    print(n, "no plan", e.filename); sys.exit()
for d in (a, b):
    d.pop("runtime_s", None)
print(n, "same plan" if a == b else "DIFF", "orbit_fit" in b)
PY
done
