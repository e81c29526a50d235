"""cpu-audit: how far today's replay of every registered task's recording (tests/recorded/) is
from the committed file, under whatever CPU emulation the environment sets (README.md).

``python results/audit/cpu/measure_recorded.py OUT.json`` writes, per task and per float
dtype, the largest absolute and relative difference and the number of values not bit-equal,
and whether every bool/int array is equal; run once natively and once per emulated CPU.
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

from poc_env import recorded, tasks


def compare(want: dict[str, np.ndarray], got: dict[str, np.ndarray]) -> dict:
    """Largest differences of ``got`` from ``want`` per float dtype; exactness of the rest."""
    out: dict = {"exact_other": True}
    for key, w in want.items():
        g = got[key]
        if w.dtype.kind != "f":
            out["exact_other"] &= bool(np.array_equal(g, w))
            continue
        rec = out.setdefault(str(w.dtype), {"max_abs": 0.0, "max_rel": 0.0, "n_diff": 0, "n": 0})
        w64, g64 = w.astype(np.float64), g.astype(np.float64)
        fin = np.isfinite(w64) & np.isfinite(g64)
        d = np.abs(g64[fin] - w64[fin])
        rec["n"] += int(w.size)
        rec["n_diff"] += int(np.count_nonzero(d)) + int(np.count_nonzero(~fin & (w64 != g64)))
        if d.size:
            rec["max_abs"] = max(rec["max_abs"], float(d.max()))
            scale = np.abs(w64[fin])
            nz = scale > 0
            if nz.any():
                rec["max_rel"] = max(rec["max_rel"], float((d[nz] / scale[nz]).max()))
    return out


def main(out: str) -> None:
    env = {
        k: os.environ.get(k)
        for k in (
            "NUMBA_CPU_NAME",
            "NUMBA_CPU_FEATURES",
            "NPY_DISABLE_CPU_FEATURES",
            "ATEN_CPU_CAPABILITY",
            "MKL_ENABLE_INSTRUCTIONS",
            "DNNL_MAX_CPU_ISA",
            "GLIBC_TUNABLES",
        )
    }
    res = {"env": env, "tasks": {}}
    for tid in tasks.TASKS:
        want = recorded.load(tid)
        res["tasks"][tid] = compare(want, recorded.replay(want))
        print(tid, res["tasks"][tid], flush=True)
    tmp = out + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(res, f, indent=1)
    os.replace(tmp, out)


if __name__ == "__main__":
    main(sys.argv[1])
