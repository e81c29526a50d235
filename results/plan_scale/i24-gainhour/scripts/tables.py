"""i24-gainhour: the tables of README.md from rules.py's records (``python tables.py
big.json paper.json final.json final2.json``; final.json's rows named ``screened`` (the
credit-screened rule at 905e5d1), final2.json's ``final`` (every marginal, c1134dd); more
files (final2_alt.json) as ``final-RULE``):
per case and rule, UAVs flying, flight hours, planned and flown POS_C and their differences
from main's rule (``budget``); for the ``paper_6_2`` priors the paired differences, Student's
t 95 % interval and wins/ties/losses against ``budget``."""

import json
import statistics
import sys

from scipy import stats


def row(key, r, b):
    return (
        f"| {key} | {r['flying']} | {r['hours']:.1f} | {r['planned']:.6f} | "
        f"{r['planned'] - b['planned']:+.1e} | {r['flown']:.6f} | "
        f"{r['flown'] - b['flown']:+.1e} | {r['collision_steps']} | {len(r['home'])} |"
    )


with open(sys.argv[1]) as f:
    big = json.load(f)
with open(sys.argv[2]) as f:
    paper = json.load(f)
for arg, name in (
    (sys.argv[3], "screened"),
    (sys.argv[4], "final"),
    *[(a, "final-") for a in sys.argv[5:]],
):
    with open(arg) as f:
        for key, r in json.load(f).items():
            case, rule = key.rsplit(":", 1)
            named = name + rule if name.endswith("-") else name
            (paper if key.startswith("paper") else big)[case + ":" + named] = r
print(
    "| case:rule | flying | hours | planned | vs budget | flown | vs budget | collision | by rule |"
)
print("|---|---|---|---|---|---|---|---|---|")
for key, r in big.items():
    b = big[key.rsplit(":", 1)[0] + ":budget"]
    print(row(key, r, b))
rules = sorted({k.rsplit(":", 1)[1] for k in paper})
print()
print(
    "| rule | cases | plans equal to budget's | planned diff mean [95 % CI] | flown diff mean "
    "[95 % CI] | flown W/T/L | hours diff |"
)
print("|---|---|---|---|---|---|---|")
for rule in rules:
    keys = [k for k in paper if k.endswith(":" + rule)]
    d_pl, d_fl, d_h, same = [], [], [], 0
    for k in keys:
        b = paper[k.rsplit(":", 1)[0] + ":budget"]
        r = paper[k]
        same += r["digest"] == b["digest"]
        d_pl.append(r["planned"] - b["planned"])
        d_fl.append(r["flown"] - b["flown"])
        d_h.append(r["hours"] - b["hours"])

    def ci(d):
        m = statistics.mean(d)
        s = statistics.stdev(d) if len(d) > 1 else 0.0
        h = stats.t.ppf(0.975, len(d) - 1) * s / len(d) ** 0.5 if s else 0.0
        return f"{m:+.2e} [{m - h:+.2e}, {m + h:+.2e}]"

    wtl = (sum(x > 0 for x in d_fl), sum(x == 0 for x in d_fl), sum(x < 0 for x in d_fl))
    print(
        f"| {rule} | {len(keys)} | {same} | {ci(d_pl)} | {ci(d_fl)} | {wtl[0]}/{wtl[1]}/{wtl[2]} "
        f"| {statistics.mean(d_h):+.2f} |"
    )
