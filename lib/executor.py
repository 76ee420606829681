"""Run independent tasks on Dask (``distributed``): an in-process ``LocalCluster`` or any running scheduler.

A task is a plain function and its arguments (picklable: remote workers rebuild what they need from the
folders), with an expected cost in seconds and the MPI ranks it takes.  Tasks start longest first (Dask
priority = the cost: each freed slot takes the longest task waiting, so the slots end nearly together and a
short task, not a long one, runs last; bench/dem_schedule.py); a task of k ranks holds k of its worker's
``RANKS`` resource, so a local cluster of ``jobs`` slots runs two 1-rank tasks side by side or one 2-rank task
alone.  A task returns an ``Outcome``; a failed outcome or an exception (a lost worker too) is retried
``retries`` times, an interrupted one never.  ``KeyboardInterrupt`` (SIGINT, or a SIGTERM handler that raises)
cancels the queue, then calls ``stop`` to end what runs in this process (``stop`` must also keep a task that is
starting from launching anything); workers of a remote cluster finish their current task (Dask cannot stop a
running task).
"""
from __future__ import annotations

import logging
import signal
import sys
import uuid
from collections.abc import Callable
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field

from tqdm import tqdm

from .validate import require

RANKS = "ranks"  # the worker resource a task's MPI ranks hold
DEFAULT_RETRIES = 1


@dataclass(frozen=True)
class Task:
    """``fn(*args)`` returning an Outcome; ``key`` names it in the study's records."""

    key: str
    fn: Callable
    args: tuple = ()
    cost: float = 1.0  # expected seconds: the order (longest first) and the progress bar's ETA
    ranks: int = 1


@dataclass(frozen=True)
class Outcome:
    status: str  # complete | failed | interrupted
    message: str = ""
    info: dict = field(default_factory=dict)
    attempts: int = 1


def _call(fn, args) -> Outcome:
    """A task on its worker: an exception is a failed outcome with its reason (the traceback stays there)."""
    try:
        return fn(*args)
    except Exception as exc:  # recorded, never lost
        return Outcome("failed", f"{type(exc).__name__}: {exc}")


#: the form of --scheduler, and how long a scheduler has to answer
SCHEDULER_FORM, CONNECT_TIMEOUT = "SCHEME://HOST:PORT (e.g. tcp://node12:8786)", 5


def scheduler_address(address: str) -> str:
    """``address`` if it has the form SCHEME://HOST:PORT of a Dask comm (tcp, tls, ws, wss, ucx), a port 1-65535;
    nothing is contacted (ValueError naming --scheduler)."""
    from distributed.comm import registry
    from distributed.comm.addressing import parse_address, parse_host_port

    schemes = sorted(set(registry.backends) - {"inproc"})  # inproc: this process only
    try:
        scheme, location = parse_address(address, strict=True)
        host, port = parse_host_port(location)
    except (ValueError, TypeError):
        scheme, host, port = None, "", 0
    require(scheme in schemes and bool(host) and isinstance(port, int) and 1 <= port <= 65535, "--scheduler",
            f"a Dask scheduler's address {SCHEDULER_FORM}, SCHEME one of {', '.join(schemes)}", address)
    return address


