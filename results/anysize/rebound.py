"""i24-tightbound: the rule-aware figures of the any-size evaluations on ``wide_400`` (three
airfields) renormalised by the tight rule-aware bound, no re-flying.

:func:`poc_env.theory.bound.rule_bound` merged airfields beyond two until i24-tightbound. For
each folder (``DIR=TASK``) this recomputes each seed's bound on the task's scenario and the
seed's random prior (``episode_prior``, what ``poc-env evaluate --task TASK`` draws), checks
that the stored ``bound_rule`` is the merged relaxation's (``RuleBound.merged``, to 1e-9) or
already the new bound, rewrites ``bound_rule`` and ``normalised_rule`` of ``episodes.csv``
(every other cell as it was), and writes the summary files again from it as ``poc-env
summarise`` does (:func:`~poc_env.agents.experiments.evaluate.read_episodes`; baseline
``allocation_plan`` where the folder has a ``paired.csv``). All files are written atomically.

    PYTHONPATH=. OMP_NUM_THREADS=1 python results/anysize/rebound.py \\
        results/anysize/base_wide_n6=UAVSearch-Wide-N6-Random-Set-Heading-v1 ...
"""

from __future__ import annotations

import csv
import io
import sys
from pathlib import Path

from poc_env.agents.experiments.evaluate import episode_prior, read_episodes
from poc_env.io import write_text_atomic
from poc_env.tasks import get_task
from poc_env.theory.bound import RuleBound, rule_bound

_cache: dict[tuple[str, int], RuleBound] = {}


def rebound(folder: Path, task: str) -> None:
    sc = get_task(task).load_scenario()
    path = folder / "episodes.csv"
    text = path.read_text(encoding="utf-8")
    reader = csv.DictReader(io.StringIO(text))
    rows = list(reader)
    for r in rows:
        seed = int(r["seed"])
        if (task, seed) not in _cache:
            _cache[(task, seed)] = rule_bound(sc, episode_prior(sc, seed))
        rb = _cache[(task, seed)]
        old = float(r["bound_rule"])
        if abs(old - rb.merged) > 1e-9 and abs(old - rb.upper) > 1e-9:
            raise SystemExit(f"{path}: seed {seed}: stored bound_rule {old} is neither "
                             f"{rb.merged} (merged) nor {rb.upper}")  # fmt: skip
        r["bound_rule"] = repr(rb.upper)
        r["normalised_rule"] = repr(float(r["posc"]) / rb.upper)
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=reader.fieldnames, lineterminator="\r\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(path, buf.getvalue())
    baselines = ["allocation_plan"] if (folder / "paired.csv").exists() else []
    for name, body in read_episodes(path).summary_files(baselines).items():
        write_text_atomic(folder / name, body)
    share = [float(r["bound_rule"]) / _cache[(task, int(r["seed"]))].merged for r in rows]
    mean = sum(share) / len(share)
    print(f"{folder}: {len(rows)} episodes; new bound / merged: mean {mean:.3f}, "
          f"min {min(share):.3f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    for arg in sys.argv[1:]:
        d, t = arg.split("=", 1)
        rebound(Path(d), t)
