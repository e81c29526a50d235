"""i24-boxes: two stage2.py variants paired per seed (their gains over the same stored plans).

``python results/plan_scale/boxes/paired.py A.json VARIANT_A B.json VARIANT_B``: the
difference A - B of the planned POS (2 x 2 lattice) and of the 8 x 8 lattice's, over the
rule-aware bound, per seed and as a mean ± Student's t 95 % (wins / ties / losses).
"""

import json
import sys

from stage2 import t95


def main(a_path: str, a_var: str, b_path: str, b_var: str) -> None:
    with open(a_path) as f:
        a = {r["seed"]: r for r in json.load(f) if r["variant"] == a_var}
    with open(b_path) as f:
        b = {r["seed"]: r for r in json.load(f) if r["variant"] == b_var}
    seeds = sorted(set(a) & set(b))
    d2 = [(a[s]["planned_posc"] - b[s]["planned_posc"]) / a[s]["rule_bound"] for s in seeds]
    d8 = [(a[s]["fine_posc"] - b[s]["fine_posc"]) / a[s]["rule_bound"] for s in seeds]
    for s, x, y in zip(seeds, d2, d8):
        print(s, f"{x:+.4f}", f"{y:+.4f}")
    print(f"{a_var} - {b_var}: n={len(seeds)} 2x2 {t95(d2)}  8x8 {t95(d8)}")


if __name__ == "__main__":
    main(*sys.argv[1:5])
