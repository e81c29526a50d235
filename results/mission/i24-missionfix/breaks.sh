#!/bin/bash
# Each new test's feature broken once, in a scratch copy of the branch (PYTHONPATH first):
# the tests named must fail. Usage: breaks.sh (writes /tmp/i24-missionfix-breaks)
set -u
SRC=/work/wt/i24-missionfix
PY=$SRC/.venv/bin/python
run() {  # name, file, old, new, test file, tests (-k expression)
  local name=$1 file=$2 old=$3 new=$4 T=$5 k=$6 d=/tmp/i24-missionfix-breaks
  rm -rf $d && mkdir -p $d && (cd $SRC && git ls-files -z | xargs -0 cp -P --parents -t $d)
  $PY - "$d/$file" "$old" "$new" <<'PY'
import sys
p, old, new = sys.argv[1:4]
s = open(p).read()
assert s.count(old) == 1, (p, old)
open(p, "w").write(s.replace(old, new))
PY
  (cd $d && PYTHONPATH=$d OMP_NUM_THREADS=1 nice -n 10 $PY -m pytest -q -p no:cacheprovider $T -k "$k" 2>&1 | tail -1 | sed "s/^/$name: /")
}
F=tests/mission/test_missionfix.py
run "no departure heading (main's refusal)" agents/mission/terrain.py \
  "            turned = departure_spiral(t, p, z, dist, where, speed_mps, layer_m, grad, airspace)" \
  "            turned = None" $F "heading_of_its_own"
run "departure not exported to QGC" agents/mission/formats/qgc.py \
  "    if sp is not None and sp.depart_m > 0.0:  # (PX4 climbs out on the course towards it)" \
  "    if False:" $F "heading_of_its_own"
run "the departure not charged" agents/mission/terrain.py \
  "        return (self.length_m + 2.0 * self.depart_m) / self.speed_mps" \
  "        return self.length_m / self.speed_mps" $F "heading_of_its_own"
run "terrain record read per trial" agents/mission/terrain.py \
  "        t = t or _record_terrain(rec, memo)
        where" "        t = t or from_record(rec)
        where" $F "once"
run "route line straight from the approach point" agents/mission/features.py \
  "        if p.descent is not None:  # the glide flown from the orbit's exit, not from its centre" \
  "        if False:" $F "descent_orbit_exit"
run "stale DE rectangles kept" agents/planning/geography.py \
  "        if u.get(\"rectangle\") is not None or u.get(\"flown_rectangle\") is not None:" \
  "        if False:" $F "stale"
run "stale DE x kept" agents/planning/geography.py \
  "    elif \"x\" in out:  # a DE plan" "    elif False:  # a DE plan" $F "stale"
run "survey not trimmed" agents/planning/survey.py \
  "        prior,  # orbits that do not fit" "        None,  # orbits that do not fit" $F "survey"
run "field-mates' approaches not kept apart" agents/mission/features.py \
  "    return {**plan, \"uavs\": _approaches_apart(uavs, plan.get(\"no_fly_zones_m\"))," \
  "    return {**plan, \"uavs\": uavs," $F "approaches_apart"
run "export warnings on stdout" agents/mission/export.py \
  "            say_warning(line)" "            print(f\"warning: {line}\")" \
  "tests/mission/test_missionfix.py tests/mission/test_final_glide.py" "heading_of_its_own or field_mates_orbits"
run "plan warnings on stdout" poc_env/cli.py \
  "            say_warning(warning)

" "            print(f\"warning: {warning}\")

" tests/planning/test_planner.py "sample_points_are_wider"
run "replan's track warning on stdout" agents/planning/replan.py \
  "        say_warning(
            f\"{field}:" "        print(
            f\"warning: {field}:" tests/planning/test_replan.py "partly_outside"
