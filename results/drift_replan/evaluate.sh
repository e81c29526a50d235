#!/bin/bash
# Fly each policy on the evaluation stream (seeds 8000-8049), one poc-env evaluate per policy
# so that its wall time is its own; times.csv: policy, seconds, load average at the start.
# usage: results/drift_replan/evaluate.sh OUT_ROOT POLICY...
set -e
out=$1; shift
mkdir -p "$out"
for p in "$@"; do
  d="$out/$(echo "$p" | tr ':/@.' '____')"
  load=$(cut -d' ' -f1 /proc/loadavg)
  t0=$(date +%s.%N)
  OMP_NUM_THREADS=1 python -m poc_env.cli evaluate --task UAVSearch-Small-Drift-Heading-v1 \
      --episodes 50 --seed 8000 --policies "$p" --out "$d" > "$d.log" 2>&1
  t1=$(date +%s.%N)
  echo "$p,$(echo "$t1 - $t0" | bc),$load" >> "$out/times.csv"
done