def check_scheduler(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """A running scheduler at ``address`` whose workers offer the RANKS resource (ValueError naming --scheduler;
    an address that does not answer as a Dask scheduler within ``timeout`` seconds is refused)."""
    import asyncio

    from distributed.core import rpc

    scheduler_address(address)

    async def identity() -> dict:
        async with rpc(address, timeout=timeout) as scheduler:
            return await asyncio.wait_for(scheduler.identity(), timeout)  # a service that never answers too

    try:
        info = asyncio.run(identity())
        workers = list(info["workers"].values())
    except Exception as exc:  # refused, unresolved, timed out, not a Dask scheduler: all the same to the user
        why = " ".join(str(exc).split()) or f"no Dask scheduler answered within {timeout:g} s"
        raise ValueError(f"--scheduler must be the address {SCHEDULER_FORM} of a running Dask scheduler, got "
                         f"{address!r} ({why})") from None
    offering = [w for w in workers if RANKS in (w.get("resources") or {})]
    if not offering:
        got = (f"{len(workers)} worker(s) without it" if workers else
               "no worker yet (a cluster's first job may still wait in the queue: start the study once it runs)")
        raise ValueError(f"--scheduler must have workers offering the '{RANKS}' resource (dask worker --resources "
                         f"{RANKS}=N), got {got} at {address}")


def _pool_child() -> None:
    """A forked pool process leaves interrupts to its parent: SIGINT ignored (a terminal's Ctrl-C reaches the
    whole process group), SIGTERM its default (a handler copied from the parent would raise in here)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextmanager
def forked_pool(jobs: int):
    """``jobs`` forked processes (a ProcessPoolExecutor) for work that stays on this machine: a child that dies
    breaks the pool (BrokenProcessPool) rather than hanging it, and leaving the block by an exception (an
    interrupt) ends the children at once, without their tracebacks, and runs nothing still queued."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(jobs, mp_context=mp.get_context("fork"), initializer=_pool_child)
    try:
        yield pool
    except BaseException:
        children = list((pool._processes or {}).values())  # no public handle before Python 3.14's terminate_workers
        pool.shutdown(wait=False, cancel_futures=True)
        for child in children:
            child.terminate()
        raise
    pool.shutdown()


@contextmanager
def _quiet(prefix: str = "distributed"):
    """Dask's loggers silent in the block: an interrupted run's shutdown cancels its in-process worker's running
    tasks, which Dask reports as warnings (CancelledError) that say nothing to the user."""
    loggers = [logging.getLogger(name) for name in [prefix, *list(logging.root.manager.loggerDict)]
               if name == prefix or name.startswith(prefix + ".")]
    levels = [log.level for log in loggers]
    for log in loggers:
        log.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for log, level in zip(loggers, levels, strict=True):
            log.setLevel(level)


class Executor:
    """``jobs`` rank slots on a local in-process cluster, or the cluster at ``scheduler`` (an address)."""

    def __init__(self, jobs: int = 2, scheduler: str | None = None, retries: int = DEFAULT_RETRIES):
        self.jobs, self.scheduler, self.retries = jobs, scheduler, retries

    def _client(self):
        from distributed import Client, LocalCluster

        if self.scheduler:
            return None, Client(self.scheduler)
        # threads: a task waits on its LAMMPS subprocess, so one process suffices and holds no copies
        cluster = LocalCluster(n_workers=1, threads_per_worker=self.jobs, processes=False,
                               resources={RANKS: self.jobs}, dashboard_address=None,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})  # a free local port
        return cluster, Client(cluster)

    def run(self, tasks, on_done: Callable[[Task, Outcome], None] | None = None, stop: Callable[[], None] | None = None,
            progress: bool = False, desc: str = "runs", expected: float | None = None) -> dict[str, Outcome]:
        """Run ``tasks``; ``on_done(task, outcome)`` in this thread as each finishes (for the records); returns
        each task's last outcome by key.  The progress bar counts ``expected`` seconds of wall time (the plan's
        estimate; default: the tasks' costs summed), each finished task its share of them."""
        from distributed import as_completed

        tasks = sorted(tasks, key=lambda t: -t.cost)
        by_key = {t.key: t for t in tasks}
        ranks_max = max((t.ranks for t in tasks), default=1)
        if self.scheduler is None and ranks_max > self.jobs:
            raise ValueError(f"--jobs: at least the ranks of the largest task ({ranks_max}), got {self.jobs}")
        outcomes: dict[str, Outcome] = {}
        if not tasks:
            return outcomes
        cluster, client = self._client()
        work = sum(t.cost for t in tasks)
        share = (expected / work) if expected and work > 0 else 1.0
        bar = tqdm(total=round(work * share), desc=desc, unit="s est.", disable=not progress, file=sys.stderr,
                   dynamic_ncols=True)
        finished = 0.0  # the finished tasks' cost: the bar shows its share of the estimate, in whole seconds
        attempts = dict.fromkeys(by_key, 1)

        run_id = uuid.uuid4().hex[:8]  # Dask keys are shared by every client of a scheduler
        futures: dict = {}  # future -> its task

        def submit(task: Task):
            future = client.submit(_call, task.fn, task.args, key=f"{task.key}-{run_id}-{attempts[task.key]}",
                                   pure=False, priority=task.cost, resources={RANKS: task.ranks})
            futures[future] = task
            return future

        with ExitStack() as shutdown:
            try:
                pending = as_completed([submit(t) for t in tasks])
                for future in pending:
                    task = futures.pop(future)
                    try:
                        outcome = future.result()
                    except Exception as exc:  # a lost worker (KilledWorker, a closed connection): the task failed
                        outcome = Outcome("failed", f"{type(exc).__name__}: {exc}")
                    outcome = Outcome(outcome.status, outcome.message, outcome.info, attempts[task.key])
                    if outcome.status == "failed" and attempts[task.key] <= self.retries:
                        attempts[task.key] += 1
                        pending.add(submit(task))
                        continue
                    outcomes[task.key] = outcome
                    finished += task.cost
                    bar.update(round(finished * share) - bar.n)
                    if on_done is not None:
                        on_done(task, outcome)
            except BaseException:
                shutdown.enter_context(_quiet())  # until the cluster is closed
                client.cancel(list(futures))  # nothing queued starts; then what runs here is stopped
                if stop is not None:
                    stop()
                raise
            finally:
                bar.close()
                client.close()
                if cluster is not None:
                    cluster.close()
        return outcomes
