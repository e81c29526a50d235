#!/bin/sh
# Validation priors only: paper_6_2's own prior (seed -1) and 5000-5011, in two processes
# (part1: -1, 5000-5005; part2: 5006-5011); the thorough records of 5000-5011 copied from
# results/plan_scale/polish/validation_paper_6_2_thorough_basepolished.json (seed -1 re-planned:
# equal to the last digit).
V=thorough,thorough+polish_starts=2,thorough+polish_grade=1,thorough+polish_starts=2+polish_grade=1
O=results/plan_scale/grade
export OMP_NUM_THREADS=1
case "$1" in
  part1) python tests/planning/effort_ab.py polish paper_6_2 -1 0 $V $O/validation_paper_6_2_part1.json &&
         python tests/planning/effort_ab.py polish paper_6_2 5000 5006 $V $O/validation_paper_6_2_part1.json ;;
  part2) python tests/planning/effort_ab.py polish paper_6_2 5006 5012 $V $O/validation_paper_6_2_part2.json ;;
esac
