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
