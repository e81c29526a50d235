#!/bin/bash
# waits for the fleet run, then the one-size default plans at 24 and 48 UAVs
while pgrep -f "fleet-sizes 16,32,48,64 --out fleet/plan.json" > /dev/null; do sleep 5; done
P=/work/wt/i24-leftovers/.venv/bin/poc-env
for n in 24 48; do
  uptime
  OMP_NUM_THREADS=1 nice -n 10 /usr/bin/time -f "elapsed %e s cpu %U s" $P plan --scenario big.yaml --planner allocation --uavs $n --quiet --out single/plan_n$n.json
  uptime
done
