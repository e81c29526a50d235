set -e
W=/work/wt/export-scale
export OMP_NUM_THREADS=1
nice -n 10 $W/.venv/bin/python $W/results/audit/scale/raw/make_inputs.py 500 24 in $W/configs/large_400.yaml > make.log 2>&1
cd in
ls
nice -n 10 $W/.venv/bin/poc-env scenario import area.geojson --prior prior.csv --airfields fields.geojson \
    --no-fly zones.geojson --dem dem.tif --cell-km 3.125 --origin 45.0,5.0 --base base.yaml --out big.yaml
nice -n 10 $W/.venv/bin/poc-env plan --scenario big.yaml --planner de --popsize 16 --maxiter 20 --quiet \
    --overrides sensor.sweep_width_km=0.5 --out pdn.json > plan_dn.log 2>&1
echo done
