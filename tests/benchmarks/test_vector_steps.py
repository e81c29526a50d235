"""``agents/benchmarks/vector_steps.py``: make_vec steps timed and measured by kind."""

from __future__ import annotations

from poc_env.agents.benchmarks import vector_steps


def test_steps_are_sorted_by_kind_and_counted():
    # Small episodes last 81 steps: 20 warm-up steps and 80 timed ones reach an autoreset
    rows = vector_steps.time_steps("Small", 2, 80)
    assert sum(rows[k]["count"] for k in vector_steps.KINDS) == rows["whole"]["count"] == 80
    assert rows["autoreset"]["count"] >= 1
    assert 1 <= rows["autoreset"]["envs_reset"] <= 2
    peaks = vector_steps.peak_per_env("Small", 2, 80)
    assert set(peaks) <= set(vector_steps.KINDS) and "autoreset" in peaks
    assert all(v > 0 for v in peaks.values())
