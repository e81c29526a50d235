"""Paired tables of the instrument records (``instrument.py``'s JSON lines):

    PYTHONPATH=. python results/moving/recede/table.py A.jsonl[,MORE.jsonl] [B.jsonl[,...]] \
        [--names A_NAME B_NAME]
    PYTHONPATH=. python results/moving/recede/table.py --rows A.jsonl[,MORE.jsonl]

For each side: seeds, mean POSC of ``spacetime_plan`` and ``spacetime_receding``, receding - plan
(Student's t 95 %, wins/ties/losses), re-plans due / made / flown per episode and how the made
ones scored against the routes being flown; then after - before of each policy, paired by seed.
"""

from __future__ import annotations

import json
import sys

import numpy as np

from poc_env.agents.policies.moving import SWITCH_MARGIN
from poc_env.stats import ci95

TIE = 1e-12
MARGIN = SWITCH_MARGIN


def load(arg: str) -> dict[int, dict]:
    out = {}
    for path in arg.split(","):
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.strip():
                    r = json.loads(line)
                    out[r["seed"]] = r
    return out


def paired(d) -> str:
    d = np.asarray(d, dtype=float)
    w, t, lo = int((d > TIE).sum()), int((abs(d) <= TIE).sum()), int((d < -TIE).sum())
    return f"{d.mean():+.4f} ± {float(ci95(d)):.4f} ({w}/{t}/{lo})"


def side(name: str, recs: dict[int, dict]) -> None:
    seeds = sorted(s for s in recs if "plan" in recs[s])
    plan = np.array([recs[s]["plan"] for s in seeds])
    rec = np.array([recs[s]["receding"] for s in seeds])
    made = [[x for x in recs[s]["log"] if x["made"]] for s in seeds]
    diffs = np.array([x["diff"] for m in made for x in m])
    flown = np.array([recs[s]["switches"] for s in seeds])
    print(f"## {name}: seeds {seeds[0]}-{seeds[-1]} (n={len(seeds)})")
    print(f"spacetime_plan {plan.mean():.4f} ± {float(ci95(plan)):.4f}")
    print(f"spacetime_receding {rec.mean():.4f} ± {float(ci95(rec)):.4f}")
    print(f"receding - plan {paired(rec - plan)} (wins/ties/losses)")
    print(
        f"re-plans per episode: due {np.mean([len(recs[s]['log']) for s in seeds]):.1f}, "
        f"made {np.mean([len(m) for m in made]):.1f}, flown {flown.mean():.2f}; "
        f"episodes with none flown {int((flown == 0).sum())}"
    )
    if len(diffs):
        print(
            f"made re-plans' model score - kept: median {np.median(diffs):+.4f}, "
            f"min {diffs.min():+.4f}, max {diffs.max():+.4f}; "
            f"< 0: {int((diffs < 0).sum())}, in [0, margin]: "
            f"{int(((diffs >= 0) & (diffs <= MARGIN)).sum())}, "
            f"> margin: {int((diffs > MARGIN).sum())}"
        )


def rows(recs: dict[int, dict]) -> None:
    """One markdown row a seed: drift, both POSCs, the difference, re-plans made / flown (when),
    the made ones' model score - kept below 0 / within the margin / above it."""
    for s in sorted(x for x in recs if "plan" in recs[x]):
        r = recs[s]
        made = [x for x in r["log"] if x["made"]]
        d = [x["diff"] for x in made]
        at = ", ".join(f"{x['min']:g}" for x in made if x["switched"])
        neg = sum(1 for x in d if x < 0)
        mid = sum(1 for x in d if 0 <= x <= MARGIN)
        print(
            f"| {s} | {r['drift_kmh']:.1f} | {r['plan']:.4f} | {r['receding']:.4f} | "
            f"{r['receding'] - r['plan']:+.4f} | {len(made)} / {r['switches']} ({at}) | "
            f"{neg} / {mid} / {len(d) - neg - mid} |"
        )


def main() -> None:
    args = sys.argv[1:]
    if args[0] == "--rows":
        rows(load(args[1]))
        return
    names = ["main", "variant"]
    if "--names" in args:
        i = args.index("--names")
        names[: len(args) - i - 1] = args[i + 1 :]
        args = args[:i]
    before, after = load(args[0]), load(args[1]) if len(args) > 1 else {}
    side(names[0], before)
    if after:
        side(names[1], after)
        seeds = sorted(
            s for s in before if s in after and "plan" in before[s] and "plan" in after[s]
        )
        print(f"## {names[1]} - {names[0]}, paired (n={len(seeds)})")
        for pol in ("plan", "receding"):
            d = [after[s][pol] - before[s][pol] for s in seeds]
            print(f"{pol}: {paired(d)}")


if __name__ == "__main__":
    main()
