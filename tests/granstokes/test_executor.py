"""The executor (granstokes.lib.executor): order, retry, failure records, interrupts (a quiet shutdown), rank
slots, a scheduler (its address's form, one that does not answer, a dask-jobqueue cluster's); the forked pool
(interrupted at once and quietly, a dead child an error)."""
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from granstokes.lib.executor import Executor, Outcome, Task, check_scheduler, forked_pool, scheduler_address

_LOCK = threading.Lock()


def _log(path: str, key: str, status: str = "complete", sleep: float = 0.0) -> Outcome:
    """Append ``key`` to the file ``path`` (start order), sleep, return ``status``."""
    with _LOCK, open(path, "a") as f:
        f.write(key + "\n")
    time.sleep(sleep)
    return Outcome(status, key)


def _stamped(path: str, key: str, sleep: float) -> Outcome:
    """Append ``key``, its start and its end (wall-clock seconds) to the file ``path`` around a sleep."""
    start = time.time()
    time.sleep(sleep)
    with _LOCK, open(path, "a") as f:
        f.write(f"{key} {start!r} {time.time()!r}\n")
    return Outcome("complete", key)


def _intervals(path: Path) -> dict[str, tuple[float, float]]:
    return {k: (float(a), float(b)) for k, a, b in (line.split() for line in path.read_text().splitlines())}


def _flaky(path: str, key: str) -> Outcome:
    """Fails on its first call (the marker file absent), completes on the second."""
    marker = Path(path)
    if not marker.exists():
        marker.write_text("tried")
        return Outcome("failed", "first attempt")
    return Outcome("complete")


def _raises(path: str) -> Outcome:
    with open(path, "a") as f:
        f.write("x\n")
    raise RuntimeError("a bug, not a LAMMPS failure")


def test_one_slot_runs_the_longest_first(tmp_path):
    log = str(tmp_path / "order")
    tasks = [Task(f"t{c}", _log, (log, f"t{c}"), cost=c) for c in (1, 5, 3, 4, 2)]
    outcomes = Executor(jobs=1).run(tasks)
    assert Path(log).read_text().split() == ["t5", "t4", "t3", "t2", "t1"]
    assert all(o.status == "complete" and o.attempts == 1 for o in outcomes.values())


#: sleeps of the tasks by cost (6 longest): chosen so that no two slots free at once and the start order is the
#: executor's choice alone: t6 ends at 0.2 s, t5 0.45, t4 0.7, t3 0.95, t2 1.2 (t1 starts then)
SLEEPS = {6: 0.2, 5: 0.45, 4: 0.5, 3: 0.5, 2: 0.5, 1: 0.1}


def test_two_slots_start_the_longest_first_and_take_the_next_longest_as_each_frees(tmp_path):
    """The schedule's order: the two longest start at once, then each freed slot takes the longest waiting."""
    log = str(tmp_path / "order")
    tasks = [Task(f"t{c}", _log, (log, f"t{c}", "complete", SLEEPS[c]), cost=c) for c in (2, 6, 1, 4, 3, 5)]
    outcomes = Executor(jobs=2).run(tasks)
    started = Path(log).read_text().split()
    assert set(started[:2]) == {"t6", "t5"} and started[2:] == ["t4", "t3", "t2", "t1"]
    assert all(o.status == "complete" for o in outcomes.values())


def test_a_failed_task_is_retried_once_then_recorded(tmp_path):
    done = []
    tasks = [Task("flaky", _flaky, (str(tmp_path / "marker"), "flaky")),
             Task("bad", _log, (str(tmp_path / "bad"), "bad", "failed")),
             Task("bug", _raises, (str(tmp_path / "bug"),))]
    outcomes = Executor(jobs=2).run(tasks, on_done=lambda t, o: done.append((t.key, o.status)))
    assert outcomes["flaky"].status == "complete" and outcomes["flaky"].attempts == 2
    assert outcomes["bad"].status == "failed" and outcomes["bad"].attempts == 2
    assert len((tmp_path / "bad").read_text().split()) == 2  # tried twice, no more
    assert outcomes["bug"].status == "failed" and "RuntimeError: a bug" in outcomes["bug"].message
    assert sorted(done) == [("bad", "failed"), ("bug", "failed"), ("flaky", "complete")]


def test_an_interrupted_task_is_not_retried(tmp_path):
    outcomes = Executor(jobs=1).run([Task("i", _log, (str(tmp_path / "i"), "i", "interrupted"))])
    assert outcomes["i"].status == "interrupted" and outcomes["i"].attempts == 1
    assert (tmp_path / "i").read_text().split() == ["i"]


def test_a_two_rank_task_holds_both_slots(tmp_path):
    """Two slots: two 1-rank tasks overlap in time, two 2-rank tasks do not (from each task's own start and end,
    whatever the executor's start-up costs)."""
    one, two = tmp_path / "one", tmp_path / "two"
    Executor(jobs=2).run([Task(k, _stamped, (str(one), k, 0.4)) for k in "ab"])
    Executor(jobs=2).run([Task(k, _stamped, (str(two), k, 0.4), ranks=2) for k in "ab"])
    (a0, a1), (b0, b1) = _intervals(one).values()
    assert min(a1, b1) - max(a0, b0) > 0.2  # side by side: 0.4 s each, overlapping by most of it
    (a0, a1), (b0, b1) = sorted(_intervals(two).values())
    assert b0 >= a1  # in turn: the second starts after the first ends
    log = str(tmp_path / "r")
    with pytest.raises(ValueError, match="--jobs"):
        Executor(jobs=1).run([Task("c", _log, (log, "c"), ranks=2)])


