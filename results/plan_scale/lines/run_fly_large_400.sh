#!/bin/sh
# The chosen variant flown on large_400's reported priors 0-19 in two processes (a: 0-9,
# b: 10-19), paired against the stored thorough flights of results/plan_scale/grade (README).
# Usage: run_fly_large_400.sh a|b VARIANT
P=allocation_plan@$2
O=results/plan_scale/lines
R="results/plan_scale/large_400.json results/plan_scale/effort/flown_large_400.json results/plan_scale/polish/flown_large_400_thorough.json results/plan_scale/grade/flown_large_400.json"
export OMP_NUM_THREADS=1
case "$1" in
  a) python tests/planning/effort_ab.py fly large_400 0 10 $P $O/flown_large_400_a.json 0 $R ;;
  b) python tests/planning/effort_ab.py fly large_400 10 20 $P $O/flown_large_400_b.json 0 $R ;;
esac
