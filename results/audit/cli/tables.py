"""Markdown tables of the cli-audit logs: ``python results/audit/cli/tables.py KILLS.jsonl
[PROBES.jsonl ...]`` (kill harness: one row per command; probes: exit statuses)."""

from __future__ import annotations

import collections
import json
import sys


def _rows(path: str) -> list[dict]:
    with open(path, encoding="utf-8") as fh:
        return [json.loads(line) for line in fh]


def kills(path: str) -> None:
    rows = _rows(path)
    refs = {r["command"]: r for r in rows if r.get("reference")}
    by = collections.defaultdict(list)
    for r in rows:
        if not r.get("reference"):
            by[r["command"]].append(r)
    print("| command | T (s, load) | kills | states after the kill | SIGINT exits | "
          "tracebacks | hidden temp left | rerun ok |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    for name, ref in refs.items():
        ks = by.get(name, [])
        if ref["exit"] != 0:
            print(f"| {name} | reference failed: {str(ref['err'])[:90]} | 0 | | | | | |")
            continue
        states = collections.Counter(
            ("finished " if k["finished_first"] else "") + k["state"]
            + (" (over old)" if k["over"] else "")
            for k in ks
        )  # fmt: skip
        ints = collections.Counter(str(k["exit"]) for k in ks if k["signal"] == "SIGINT")
        tb = sum(k["traceback"] for k in ks)
        temp = sum(bool(k["temp_left"]) for k in ks)
        ok = sum(k["rerun_ok"] for k in ks)
        print(
            f"| {name} | {ref['wall_s']} ({ref['load1']:.1f}) | {len(ks)} | "
            + ", ".join(f"{s} {n}" for s, n in sorted(states.items()))
            + f" | {', '.join(f'{e}: {n}' for e, n in sorted(ints.items()))} | {tb} | {temp} "
            f"| {ok}/{len(ks)} |"
        )


def probes(path: str) -> None:
    rows = _rows(path)
    c = collections.Counter(str(r["exit"]).split(" ")[0] for r in rows)
    stray = sum(bool(r["stray_in_inputs"]) for r in rows)
    outside = sum(bool(r.get("outside")) for r in rows)
    print(f"{path}: {len(rows)} probes; exit statuses {dict(sorted(c.items()))}; writes into "
          f"the inputs: {stray}; new entries beside the probe folders: {outside}")  # fmt: skip
    for r in rows:
        if str(r["exit"]) != "2":
            print(f"  - `{r['probe'][:60]}`: {r['exit']} {r['traceback'][:90]}")


if __name__ == "__main__":
    kills(sys.argv[1])
    for p in sys.argv[2:]:
        probes(p)
