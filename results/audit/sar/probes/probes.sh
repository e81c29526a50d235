#!/usr/bin/env bash
# The audit's probes (results/audit/sar/README.md), run in a scratch folder:
#   export PATH=$REPO/.venv/bin:$PATH; mkdir /tmp/audit && cd /tmp/audit
#   python $REPO/results/audit/sar/probes/layers.py . && bash $REPO/results/audit/sar/probes/probes.sh
# Each line prints what the command printed besides "wrote ..." lines.
export OMP_NUM_THREADS=1
imp() { d=$1; shift; echo "== import $d: $*"; rm -rf "$d"
        poc-env scenario import "$@" --out "$d/s.yaml" 2>&1 | grep -v '^wrote'; }
fly() { d=$1; pl=$2; shift 2; [ -f "$d/s.yaml" ] || return 0
        (cd "$d" && nice -n 10 poc-env plan --scenario s.yaml --planner "$pl" --quiet "$@" \
            --out "p_$pl.json" 2>&1 | grep -E 'POS_C|no search|error'
         for f in geojson kml qgc html; do
             poc-env export "p_$pl.json" --format "$f" --out "ex_$pl" 2>&1 | grep -v '^wrote'
         done); }
# 1. CSV priors
for f in bom semi zero crlf quoted upper; do
    imp "csv_$f" ch_area.geojson --airfields ch_field.geojson --prior "$f.csv" --base small
done
# 2. CRSs, hemispheres, shapes
imp nz nz_area.geojson --airfields nz_field.geojson --base small
imp nzu nz_area.geojson --airfields nz_field.geojson --projection utm --base small
imp fj fj_area.geojson --airfields fj_field.geojson --base small
imp fjw fj_area.geojson --airfields fj_field_w.geojson --base small
imp am am_area.geojson --airfields fj_field.geojson --base small
imp po po_area.geojson --airfields po_field.geojson --base small
imp bare bare_area.geojson --airfields nz_field.geojson --base small
imp mp mp_area.geojson --airfields nz_field.geojson --base small
imp feat feat_area.geojson --airfields nz_field.geojson --base small
imp bf nz_area.geojson --airfields bare_field.geojson --base small
imp kml1 area.kml --airfields fields.kml --base small
imp kml2 area.kml --airfields fields_line.kml --base small
for d in nz nzu fj fjw po; do fly $d allocation; done
# 3. no-fly zones
for z in touch overlap between many field whole hole bowtie empty emptyfc nullgeom dup far \
         long_name ctl uni; do
    imp "z_$z" nz_area.geojson --airfields nz_field.geojson --no-fly "z_$z.geojson" --base small
    fly "z_$z" allocation
done
for n in 64 360 2000; do
    imp "c$n" nz_area.geojson --airfields nz_field.geojson --no-fly "circle$n.geojson" --base small
    fly "c$n" allocation
done
imp f_long nz_area.geojson --airfields f_long.geojson --base small; fly f_long allocation --refine 0
imp f_ctl nz_area.geojson --airfields f_ctl.geojson --base small
imp uni nz_area.geojson --airfields f_uni.geojson --no-fly z_uni.geojson --base small
fly uni allocation --refine 0
# 4. sizes: a tiny area, a thin one, an airfield out of reach, 1 UAV, 24 UAVs, the largest area
imp tiny tiny_area.geojson --airfields tiny_field.geojson --base small --cell-km 0.5
imp tiny5 tiny_area.geojson --airfields tiny_field.geojson --base small --cell-km 5
imp far nz_area.geojson --airfields far_field.geojson --base small
imp thin thin_area.geojson --airfields nz_field.geojson --base small
for d in tiny tiny5 far thin; do fly $d allocation; fly $d de; done
fly nz allocation --uavs 1
fly nz allocation --uavs 24
imp big big_area.geojson --airfields big_fields.geojson --no-fly big_zones.geojson \
    --prior big_prior.csv --base wide_400
fly big allocation --uavs 24
