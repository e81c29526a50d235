"""Worker processes for independent jobs (episodes, plans): safe to start, never waited on
forever.

Pools are started by a fork server, never by forking this process: a process that has started
torch's (or OpenMP's) thread pool and then forks can leave the children waiting forever on a
lock the pool held. Workers import what they run afresh, so only policies registered at import
time (every built-in) reach them, and a script that runs jobs on workers needs the usual
``if __name__ == "__main__":`` guard.

Inside :func:`ray_jobs` (``poc-env evaluate/experiment --ray [ADDRESS]``) the same jobs run as
Ray tasks instead, on a local Ray instance or an existing cluster
(:func:`poc_env.agents.rl.cluster.ray_session`); results come back in job order, so they equal
the local ones job for job (every job seeds its own generators).

Workers die with the process that started them: each worker watches its parent command (a
``kill -9`` of ``poc-env evaluate --workers N`` leaves no worker behind, and the fork server
ends by itself when its client is gone). On Linux the kernel's parent-death signal ends a
worker whose fork server has gone; a watchdog thread in every worker, on every platform, ends
it within :data:`WATCH_S` seconds of the command's end.

Every wait for a result has a timeout, :func:`worker_timeout_s` seconds per job (30 minutes
unless ``POC_ENV_WORKER_TIMEOUT_S`` says otherwise): a worker that hangs or dies ends the
command with :class:`WorkerTimeoutError` and its pool is stopped, instead of a silent wait.
"""

from __future__ import annotations

import contextlib
import contextvars
import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any

from poc_env.errors import ConfigError, PocEnvError, as_number
from poc_env.proc import die_with_parent

DEFAULT_TIMEOUT_S = 1800.0
#: seconds between a worker's checks that the command that started it still runs
WATCH_S = 0.5
_ENV_VAR = "POC_ENV_WORKER_TIMEOUT_S"
#: True inside :func:`ray_jobs`: :func:`run_jobs` sends its jobs to Ray.
_ON_RAY: contextvars.ContextVar[bool] = contextvars.ContextVar("poc_env_on_ray", default=False)


@contextlib.contextmanager
def ray_jobs(address: str | None = None, num_cpus: int = 2) -> Iterator[None]:
    """Within the block, :func:`run_jobs` runs every job as a Ray task, on a local instance
    (``address`` None or ``"local"``, ``num_cpus`` CPUs) or the cluster at ``address``."""
    from poc_env.agents.rl.cluster import ray_session

    with ray_session(address, num_cpus, what="--ray"):
        token = _ON_RAY.set(True)
        try:
            yield
        finally:
            _ON_RAY.reset(token)


def _call(fn: Callable[[Any], Any], job: Any) -> Any:
    return fn(job)


def _run_on_ray(fn: Callable[[Any], Any], jobs: Sequence[Any], bar: Any) -> list[Any]:
    import ray
    from ray.exceptions import GetTimeoutError, RayTaskError

    remote = ray.remote(num_cpus=1, max_retries=0)(_call)
    refs = [remote.remote(fn, job) for job in jobs]
    timeout = worker_timeout_s()
    out = []
    # No ray.cancel of the other jobs when one fails: in Ray 2.60 a cancel (forced or not) that
    # races with the reply of a task that is finishing aborts the driver process
    # ("task_manager.cc: Check failed: it != submissible_tasks_.end() Tried to complete task that
    # was not pending", ray-project/ray#54846; the crashed CI worker of stop 32). The other jobs
    # run out: a local instance stops them when its ray_session ends, a cluster finishes them
    # and their results are dropped.
    for k, ref in enumerate(refs):
        try:
            out.append(ray.get(ref, timeout=timeout))
        except GetTimeoutError:
            raise WorkerTimeoutError(
                f"job {k} of {len(jobs)} on Ray gave no result within {timeout:g} s; "
                f"allowed: jobs that finish within {_ENV_VAR} seconds"
            ) from None
        except RayTaskError as exc:  # the job's own error, as a local run would raise it
            cause = getattr(exc, "cause", None)
            if isinstance(cause, BaseException):
                raise cause from None
            raise
        if bar is not None:
            bar.update(1)
    return out


