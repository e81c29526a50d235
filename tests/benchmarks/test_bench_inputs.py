"""``poc-env bench NAME`` with bad values: a clear ``error: FIELD: ...`` (exit status 2), never
a traceback nor a table of ``nan`` / ``0 in 0.0 s`` from a count below one."""

import subprocess
import sys

import pytest

from poc_env.cli import BENCHMARKS


@pytest.mark.parametrize("what", ["env", "plan", "train", "moving-bound"])
def test_bench_bad_input_ends_as_an_error_line_not_a_traceback(what):
    """An unknown scenario to ``poc-env bench NAME``: ``error: scenario: ...`` and status 2, as
    the other benchmarks (their ``__main__`` is ``run_main``)."""
    r = subprocess.run(
        [sys.executable, "-m", BENCHMARKS[what], "--scenario", "nosuch"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("error: scenario: got 'nosuch'")
    assert "Traceback" not in r.stderr
