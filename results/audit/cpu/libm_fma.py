"""cpu-audit: glibc's libm (which numba kernels call for exp, log1p, ...) with and without FMA.

``python results/audit/cpu/libm_fma.py OUT.json`` writes every result's hex for 200 000
arguments drawn from ``random.Random(1)``; ``python results/audit/cpu/libm_fma.py --compare
A.json B.json`` counts the values that differ and their largest relative difference. Run once
natively and once with ``GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA`` (glibc's code paths for a
CPU without FMA; numpy and numba's own code are unaffected by it).
"""

from __future__ import annotations

import json
import math
import random
import sys

FUNCTIONS = {
    "exp": math.exp,
    "log1p": lambda v: math.log1p(abs(v)),
    "expm1": math.expm1,
    "atan": math.atan,
    "sin": math.sin,
    "pow": lambda v: math.pow(abs(v), 1.5),
}


def _numba_exp(xs: list[float]) -> list[float]:
    """``exp`` in a numba loop (LLVM's ``llvm.exp``, which resolves to glibc's ``exp``)."""
    import numba
    import numpy as np

    @numba.njit(cache=False)
    def run(x, out):
        for i in range(x.size):
            out[i] = math.exp(x[i])

    x = np.array(xs)
    out = np.empty_like(x)
    run(x, out)
    return [float(v) for v in out]


def values(out: str) -> None:
    rng = random.Random(1)
    xs = [rng.uniform(-30.0, 30.0) for _ in range(200_000)]
    res = {name: [fn(x).hex() for x in xs] for name, fn in FUNCTIONS.items()}
    res["numba_exp"] = [v.hex() for v in _numba_exp(xs)]
    with open(out, "w", encoding="utf-8") as f:
        json.dump(res, f)


def compare(a_path: str, b_path: str) -> None:
    with open(a_path, encoding="utf-8") as f:
        a = json.load(f)
    with open(b_path, encoding="utf-8") as f:
        b = json.load(f)
    for name in [*FUNCTIONS, "numba_exp"]:
        pairs = [(float.fromhex(x), float.fromhex(y)) for x, y in zip(a[name], b[name]) if x != y]
        rel = max((abs(x - y) / abs(x) for x, y in pairs if x), default=0.0)
        print(f"{name:6s} {len(pairs):4d} of {len(a[name])} differ, largest relative {rel:.3g}")


if __name__ == "__main__":
    if sys.argv[1] == "--compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        values(sys.argv[1])