@pytest.mark.slow
def test_the_same_tasks_through_a_scheduler(tmp_path):
    """--scheduler: a LocalCluster of 2 worker processes that the test starts; tasks and retries as locally."""
    from distributed import LocalCluster

    log = str(tmp_path / "s")
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, resources={"ranks": 1},
                      dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        check_scheduler(cluster.scheduler_address)
        outcomes = Executor(scheduler=cluster.scheduler_address).run(
            [Task("a", _log, (log, "a")), Task("f", _flaky, (str(tmp_path / "m"), "f"))])
    assert outcomes["a"].status == "complete" and outcomes["f"].attempts == 2
    assert Path(log).read_text().split() == ["a"]


def test_an_interrupt_cancels_the_queue_and_calls_stop(tmp_path):
    """KeyboardInterrupt while tasks wait (raised here by the record of the first): the queued tasks never start,
    ``stop`` is called once, the interrupt goes on to the caller."""
    log, stops = str(tmp_path / "log"), []

    def interrupt(task, outcome):
        raise KeyboardInterrupt

    tasks = [Task(f"t{k}", _log, (log, f"t{k}", "complete", 0.3), cost=10 - k) for k in range(4)]
    with pytest.raises(KeyboardInterrupt):
        Executor(jobs=1).run(tasks, on_done=interrupt, stop=lambda: stops.append(1))
    time.sleep(0.5)  # a task started after the interrupt would have logged by now
    started = Path(log).read_text().split()
    assert stops == [1] and started[0] == "t0" and len(started) <= 2 and "t3" not in started


@pytest.mark.slow
def test_a_scheduler_without_rank_slots_is_refused():
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        with pytest.raises(ValueError, match="--scheduler must have workers offering the 'ranks' resource"):
            check_scheduler(cluster.scheduler_address)
    with pytest.raises(ValueError, match="--scheduler must be the address .* of a running Dask scheduler"):
        check_scheduler("tcp://127.0.0.1:9")


@pytest.mark.parametrize("address", ["127.0.0.1", "127.0.0.1:8786", "tcp://127.0.0.1", "tcp://:8786",
                                     "tcp://host:0", "tcp://host:70000", "tcp://host:port", "foo://host:8786",
                                     "inproc://host:8786", ""])
def test_a_malformed_scheduler_address_is_refused_naming_the_option(address):
    with pytest.raises(ValueError, match=r"^--scheduler must be a Dask scheduler's address SCHEME://HOST:PORT"):
        scheduler_address(address)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "tcp://node12:8786", "tls://[::1]:1", "ws://h:65535"])
def test_a_well_formed_scheduler_address_passes_without_contact(address):
    assert scheduler_address(address) == address


@pytest.mark.slow
def test_an_address_where_no_scheduler_answers_is_refused_within_the_timeout():
    """A port nobody listens on, and a listener that never speaks Dask: one ValueError naming --scheduler each,
    within the connect timeout (not Dask's default of 30 s, nor forever)."""
    with socket.socket() as closed:
        closed.bind(("127.0.0.1", 0))
        refused = closed.getsockname()[1]
    with socket.socket() as silent:  # the kernel accepts the connection; nothing ever answers
        silent.bind(("127.0.0.1", 0))
        silent.listen()
        for port in (refused, silent.getsockname()[1]):
            start = time.monotonic()
            with pytest.raises(ValueError, match=r"^--scheduler must be the address .* of a running Dask scheduler, "
                                                 rf"got 'tcp://127.0.0.1:{port}' \(.+\)$"):
                check_scheduler(f"tcp://127.0.0.1:{port}", timeout=1.0)
            assert time.monotonic() - start < 5


