#!/bin/bash
HERE=$(cd "$(dirname "$0")" && pwd)
# usage: pair.sh SCENARIO N  (main at /work/main, this tree; one warm plan per process)
# alternate main / branch, one process each, CPU and wall of one warm plan, with the load
for r in 1 2; do
  for tree in /work/main /work/wt/i24-fleet; do
    out=$(cd /tmp && OMP_NUM_THREADS=1 PYTHONPATH=$tree nice -n 10 $HERE/../../../.venv/bin/python $HERE/warm_plan.py "$@")
    echo "$* round $r $tree $out load $(cut -d' ' -f1 /proc/loadavg)"
  done
done
