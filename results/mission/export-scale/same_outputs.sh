W=/work/wt/export-scale
cd /tmp/es_big/in
export OMP_NUM_THREADS=1
for f in geojson kml qgc; do
  rm -rf old_$f new_$f
  if [ $f = qgc ]; then extra=""; newextra="--allow-infeasible"; else extra=""; newextra=""; fi
  PYTHONPATH=/tmp/es_main nice -n 10 $W/.venv/bin/poc-env export pdn.json --format $f --out old_$f > old_$f.log 2>&1
  nice -n 10 $W/.venv/bin/poc-env export pdn.json --format $f $newextra --out new_$f > new_$f.log 2>&1
  echo "$f: $(diff -r old_$f new_$f > /dev/null && echo identical || echo DIFFERENT)"
done
nice -n 10 $W/.venv/bin/poc-env export pdn.json --format qgc --out refused_qgc > refused_qgc.log 2>&1; echo "qgc without --allow-infeasible: exit $?"
echo done
