set -x
P=/work/wt/i24-fleetcli/.venv/bin/poc-env
R=/work/wt/i24-fleetcli/results/plan_scale/i24-fleetcli
PY=/work/wt/i24-fleetcli/.venv/bin/python
uptime
/usr/bin/time -f "elapsed %e s cpu %U s" $P plan --scenario big.yaml --planner allocation --fleet-sizes 16,32,48,64 --quiet --out fleet/plan.json
uptime
for n in 16 32 48 64; do /usr/bin/time -f "elapsed %e s cpu %U s" $P plan --scenario big.yaml --planner allocation --uavs $n --quiet --out single/plan_n$n.json | grep -E "POS_C =|rule-aware|wrote"; uptime; done
$PY $R/conflicts.py big.yaml fleet/plan_n16.json fleet/plan_n32.json fleet/plan_n48.json fleet/plan_n64.json single/plan_n16.json single/plan_n32.json single/plan_n48.json single/plan_n64.json > conflicts.txt
$PY $R/fly.py big.yaml 0,1 fleet/plan_n16.json fleet/plan_n32.json fleet/plan_n48.json fleet/plan_n64.json single/plan_n16.json single/plan_n32.json single/plan_n48.json single/plan_n64.json > flown.jsonl
uptime
