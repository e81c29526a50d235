#!/usr/bin/env bash
# replan-audit: the officer's CLI probes, run from the repository root with the worktree's venv:
#   OMP_NUM_THREADS=1 nice -n 10 bash results/audit/replan/cli_probes.sh /tmp/replan-audit/cli > results/audit/replan/cli_probes_branch.log 2>&1
# Each probe prints its command and the lines that matter (sortie summary, error, crs).
set -u
R=$(pwd); P=$R/.venv/bin; D=${1:-/tmp/replan-audit/cli}; rm -rf "$D"; mkdir -p "$D"; cd "$D"
run() { echo "\$ poc-env $*"; "$P/poc-env" "$@" 2>&1 | grep -E "^sortie|^error|^swept|^warning" ; echo "  (exit ${PIPESTATUS[0]})"; }
field() { "$P/python" -c "import json,sys; d=json.load(open(sys.argv[1])); print('  ', sys.argv[1], {k: d.get(k) for k in sys.argv[2:]})" "$@"; }
run plan --scenario small --planner allocation --origin 46.5,7.9 --quiet --out p1.json
echo "## three sorties on small"
run replan --plan p1.json --out p2.json
run replan --plan p1.json --plan p2.json --out p3.json
echo "## A: replan on its own output alone, and out of order"
run replan --plan p2.json --out x_alone.json
run replan --plan p2.json --plan p1.json --out x_swapped.json
echo "## another scenario's plan; the same scenario's plan of another seed as sortie 2"
run plan --scenario paper_6_2 --planner allocation --origin 46.5,7.9 --quiet --out q1.json
run replan --scenario small --plan q1.json --out x_other.json
run plan --scenario small --planner allocation --seed 7 --origin 46.5,7.9 --quiet --out p1s7.json
run replan --plan p1.json --plan p1s7.json --out x_seed7.json
echo "## B: a plan made with --map, replanned without it"
"$P/python" -c "
import numpy as np
from poc_env.config import load_scenario
from poc_env.theory.probability_map import build_prior
p = build_prior(load_scenario('small').map); np.save('flipped.npy', p[::-1, ::-1] / p.sum())"
run plan --scenario small --planner allocation --map flipped.npy --origin 46.5,7.9 --quiet --out pm1.json
field pm1.json posc map_source
run replan --plan pm1.json --out pm2.json
field pm2.json searched_pos map_source
echo "## C: --origin that disagrees with the plan's crs"
"$P/python" - <<'PY'
import json
from poc_env.crs import to_geographic
plan = json.load(open("p1.json"))
feats = [{"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": [
    [lon, lat] for lat, lon in to_geographic([u["takeoff_m"], *u["waypoints_m"], u["landing_m"]], plan["crs"])]}}
    for u in plan["uavs"]]
json.dump({"type": "FeatureCollection", "features": feats}, open("t.geojson", "w"))
json.dump({"type": "FeatureCollection", "features": [
    {**f, "geometry": {"type": "LineString", "coordinates": [[b, a] for a, b in f["geometry"]["coordinates"]]}}
    for f in feats]}, open("swapped.geojson", "w"))
PY
run replan --plan p1.json --tracks t.geojson --origin 46.6,7.95 --out x_origin.json
echo "## lat/lon swapped in a GeoJSON"
run replan --plan p1.json --tracks swapped.geojson --out x_swapped_ll.json
echo "## D: the Alps walkthrough, then its area re-imported 0.05 deg larger into the same alps.yaml"
mkdir -p alps && cd alps
cat > area.geojson <<'J'
{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"name": "Bernese Oberland search area"}, "geometry": {"type": "Polygon", "coordinates": [[[7.90, 46.50], [8.68, 46.50], [8.68, 46.859], [7.90, 46.859], [7.90, 46.50]]]}}]}
J
cat > airfield.geojson <<'J'
{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"name": "valley"}, "geometry": {"type": "Point", "coordinates": [7.77, 46.68]}}]}
J
cat > zone.geojson <<'J'
{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"name": "R-7 firing range"}, "geometry": {"type": "Polygon", "coordinates": [[[8.05, 46.63], [8.13, 46.63], [8.13, 46.72], [8.05, 46.72], [8.05, 46.63]]]}}]}
J
printf 'lat,lon,probability\n46.66,8.30,0.30\n46.70,8.36,0.25\n46.63,8.22,0.20\n46.74,8.45,0.15\n46.58,8.55,0.10\n' > prior.csv
(cd "$R" && "$P/python" -c "
import sys; from pathlib import Path; sys.path[:0] = ['tests/mission', 'tests']
import test_terrain as t; t._dem(Path('$D/alps/dem.tif'))")
"$P/poc-env" scenario import area.geojson --prior prior.csv --airfields airfield.geojson --no-fly zone.geojson --dem dem.tif --base small --out alps.yaml > /dev/null
A="--overrides uav.max_altitude_m=6000"
run plan --scenario alps.yaml --planner allocation $A --quiet --out a1.json
run replan --scenario alps.yaml --plan a1.json $A --out a2.json
run replan --plan a1.json --plan a2.json $A --out a3.json
run replan --plan a1.json --plan a2.json --plan a3.json $A --out a4.json
cat > crossing.geojson <<'J'
{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {"name": "UAV 1, straight through R-7"}, "geometry": {"type": "LineString", "coordinates": [[7.77, 46.68, 700], [8.09, 46.675, 3000], [8.30, 46.66, 3000], [8.45, 46.74, 3000], [7.77, 46.68, 700]]}}]}
J
echo "## a flown track across the no-fly zone (a real flight may): swept, not refused"
run replan --plan a1.json --tracks crossing.geojson $A --out a2_crossing.json
sed -i 's/\[7.90, 46.50\], \[8.68, 46.50\]/[7.90, 46.45], [8.75, 46.45]/; s/\[8.68, 46.859\], \[7.90, 46.859\], \[7.90, 46.50\]/[8.75, 46.859], [7.90, 46.859], [7.90, 46.45]/' area.geojson
"$P/poc-env" scenario import area.geojson --prior prior.csv --airfields airfield.geojson --no-fly zone.geojson --dem dem.tif --base small --out alps.yaml > /dev/null
run replan --scenario alps.yaml --plan a1.json $A --out r2.json
field a1.json crs
field r2.json crs
