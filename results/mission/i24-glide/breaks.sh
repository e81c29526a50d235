#!/bin/bash
# Break each feature once in a scratch copy (/tmp/i24-glide-break) and run its test.
set -u
SRC=/work/wt/i24-glide
B=/tmp/i24-glide-break
PY=$SRC/.venv/bin/python
run() {  # name, file, python-replace-old, new, test
  name=$1; file=$2; old=$3; new=$4; test=$5
  rm -rf $B && mkdir -p $B && (cd $SRC && tar --exclude=.venv --exclude=.git --exclude=results -cf - .) | (cd $B && tar xf -)
  $PY - "$B/$file" "$old" "$new" <<'PY'
import sys
p, old, new = sys.argv[1:]
s = open(p).read()
assert s.count(old) == 1, old
open(p, "w").write(s.replace(old, new))
PY
  out=$(cd $B && PYTHONPATH=$B OMP_NUM_THREADS=1 nice -n 10 $PY -m pytest -q -x -p no:cacheprovider "$test" 2>&1)
  echo "$name | $test | $(echo "$out" | tail -1) | $(echo "$out" | grep -m1 '^E ' | cut -c1-160) | $(echo "$out" | grep -m1 -o 'test_final_glide.py:[0-9]*')"
}
T=tests/mission/test_final_glide.py
run "no descent orbit (straight glides only)" agents/mission/terrain.py \
  "for loiter in ((True,) if app == path[-1] else (False, True))" "for loiter in ((False,) if app != path[-1] else ())" \
  "$T::test_a_glide_over_high_ground_lands_on_a_descent_orbit"
run "QGC without the descent loiter item" agents/mission/formats/qgc.py \
  "    if prof.descent is not None:  # orbit" "    if False:  # orbit" \
  "$T::test_a_glide_over_high_ground_lands_on_a_descent_orbit"
run "descent orbit's clearance not read (disc ground ignored)" agents/mission/terrain.py \
  "    need += t.min_clearance_m" "    need = 0.0" \
  "$T::test_a_glide_over_high_ground_lands_on_a_descent_orbit"
run "no side clears: the glide left unchecked instead of refused" agents/mission/terrain.py \
  "    raise ConfigError(
        where, first.value," "    return profile(t, path, where, None, layer, speed_mps)
    raise ConfigError(
        where, first.value," \
  "$T::test_no_side_of_the_field_clears_refused_naming_the_uav"
run "orbit radius without the layer" agents/mission/terrain.py \
  "    return speed_mps / t.turn_rate_rad_s + float(layer_m)" "    return speed_mps / t.turn_rate_rad_s" \
  "$T::test_field_mates_orbits_are_kept_apart_by_their_layers"
run "no shared-orbit warning" agents/mission/export.py \
  "        if len(ids) > 1" "        if len(ids) > 9" \
  "$T::test_field_mates_orbits_are_kept_apart_by_their_layers"
