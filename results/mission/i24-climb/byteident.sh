#!/bin/bash
# i24-climb: every mission that exported on main exports byte-identically on the branch.
# Usage: byteident.sh WORKDIR  (inputs copied from /tmp/dayaudit, read-only there)
# For each scenario: plan with main's CLI and with the branch's (the same routes; the branch's
# terrain record carries two more keys), export every format x {no layers, --separation-m 30,
# --separation-m 30 --layer-by fleet} with main from main's plan and with the branch from both
# plans, and compare the files byte for byte. Refusals are compared by their message.
set -u
W=$1
M=/work/main/.venv/bin/poc-env
B=${BRANCH_POC_ENV:-/work/wt/i24-climb/.venv/bin/poc-env}  # i24-glide: its own with BRANCH_POC_ENV
mkdir -p "$W" && cd "$W" || exit 1
cp -rn /tmp/dayaudit/in /tmp/dayaudit/s150.* /tmp/dayaudit/s150land.* /tmp/dayaudit/swall* /tmp/dayaudit/alps . 2>/dev/null
cases="s150:s150.yaml: s150land:s150land.yaml: alps:alps/alps.yaml:--overrides=uav.max_altitude_m=6000 swall:swall.yaml: swall2:swall2.yaml:"
for c in $cases; do
  IFS=: read -r name yaml over <<<"$c"
  for who in main branch; do
    P=$M; [ $who = branch ] && P=$B
    mkdir -p "$who"
    $P plan --scenario "$yaml" --planner allocation $over --quiet --out "$who/$name.json" >"$who/$name.plan.log" 2>&1
    echo "$name plan $who rc=$?"
  done
  for opts in "" "--separation-m 30" "--separation-m 30 --layer-by fleet"; do
    tag=$(echo "$opts" | tr -d ' -')
    for fmt in qgc kml geojson html; do
      for run in main:main branch:branch branch:main; do
        IFS=: read -r who planof <<<"$run"
        P=$M; [ $who = branch ] && P=$B
        d="out/$name/$fmt$tag/$who-$planof"
        mkdir -p "$d"
        [ -f "$planof/$name.json" ] || { echo "no plan" >"$d.log"; continue; }
        cp "$planof/$name.json" "$d/plan.json"
        (cd "$d" && $P export plan.json --format $fmt $opts --out ex >../$who-$planof.log 2>&1; echo "rc=$?" >>../$who-$planof.log)
      done
      base="out/$name/$fmt$tag"
      a=$(cd "$base/main-main" 2>/dev/null && find ex -type f | sort | xargs -r sha256sum | sha256sum)
      b=$(cd "$base/branch-branch" 2>/dev/null && find ex -type f | sort | xargs -r sha256sum | sha256sum)
      c2=$(cd "$base/branch-main" 2>/dev/null && find ex -type f | sort | xargs -r sha256sum | sha256sum)
      n=$(cd "$base/main-main" 2>/dev/null && find ex -type f | wc -l)
      same1=$([ "$a" = "$b" ] && echo same || echo DIFF)
      same2=$([ "$a" = "$c2" ] && echo same || echo DIFF)
      echo "$name $fmt [$opts] files=$n branch-plan:$same1 main-plan:$same2 main:$(tail -1 $base/main-main.log) branch:$(tail -1 $base/branch-branch.log)"
    done
  done
done
