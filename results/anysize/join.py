"""Join `poc-env evaluate --out` folders that flew the same seeds into one folder, and write its
summary (paired differences against ``--baseline``) with the code of ``poc-env summarise``.

The planners were evaluated once per condition while the policy trained; the checkpoints later,
on the same seeds. Episodes are deterministic per seed, so the joined folder is what one
``poc-env evaluate`` of all the policies would have written (its figure aside).

    python results/anysize/join.py --out results/anysize/eval_paper62 \
        results/anysize/base_paper62 results/anysize/ppo_paper62 --baseline allocation_plan
"""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path

from poc_env.agents.experiments.evaluate import read_episodes
from poc_env.errors import ConfigError
from poc_env.io import write_text_atomic


def join(folders: list[Path], out: Path, baselines: list[str]) -> Path:
    header: list[str] | None = None
    rows: list[dict[str, str]] = []
    seen: set[str] = set()
    for folder in folders:
        with (folder / "episodes.csv").open(newline="", encoding="utf-8") as f:
            reader = csv.DictReader(f)
            if header is None:
                header = list(reader.fieldnames or [])
            elif list(reader.fieldnames or []) != header:
                raise ConfigError("folders", str(folder), f"an episodes.csv with columns {header}")
            new = [r for r in reader if r["policy"] not in seen]  # a policy once (the first)
        seen |= {r["policy"] for r in new}
        rows += new
    assert header is not None
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=header, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "episodes.csv", buf.getvalue())
    ev = read_episodes(out / "episodes.csv")  # refuses policies flown on other seeds
    for name, text in ev.summary_files(baselines).items():
        write_text_atomic(out / name, text)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("folders", nargs="+", type=Path)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--baseline", default="allocation_plan")
    a = p.parse_args()
    out = join(a.folders, a.out, a.baseline.split(","))
    print((out / "evaluate.txt").read_text())


if __name__ == "__main__":
    main()
