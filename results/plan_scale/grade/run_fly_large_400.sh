#!/bin/sh
# thorough + grade moves flown on large_400's reported priors (as many as time allowed), paired
# with the stored flights (README).
P=allocation_plan@thorough+polish_grade=1
O=results/plan_scale/grade
R="results/plan_scale/large_400.json results/plan_scale/effort/flown_large_400.json results/plan_scale/polish/flown_large_400_thorough.json"
export OMP_NUM_THREADS=1
case "$1" in
  a) python tests/planning/effort_ab.py fly large_400 0 10 $P $O/flown_large_400_a.json 0 $R ;;
  b) python tests/planning/effort_ab.py fly large_400 10 20 $P $O/flown_large_400_b.json 0 $R ;;
esac
