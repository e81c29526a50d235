#!/bin/bash
# Each new test's feature broken once, in a scratch copy of the branch (PYTHONPATH first):
# the tests named must fail. Usage: breaks.sh (from anywhere; writes /tmp/i24-rates-breaks)
set -u
SRC=/work/wt/i24-rates
PY=$SRC/.venv/bin/python
T=tests/mission/test_vertical_rates.py
run() {  # name, file, old, new, tests (-k expression)
  local name=$1 file=$2 old=$3 new=$4 k=$5 d=/tmp/i24-rates-breaks
  rm -rf $d && mkdir -p $d && (cd $SRC && git ls-files -z | xargs -0 cp -P --parents -t $d) && cp -r $SRC/$T $d/$T
  $PY - "$d/$file" "$old" "$new" <<'PY'
import sys
p, old, new = sys.argv[1:4]
s = open(p).read()
assert s.count(old) == 1, (p, old)
open(p, "w").write(s.replace(old, new))
PY
  (cd $d && PYTHONPATH=$d OMP_NUM_THREADS=1 $PY -m pytest -q -p no:cacheprovider $T -k "$k" 2>&1 | tail -1 | sed "s/^/$name: /")
}
run "vertical_angle ignores the rates" agents/mission/terrain.py \
  "    if rate is None or math.tan(t.max_pitch_rad) * speed_mps <= rate:" \
  "    if True:" "spiral or sink or trims"
run "the straight climb after the spiral at eq. 19" agents/mission/terrain.py \
  "        spiral = climb_spiral(t, p, z, dist, where, speed_mps, layer_m, grad)" \
  "        spiral = climb_spiral(t, p, z, dist, where, speed_mps, layer_m, math.tan(t.max_pitch_rad))" "spiral_that_clears"
run "no export warning" agents/mission/export.py \
  "    unset = {k for k in (\"climb\", \"sink\") if rec.get(f\"max_{k}_rate_mps\") is None}" \
  "    unset: set = set()" "need_more_than"
run "rates not recorded in the plan" agents/mission/terrain.py \
  "        **({} if t.max_climb_mps is None else {\"max_climb_rate_mps\": t.max_climb_mps})," \
  "" "recorded_only"
run "zero and negative rates accepted" poc_env/config.py \
  "        \"max_climb_rate_mps\", 1.0, default=None, lo=0.0, lo_open=True, hi=MAX_VERTICAL_RATE_MPS" \
  "        \"max_climb_rate_mps\", 1.0, default=None, hi=MAX_VERTICAL_RATE_MPS" "bad_rates and climb"
run "plan record's rates unchecked" agents/mission/plan.py \
  "            as_number(f\"{field}.{key}\", rec[key], 0.0, MAX_VERTICAL_RATE_MPS, lo_open=True)" \
  "            pass" "bad_rates"
run "orbits not kept apart" agents/mission/terrain.py \
  "    if not layers or not profs:" "    if True:" "cross_a_layer_apart"
