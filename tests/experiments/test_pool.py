"""Worker pools: results in job order, and no wait without a timeout (issue 15 item 14)."""

from __future__ import annotations

import time

import pytest

from poc_env.agents.experiments.pool import WorkerTimeoutError, run_jobs, sleep_job


def test_results_come_back_in_job_order_on_workers():
    jobs = [0.2, 0.0, 0.1]
    assert run_jobs(sleep_job, jobs, workers=2) == jobs
    assert run_jobs(sleep_job, jobs, workers=1) == jobs


def test_a_hung_worker_ends_in_a_clear_error_not_a_wait(monkeypatch):
    monkeypatch.setenv("POC_ENV_WORKER_TIMEOUT_S", "2")
    t0 = time.monotonic()
    with pytest.raises(WorkerTimeoutError, match="POC_ENV_WORKER_TIMEOUT_S"):
        run_jobs(sleep_job, [0.0, 600.0, 0.0], workers=2)
    assert time.monotonic() - t0 < 120  # the 600 s job was killed, not waited for


def test_the_timeout_setting_is_validated(monkeypatch):
    from poc_env.errors import ConfigError

    monkeypatch.setenv("POC_ENV_WORKER_TIMEOUT_S", "soon")
    with pytest.raises(ConfigError, match="POC_ENV_WORKER_TIMEOUT_S"):
        run_jobs(sleep_job, [0.0, 0.0], workers=2)


def test_workers_die_with_a_killed_command(tmp_path):
    """``kill -9`` of a command running jobs on workers leaves no worker behind (issue 27:
    they were reparented to PID 1 and kept their memory for minutes)."""
    import os
    import signal
    import subprocess
    import sys

    pids = tmp_path / "pids"
    pids.mkdir()
    script = (
        "from poc_env.agents.experiments.pool import pid_job, run_jobs\n"
        "if __name__ == '__main__':\n"
        f"    run_jobs(pid_job, [({str(pids)!r}, 600.0)] * 3, workers=3)\n"
    )
    cmd = subprocess.Popen([sys.executable, "-c", script])
    try:
        deadline = time.monotonic() + 120
        while len(list(pids.glob("*.pid"))) < 3 and time.monotonic() < deadline:
            time.sleep(0.1)
        workers = [int(p.read_text()) for p in pids.glob("*.pid")]
        assert len(workers) == 3, "the workers did not start"
    finally:
        cmd.send_signal(signal.SIGKILL)
        cmd.wait()

    def alive(pid: int) -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return False
        try:  # a reaped-later zombie is dead too
            with open(f"/proc/{pid}/stat") as f:
                return f.read().split(")")[-1].split()[0] != "Z"
        except OSError:  # reaped between the two looks (ESRCH, ENOENT)
            return False

    deadline = time.monotonic() + 30
    while any(alive(p) for p in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [p for p in workers if alive(p)]
    for p in left:  # the test's own workers, by pid: no orphan even when the check fails
        os.kill(p, signal.SIGKILL)
    assert not left, "workers outlived their command"
