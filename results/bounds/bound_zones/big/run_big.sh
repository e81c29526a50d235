set -e
B=$1; OUT=$2; export OMP_NUM_THREADS=1
cd /tmp/bz_big
[ -f big.yaml ] || { $B/python /work/wt/bound-zones/results/audit/scale/raw/make_inputs.py 500 24 in /work/wt/bound-zones/poc_env/configs/large_400.yaml && $B/poc-env scenario import in/area.geojson --prior in/prior.csv --airfields in/fields.geojson --no-fly in/zones.geojson --dem in/dem.tif --cell-km 3.125 --origin 45.0,5.0 --base in/base.yaml --out big.yaml; }
$B/poc-env plan --scenario big.yaml --planner allocation --quiet --out $OUT-p1.json
$B/poc-env replan --scenario big.yaml --plan $OUT-p1.json --out $OUT-p2.json
$B/python -c "
import json,sys
for f in ['$OUT-p1.json','$OUT-p2.json']:
    p=json.load(open(f)); print(f, 'posc', round(p['posc'],4), 'upper_bound', round(p['upper_bound'],4), 'bounds', {k:round(v,4) for k,v in p.get('bounds',{}).items()}, 'rule', round(p.get('bound_rule',-1),4))
"
