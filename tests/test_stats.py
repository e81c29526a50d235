"""Student's t confidence intervals (issue 27: tables used 1.96 standard errors for any n)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.stats

from poc_env.stats import ci95, t_quantile

ROOT = Path(__file__).resolve().parents[1]

#: t(0.975, df) from a printed table of Student's t (two-sided 95 %), 3 decimals.
PRINTED = {1: 12.706, 2: 4.303, 4: 2.776, 9: 2.262, 19: 2.093, 29: 2.045, 49: 2.010}


@pytest.mark.parametrize("n", [2, 3, 5, 10, 20, 30, 50, 1000])
def test_the_interval_is_students_t(n):
    x = np.random.default_rng(n).normal(0.5, 0.1, n)
    se = x.std(ddof=1) / np.sqrt(n)
    assert ci95(x) == pytest.approx(scipy.stats.t.ppf(0.975, n - 1) * se, rel=1e-12)
    if n - 1 in PRINTED:
        assert t_quantile(n) == pytest.approx(PRINTED[n - 1], abs=5e-4)
    assert ci95(x) > 1.96 * se  # always wider than the normal approximation


def test_small_n_is_much_wider_than_196_standard_errors():
    x = [0.40, 0.42, 0.44, 0.46, 0.48]
    se = np.std(x, ddof=1) / np.sqrt(5)
    assert ci95(x) / (1.96 * se) == pytest.approx(2.776 / 1.96, abs=1e-3)  # 42 % wider


def test_axes_and_one_sample():
    arr = np.random.default_rng(0).random((6, 4))
    np.testing.assert_allclose(ci95(arr, axis=0), [ci95(arr[:, j]) for j in range(4)])
    assert ci95([0.3]) == 0.0  # one episode: no spread to estimate, not NaN
    np.testing.assert_array_equal(ci95(np.ones((1, 3)), axis=0), np.zeros(3))
    with pytest.raises(ValueError, match="n: got 1"):
        t_quantile(1)


def test_no_other_copy_of_the_normal_interval():
    """One implementation: no module computes ``1.96 * std / sqrt(n)`` by itself any more."""
    files = [*(ROOT / "poc_env").glob("**/*.py"), *(ROOT / "agents").glob("**/*.py")]
    copies = [
        f"{f.relative_to(ROOT)}:{i}"
        for f in sorted(set(files) - {ROOT / "poc_env" / "stats.py"})  # its docstring's formula
        if "agents" not in f.relative_to(ROOT).parts[1:2]  # poc_env/agents: agents/ again
        for i, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1)
        if re.search(r"1\.96\s*\*", line)
    ]
    assert copies == []
