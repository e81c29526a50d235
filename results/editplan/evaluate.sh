#!/usr/bin/env bash
# i28-editplan: one policy's evaluation, once, on seeds 31000-31049 (no run or selection used
# them), one thread, timed: CPU seconds of the run (user; the flights cost about the same for
# every policy, so the differences are planning) in OUT/time.txt with the load average.
# Usage: bash results/editplan/evaluate.sh OUT POLICY [EXTRA evaluate args, e.g. --overrides ...]
# then:  bash results/editplan/summarise.sh OUT   (the paired summary over the runs' episodes)
set -euo pipefail
OUT=$1; POL=$2; shift 2
mkdir -p "$OUT/runs"
D="$OUT/runs/${POL//:/_}"
echo "$(date -u +%H:%M) load $(cut -d' ' -f1-3 /proc/loadavg) start $POL" >> "$OUT/time.txt"
/usr/bin/time -f "$POL user_s %U wall_s %e" -a -o "$OUT/time.txt" \
  env OMP_NUM_THREADS=1 nice -n 10 .venv/bin/poc-env evaluate --scenario paper_6_2 \
  --random-priors --seed 31000 --episodes 50 --policies "$POL" --quiet --out "$D" "$@"
echo "$(date -u +%H:%M) load $(cut -d' ' -f1-3 /proc/loadavg) end $POL" >> "$OUT/time.txt"