class WorkerTimeoutError(PocEnvError, TimeoutError):
    """A job on a worker process did not finish within the timeout."""


def worker_timeout_s() -> float:
    """Seconds to wait for any one job's result (``POC_ENV_WORKER_TIMEOUT_S``, default 1800)."""
    text = os.environ.get(_ENV_VAR)
    if text is None:
        return DEFAULT_TIMEOUT_S
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(_ENV_VAR, text, "a number of seconds > 0") from None
    return as_number(_ENV_VAR, value, 0.0, None, lo_open=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by another user (a reused pid): not ours
        return False
    return True


def _die_with(owner: int) -> None:
    """Worker initializer: end this worker when the command ``owner`` (a pid) is gone."""
    import threading

    die_with_parent(signal.SIGKILL)  # Linux: the fork server's death ends the worker at once

    def watch() -> None:
        while _alive(owner):
            threading.Event().wait(WATCH_S)
        os._exit(1)  # nobody is left to take a result: end now, without cleanup

    if not _alive(owner):
        os._exit(1)
    threading.Thread(target=watch, name="poc-env-owner-watch", daemon=True).start()


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes started by a fork server (see the module docstring);
    each worker ends when the process that made the pool ends, however it ends."""
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("forkserver"),
        initializer=_die_with,
        initargs=(os.getpid(),),
    )


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the workers now (a hung one included)."""
    procs = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.kill()
    for p in procs:
        p.join(timeout=5)


def run_jobs(
    fn: Callable[[Any], Any],
    jobs: Sequence[Any],
    workers: int = 1,
    *,
    pool: ProcessPoolExecutor | None = None,
    desc: str | None = None,
) -> list[Any]:
    """``[fn(job) for job in jobs]``, on ``workers`` processes when ``workers > 1`` (results in
    job order). ``pool``: an open pool to reuse (it stays open on success; it is stopped on a
    failure); without one a pool is made and shut down here. ``desc``: a progress bar's label.
    """
    bar = None
    if desc is not None:
        from tqdm import tqdm

        bar = tqdm(total=len(jobs), desc=desc, unit="job", leave=False)
    try:
        if _ON_RAY.get():
            return _run_on_ray(fn, jobs, bar)
        if workers == 1 or len(jobs) < 2:
            out = []
            for job in jobs:
                out.append(fn(job))
                if bar is not None:
                    bar.update(1)
            return out
        own = pool is None
        ex = process_pool(workers) if pool is None else pool
        timeout = worker_timeout_s()
        try:
            futures: list[Future] = [ex.submit(fn, job) for job in jobs]
            out = []
            for k, fut in enumerate(futures):
                try:
                    out.append(fut.result(timeout=timeout))
                except FutureTimeout:
                    raise WorkerTimeoutError(
                        f"job {k} of {len(jobs)} on a worker process gave no result within "
                        f"{timeout:g} s; allowed: jobs that finish within {_ENV_VAR} seconds "
                        f"(raise it for long jobs, or run with one worker)"
                    ) from None
                if bar is not None:
                    bar.update(1)
        except BaseException:
            stop_pool(ex)
            raise
        if own:
            ex.shutdown()
        return out
    finally:
        if bar is not None:
            bar.close()


def pid_job(args: tuple[str, float]) -> int:
    """A job that writes its worker's pid into the folder ``args[0]`` and sleeps ``args[1]``
    seconds (to test that workers die with their command)."""
    import time
    from pathlib import Path

    folder, seconds = args
    Path(folder, f"{os.getpid()}.pid").write_text(str(os.getpid()))
    time.sleep(seconds)
    return os.getpid()


def sleep_job(seconds: float) -> float:
    """A job that sleeps (to test and diagnose timeouts on real worker processes)."""
    import time

    time.sleep(seconds)
    return seconds
