#!/bin/bash
# i24-missionfix: the day audit's five DEM cases (s150, s150land, alps at a 6,000 m ceiling,
# swall = probe 13, swall2 = probe 14), 4 formats x {no layers, --separation-m 30,
# --separation-m 30 --layer-by fleet} = 60 exports, in three runs:
#   main   : main's CLI, main's plan (rates unset); the branch's plan (unset) compared as JSON
#   branch : the branch's CLI, main's plan (rates unset): byte identity against main
#   px4    : the branch's CLI, the branch's plan at PX4's defaults (5/5 m/s)
# Usage: audit60.sh WORKDIR (inputs copied from /tmp/dayaudit, read only)
set -u
W=$1
M=/work/main/.venv/bin/poc-env
B=/work/wt/i24-missionfix/.venv/bin/poc-env
RATES="uav.max_climb_rate_mps=5 uav.max_sink_rate_mps=5"
mkdir -p "$W" && cd "$W" || exit 1
cp -rn /tmp/dayaudit/in /tmp/dayaudit/s150.* /tmp/dayaudit/s150land.* /tmp/dayaudit/swall* /tmp/dayaudit/alps . 2>/dev/null
cases="swall:swall.yaml: swall2:swall2.yaml: alps:alps/alps.yaml:uav.max_altitude_m=6000 s150land:s150land.yaml: s150:s150.yaml:"
for c in $cases; do
  IFS=: read -r name yaml over <<<"$c"
  mkdir -p main px4 px4main
  [ -f "main/$name.json" ] || $M plan --scenario "$yaml" --planner allocation ${over:+--overrides $over} --quiet --out "main/$name.json" >"main/$name.plan.log" 2>&1
  echo "$name main plan rc=$?"
  mkdir -p br
  [ -f "br/$name.json" ] || $B plan --scenario "$yaml" --planner allocation ${over:+--overrides $over} --quiet --out "br/$name.json" >"br/$name.plan.log" 2>&1
  /work/wt/i24-missionfix/.venv/bin/python -c "
import json
a, b = (json.load(open(f'{w}/$name.json')) for w in ('main', 'br'))
for d in (a, b): d.pop('runtime_s', None)
print('$name branch plan, rates unset (without runtime_s):', 'same as main' if a == b else 'DIFF')"
  [ -f "px4main/$name.json" ] || $M plan --scenario "$yaml" --planner allocation --overrides $over $RATES --quiet --out "px4main/$name.json" >"px4main/$name.plan.log" 2>&1
  echo "$name main's CLI at 5/5 rc=$? $(grep -o 'error: .\{0,160\}' px4main/$name.plan.log | head -1)"
  [ -f "px4/$name.json" ] || $B plan --scenario "$yaml" --planner allocation --overrides $over $RATES --quiet --out "px4/$name.json" >"px4/$name.plan.log" 2>&1
  echo "$name branch at 5/5 rc=$? $(grep -o 'error: .\{0,160\}' px4/$name.plan.log | head -1)"
  for opts in "" "--separation-m 30" "--separation-m 30 --layer-by fleet"; do
    tag=$(echo "$opts" | tr -d ' -')
    for fmt in qgc geojson kml html; do
      base="out/$name/$fmt$tag"
      for who in main branch px4; do
        P=$M; src=main; [ $who != main ] && P=$B; [ $who = px4 ] && src=px4
        d="$base/$who"; mkdir -p "$d"
        [ -f "$src/$name.json" ] || { echo "rc=none" > "$base/$who.log"; continue; }
        cp "$src/$name.json" "$d/plan.json"
        (cd "$d" && $P export plan.json --format $fmt $opts --out ex >../$who.log 2>../$who.err; echo "rc=$?" >>../$who.log)
      done
      h() { (cd "$base/$1" 2>/dev/null && find ex -type f 2>/dev/null | sort | xargs -r sha256sum | sha256sum); }
      a=$(h main); b=$(h branch); p=$(h px4)
      echo "$name $fmt [$opts] branch-vs-main $([ "$a" = "$b" ] && echo same || echo DIFF) px4-vs-main $([ "$a" = "$p" ] && echo same || echo DIFF) main:$(tail -1 $base/main.log) branch:$(tail -1 $base/branch.log) px4:$(tail -1 $base/px4.log)"
    done
  done
done
