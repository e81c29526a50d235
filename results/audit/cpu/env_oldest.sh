# the oldest x86-64 this machine can emulate: numba for a generic x86-64, numpy's dispatch at
# its X86_V2 baseline, torch/MKL/oneDNN at their defaults/SSE4, glibc's libm without FMA/AVX2
export NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=$(mktemp -d)
export NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR"
export ATEN_CPU_CAPABILITY=default MKL_ENABLE_INSTRUCTIONS=SSE4_2 DNNL_MAX_CPU_ISA=SSE41
export GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX
export OMP_NUM_THREADS=1