def test_a_scheduler_without_workers_yet_is_refused_saying_so():
    """An adaptive cluster whose first job has not started: the study is refused, and the line says why."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, protocol="tcp", dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        with pytest.raises(ValueError, match="'ranks' resource .*, got no worker yet "):
            check_scheduler(cluster.scheduler_address)

def _square(path: str, x: int) -> Outcome:
    """Write x squared and this process's id to ``path``; the worker's ranks in the outcome."""
    from distributed import get_worker

    Path(path).write_text(f"{x * x} {os.getpid()}")
    return Outcome("complete", str(x), {"ranks": get_worker().state.total_resources.get("ranks")})


def test_the_tasks_through_a_dask_jobqueue_cluster(tmp_path):
    """--scheduler with dask-jobqueue's own cluster class whose jobs are local processes (the SLURMCluster's
    machinery without a queue): its workers offer ranks=1 (worker_extra_args), the check accepts them, and every
    task runs in a worker process and writes its result; a failed task is retried there."""
    from dask_jobqueue.local import LocalCluster

    with LocalCluster(cores=1, processes=1, memory="1GB", worker_extra_args=["--resources", "ranks=1"],
                      scheduler_options={"dashboard_address": "127.0.0.1:0"}) as cluster:
        assert "--resources ranks=1" in cluster.job_script()
        cluster.scale(jobs=2)
        cluster.wait_for_workers(2, timeout=60)
        check_scheduler(cluster.scheduler_address)
        outcomes = Executor(scheduler=cluster.scheduler_address).run(
            [Task(f"x{x}", _square, (str(tmp_path / f"x{x}"), x)) for x in range(5)]
            + [Task("f", _flaky, (str(tmp_path / "m"), "f"))])
    assert all(outcomes[f"x{x}"].status == "complete" and outcomes[f"x{x}"].info == {"ranks": 1} for x in range(5))
    assert outcomes["f"].status == "complete" and outcomes["f"].attempts == 2
    written = [(tmp_path / f"x{x}").read_text().split() for x in range(5)]
    assert [int(square) for square, _ in written] == [x * x for x in range(5)]
    assert all(int(pid) != os.getpid() for _, pid in written)


#: a run of sleeping tasks on the local cluster that reports its interrupt and prints nothing else
INTERRUPTED = """
import sys, time
from pathlib import Path
from granstokes.lib.executor import Executor, Outcome, Task

def nap(marker, key):
    Path(marker).touch()
    time.sleep(2)
    return Outcome("complete", key)

try:
    Executor(jobs=2).run([Task(f"t{i}", nap, (sys.argv[1], f"t{i}"), cost=10 - i) for i in range(6)])
except KeyboardInterrupt:
    print("interrupted", file=sys.stderr)
"""


@pytest.mark.slow
def test_an_interrupt_shuts_the_local_cluster_down_quietly(tmp_path):
    """SIGINT while tasks run on the in-process cluster: the interrupt reaches the caller and Dask's reports of
    the running tasks it cancels (CancelledError warnings) stay off stderr."""
    marker = tmp_path / "started"
    proc = subprocess.Popen([sys.executable, "-c", INTERRUPTED, str(marker)], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not marker.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert err == "interrupted\n", err


def test_the_progress_bar_counts_the_plans_wall_estimate(tmp_path, monkeypatch):
    """The bar's total is the expected wall time the plan printed (not the tasks' summed costs), and the finished
    tasks fill it exactly, each by its share of the work."""
    from granstokes.lib import executor

    bars = []

    class Bar:
        def __init__(self, total, **kwargs):
            self.total, self.n, self.steps = total, 0, []
            bars.append(self)

        def update(self, n):
            self.n += n
            self.steps.append(n)

        def close(self):
            pass

    monkeypatch.setattr(executor, "tqdm", Bar)
    log = str(tmp_path / "order")
    tasks = [Task(f"t{c}", _log, (log, f"t{c}"), cost=c) for c in (1.0, 3.0, 6.0)]
    Executor(jobs=2).run(tasks, progress=True, expected=7.0)
    (bar,) = bars
    assert bar.total == 7 and bar.n == 7 and all(isinstance(n, int) for n in bar.steps)  # whole seconds, filled
    Executor(jobs=2).run(tasks, progress=True)  # no estimate given: the summed costs
    assert bars[1].total == 10 and bars[1].n == 10


#: a forked pool of 2 busy children and queued work, its group interrupted by the test: SIGTERM raises in the
#: parent (as granstokes.dem.runner.sigterm_interrupts does), SIGINT by Python's default
POOL = """
import signal, sys, time
from pathlib import Path
from granstokes.lib.executor import forked_pool

def busy(i):
    Path(sys.argv[1], str(i)).touch()
    time.sleep(30)

def stop(signum, frame):
    raise KeyboardInterrupt

signal.signal(signal.SIGTERM, stop)
try:
    with forked_pool(2) as pool:
        list(pool.map(busy, range(6)))
except KeyboardInterrupt:
    print("interrupted", file=sys.stderr)
"""


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_pool_ends_its_children_at_once_and_quietly(tmp_path, signum):
    """The signal to the whole process group (a terminal's Ctrl-C, a batch system's SIGTERM) while both children
    are busy: the parent stops within seconds, not after their work or the queue's, and no child prints a
    traceback."""
    proc = subprocess.Popen([sys.executable, "-c", POOL, str(tmp_path)], stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60
    while len(list(tmp_path.iterdir())) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    start = time.monotonic()
    os.killpg(proc.pid, signum)
    _, err = proc.communicate(timeout=60)
    assert time.monotonic() - start < 10 and err == "interrupted\n", err
    assert len(list(tmp_path.iterdir())) == 2  # nothing queued started


def _die(i: int) -> int:
    if i == 1:
        os._exit(9)  # as the kernel's OOM killer would end it
    return i


def test_a_child_that_dies_breaks_the_pool_instead_of_hanging_it():
    from concurrent.futures.process import BrokenProcessPool

    with pytest.raises(BrokenProcessPool), forked_pool(2) as pool:
        list(pool.map(_die, range(4)))
