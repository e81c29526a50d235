#!/bin/bash
# probes 13 (swall) and 14 (swall2) of results/audit/dayaudit: main, the branch (rates unset),
# the branch at PX4's defaults (5/5 m/s), with only the sink rate at 5 m/s, and with the
# climb rate raised until UAV 3's take-off flies (8, 10, 12 m/s; sink 5)
B=/work/wt/i24-rates/.venv/bin/poc-env; M=/work/main/.venv/bin/poc-env
for s in swall swall2; do
  $M plan --scenario $s.yaml --planner allocation --quiet --out main_$s.json > main_$s.plan.log 2>&1; echo "$s main rc=$?"
  $B plan --scenario $s.yaml --planner allocation --quiet --out br_$s.json > br_$s.plan.log 2>&1; echo "$s branch rc=$?"
  $B plan --scenario $s.yaml --planner allocation --quiet --overrides uav.max_climb_rate_mps=5 uav.max_sink_rate_mps=5 --out px4_$s.json > px4_$s.plan.log 2>&1; echo "$s px4 rc=$?"
  $B plan --scenario $s.yaml --planner allocation --quiet --overrides uav.max_sink_rate_mps=5 --out sink5_$s.json > sink5_$s.plan.log 2>&1; echo "$s sink5 rc=$?"
  for c in 8 10 12; do
    $B plan --scenario $s.yaml --planner allocation --quiet --overrides uav.max_climb_rate_mps=$c uav.max_sink_rate_mps=5 --out c${c}_$s.json > c${c}_$s.plan.log 2>&1; echo "$s climb $c sink 5 rc=$?"
  done
done
