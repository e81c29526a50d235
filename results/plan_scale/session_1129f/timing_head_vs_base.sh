for i in 1 2; do
 for w in head base; do
  echo "== $w run $i $(cut -d' ' -f1-3 /proc/loadavg)"
  (cd /work/$w && OMP_NUM_THREADS=1 PYTHONPATH=/work/$w /work/main/.venv/bin/python -m poc_env.cli bench plan --scale --scale-parts timing --runs 3 2>&1 | grep "plan_s\|load")
 done
done
