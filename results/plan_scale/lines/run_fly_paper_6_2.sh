#!/bin/sh
# The chosen variant flown on paper_6_2's 50 reported priors, in two processes (0-24 with
# allocation_plan@thorough+polish_grade=1 -- thorough's options -- re-flown on seed 0 to check
# it equals the stored flight of results/plan_scale/grade; 25-49), records joined for the
# paired figures (README). Usage: run_fly_paper_6_2.sh a|b VARIANT
P=allocation_plan@$2
O=results/plan_scale/lines
R="results/plan_scale/paper_6_2.json results/plan_scale/effort/flown_paper_6_2.json results/plan_scale/polish/flown_paper_6_2_thorough.json results/plan_scale/grade/flown_paper_6_2.json"
export OMP_NUM_THREADS=1
case "$1" in
  a) python tests/planning/effort_ab.py fly paper_6_2 0 25 $P,allocation_plan@thorough+polish_grade=1 $O/flown_paper_6_2_a.json 1 $R ;;
  b) python tests/planning/effort_ab.py fly paper_6_2 25 50 $P $O/flown_paper_6_2_b.json 0 $R ;;
esac
