#!/bin/bash
# i24-rates: exports byte for byte against main's (i24-climb's byteident.sh, lighter: the
# branch exports main's plan; the branch's own plan is compared with main's as JSON without
# runtime_s). Cases in the order that matters here (the probes with orbits first), formats
# with altitudes first. Usage: byteident.sh WORKDIR (inputs copied from /tmp/dayaudit)
set -u
W=$1
M=/work/main/.venv/bin/poc-env
B=${BRANCH_POC_ENV:-/work/wt/i24-rates/.venv/bin/poc-env}
PY=/work/wt/i24-rates/.venv/bin/python
mkdir -p "$W" && cd "$W" || exit 1
cp -rn /tmp/dayaudit/in /tmp/dayaudit/s150.* /tmp/dayaudit/s150land.* /tmp/dayaudit/swall* /tmp/dayaudit/alps . 2>/dev/null
cases="swall:swall.yaml: swall2:swall2.yaml: alps:alps/alps.yaml:--overrides=uav.max_altitude_m=6000 s150land:s150land.yaml: s150:s150.yaml:"
for c in $cases; do
  IFS=: read -r name yaml over <<<"$c"
  for who in main branch; do
    P=$M; [ $who = branch ] && P=$B
    mkdir -p "$who"
    [ -f "$who/$name.json" ] || $P plan --scenario "$yaml" --planner allocation $over --quiet --out "$who/$name.json" >"$who/$name.plan.log" 2>&1
  done
  $PY -c "
import json, sys
a, b = (json.load(open(f'{w}/$name.json')) for w in ('main', 'branch'))
for d in (a, b): d.pop('runtime_s', None)
print('$name plan (without runtime_s):', 'same' if a == b else 'DIFF')"
  for opts in "" "--separation-m 30" "--separation-m 30 --layer-by fleet"; do
    tag=$(echo "$opts" | tr -d ' -')
    for fmt in qgc geojson kml html; do
      for who in main branch; do
        P=$M; [ $who = branch ] && P=$B
        d="out/$name/$fmt$tag/$who"
        mkdir -p "$d" && cp "main/$name.json" "$d/plan.json"
        (cd "$d" && $P export plan.json --format $fmt $opts --out ex >../$who.log 2>&1; echo "rc=$?" >>../$who.log)
      done
      base="out/$name/$fmt$tag"
      a=$(cd "$base/main" && find ex -type f | sort | xargs -r sha256sum | sha256sum)
      b=$(cd "$base/branch" && find ex -type f | sort | xargs -r sha256sum | sha256sum)
      n=$(cd "$base/main" && find ex -type f | wc -l)
      echo "$name $fmt [$opts] files=$n $([ "$a" = "$b" ] && echo same || echo DIFF) main:$(tail -1 $base/main.log) branch:$(tail -1 $base/branch.log)"
    done
  done
done
