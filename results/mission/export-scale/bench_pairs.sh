W=/work/wt/export-scale
B=$W/results/mission/export-scale/bench_export.py
cd /tmp/es_big/in
export OMP_NUM_THREADS=1
for i in 1 2 3; do
  PYTHONPATH=/tmp/es_main nice -n 10 $W/.venv/bin/python $B pdn.json geojson "main pair$i"
  nice -n 10 $W/.venv/bin/python $B pdn.json geojson "export-scale pair$i"
done
echo done
