# run from the repository root: WALK=/path/of/walk bash results/audit/cpu/walkthrough_plan_by_variant.sh
REPO=$PWD
cd "${WALK:?set WALK to the folder where the walkthrough setup block of docs/missions.md ran}"
export PATH=$REPO/.venv/bin:$PATH OMP_NUM_THREADS=1
v() { echo "== $1"; shift; env "$@" nice -n 10 poc-env plan --scenario harbin.yaml --popsize 40 --maxiter 100 --out plan_$RANDOM.json 2>&1 | grep -i "POS_C" | tail -2; }
v native
v glibc GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX
v numba NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=$(mktemp -d)
v numpy NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR"
v torch ATEN_CPU_CAPABILITY=default MKL_ENABLE_INSTRUCTIONS=SSE4_2 DNNL_MAX_CPU_ISA=SSE41
v numpy_haswell NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR"
