"""Executors run tasks and yield their results as they finish: in this process, or in a
local process pool. (The Ray executor is ``app.runs.ray_executor``.)
"""

from __future__ import annotations

import math
import mmap
import os
import shutil
import signal
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from app.errors import WorkerCrashError
from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.store import StoredOutcome, encode
from app.runs.tasks import Task, run_task

#: Bytes of a worker's marker file: "<object> <index>" padded with blanks.
MARKER_BYTES = 256

#: This worker's marker: (directory, its file mapped into memory), opened on first use.
_MARKER: list[tuple[str, mmap.mmap]] = []


def _marker_map(marker_dir: str) -> mmap.mmap:
    """``<marker_dir>/<pid>`` mapped into memory: writing it is a memory store, not a file
    write per hypothesis (those cost ~0.25 ms each on a busy disk, a quarter of a new design's
    time); the page stays in the page cache when the process dies, so the parent still reads
    it."""
    if _MARKER and _MARKER[0][0] == marker_dir:
        return _MARKER[0][1]
    path = Path(marker_dir) / str(os.getpid())
    with open(path, "w+b") as f:
        f.write(b" " * MARKER_BYTES)
        f.flush()
        mm = mmap.mmap(f.fileno(), MARKER_BYTES)
    _MARKER[:] = [(marker_dir, mm)]
    return mm


def run_task_marked(task: Task, marker_dir: str) -> list[tuple[int, str, StoredOutcome]]:
    """``run_task`` in a pool worker, keeping "<object> <index>" of the hypothesis it is on in
    ``<marker_dir>/<pid>`` (blank between tasks), so that the parent can name it if this
    process dies. The outcomes come back in the store's encoding (``encode``)."""
    mm = _marker_map(marker_dir)
    name = task.object_name.encode()

    def mark(i: int) -> None:
        text = (b"%s %d" % (name, i))[:MARKER_BYTES]
        mm[:] = text.ljust(MARKER_BYTES)

    out = run_task(task, on_hypothesis=mark)
    mm[:] = b" " * MARKER_BYTES
    # encoded here: the parent, the store's only writer, then only inserts the rows
    return [(di, gh, encode(o)) for di, gh, o in out]


def init_worker(object_names: Sequence[str], ignore_sigint: bool = False, nice: int = 0) -> None:
    """Pool worker start-up: optionally leave Ctrl-C to the parent and lower the worker's CPU
    priority by ``nice`` (the explorer: its page stays responsive while the workers use every
    core), then load what every task on ``object_names`` needs (objects, hypotheses, palm
    tables, the compiled kernels and their tables) by simulating one touching hypothesis of
    each, so that the first task of every object does not pay it (the explorer's first
    estimate)."""
    if ignore_sigint:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if nice:
        try:
            os.nice(nice)
        except OSError:  # not allowed here: run at the parent's priority
            pass
    from app.runs.palm_cache import palm_table

    s = SimSettings()
    for name in object_names:
        try:
            table = palm_table(name, s)
            touching = next(
                (i for i in range(min(len(table), 64)) if table.get(i).contacts.p_object.size), 0
            )
            run_task(Task(name, (touching,), (ThumbDesign(),), s))
            prepare_thumb_obstacles(name, s)
        except Exception:  # a warm-up only: the object's own tasks report what is wrong
            continue


def prepare_thumb_obstacles(object_name: str, settings: SimSettings) -> int:
    """Make what the thumb closes against on every palm stage of the object's table now
    (``palm_thumb_obstacles``; each process makes its own, about 0.1 ms a hypothesis and a
    few kB each), so that a new design's tasks do not; how many were made. Objects whose
    table is not complete (palm stages computed as they go) are left alone."""
    from app.model.objects import load_object
    from app.runs.palm_cache import palm_table
    from app.sim.simulate import base_kit, palm_thumb_obstacles

    table = palm_table(object_name, settings)
    if not table.complete:
        return 0
    obj, kit = load_object(object_name), base_kit(ThumbDesign())
    made = 0
    for i in range(len(table)):
        palm = table.get(i)
        if not math.isnan(palm.s_mm):  # a palm stage that touched: the thumb closes on it
            palm_thumb_obstacles(kit, obj, palm, settings.closing)
            made += 1
    return made


def _started() -> int:
    """A no-op task: makes the pool start its workers (and run their start-up)."""
    return os.getpid()


def _describe_exit(code: int | None) -> str:
    if code is None:
        return "it vanished"
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


class Executor:
    """Runs tasks and yields their results as they finish."""

    def run(
        self, tasks: Sequence[Task], cancel: threading.Event | None
    ) -> Iterator[tuple[Task, list[tuple[int, str, StoredOutcome]]]]:
        raise NotImplementedError

    def close(self) -> None:
        """Release workers."""


class InlineExecutor(Executor):
    """Runs tasks in this process, one after another (tests, the explorer's thread)."""

    def run(self, tasks, cancel):  # type: ignore[override]
        for t in tasks:
            if cancel is not None and cancel.is_set():
                return
            yield t, run_task(t)


#: How often a run waiting for its tasks looks at its cancel flag (the explorer's next design
#: waits this long at most, plus the tasks already running).
CANCEL_POLL_S = 0.05


class LocalExecutor(Executor):
    """A pool of local processes (spawned: safe beside threads such as the web server).

    A worker that dies (segfault, out of memory) ends the run with ``WorkerCrashError``
    naming the object and hypothesis it was on; tasks finished before stay in the store.
    """

    worker_fn: Any = staticmethod(run_task_marked)
    """The function the workers run, ``(task, marker_dir) -> results`` (tests swap it)."""

    def __init__(self, workers: int | None = None, warm_objects: Sequence[str] = ()) -> None:
        self.workers = workers or os.cpu_count() or 1
        #: objects every worker loads when it starts (``init_worker``); none: on first use
        self.warm_objects = tuple(warm_objects)
        self._pool: ProcessPoolExecutor | None = None
        self._markers = tempfile.mkdtemp(prefix="handbench-workers-")

    def _new_pool(self, ignore_sigint: bool = False, nice: int = 0) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            self.workers,
            mp_context=get_context("spawn"),
            initializer=init_worker,
            initargs=(self.warm_objects, ignore_sigint, nice),
        )

    def _get_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = self._new_pool()
        return self._pool

    def start(self) -> None:
        """Start the workers now (in the background) rather than at the first task."""
        pool = self._get_pool()
        for _ in range(self.workers):
            pool.submit(_started)

    def run(self, tasks, cancel):  # type: ignore[override]
        pool = self._get_pool()
        pending: dict[Future, Task] = {}
        queue = list(tasks)[::-1]
        procs: dict[int, Any] = {}
        while queue or pending:
            while queue and len(pending) < 2 * self.workers:
                t = queue.pop()
                pending[pool.submit(self.worker_fn, t, self._markers)] = t
            procs.update(getattr(pool, "_processes", None) or {})
            done, _ = wait(pending, timeout=CANCEL_POLL_S, return_when=FIRST_COMPLETED)
            if cancel is not None and cancel.is_set():
                for f in pending:
                    f.cancel()
                return
            for f in done:
                t = pending.pop(f)
                try:
                    res = f.result()
                except BrokenProcessPool:
                    # keep what other workers finished, then name the crash
                    for g in [g for g in pending if g.done() and g.exception() is None]:
                        yield pending.pop(g), g.result()
                    pool.shutdown(wait=False, cancel_futures=True)
                    self._pool = None
                    raise self._crash_error(t, procs) from None
                yield t, res

    def _crash_error(self, task: Task, procs: dict[int, Any]) -> WorkerCrashError:
        """The error naming the object and hypothesis the dead worker was on."""
        from app.sim.hypothesis_sets import hypotheses_of

        # the pool reports the break as soon as a worker vanishes; its exit code may be set a
        # moment later (the process is reaped asynchronously)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and all(p.exitcode in (0, None) for p in procs.values()):
            time.sleep(0.02)
        dead = [(pid, p.exitcode) for pid, p in procs.items() if p.exitcode not in (0, None)]
        crashed = [d for d in dead if d[1] != -signal.SIGTERM] or dead
        where = f"object {task.object_name!r}, one of hypotheses {list(task.gh)[:5]}..."
        how = "it died"
        for pid, code in crashed:
            how = _describe_exit(code)
            marker = Path(self._markers) / str(pid)
            words = marker.read_bytes().decode(errors="replace").split() if marker.is_file() else []
            if len(words) == 2:
                name, idx = words
                try:
                    gh_id = hypotheses_of(name, task.hypothesis_set).ids[int(idx)]
                except Exception:  # the id is a nicety; the index is enough
                    gh_id = "?"
                where = f"object {name!r}, hypothesis {gh_id} (index {idx})"
                break
        designs = ", ".join(f"CMC {d.cmc_deg:g}° MCP {d.mcp_deg:g}°" for d in task.designs[:3])
        return WorkerCrashError(
            f"a worker process died ({how}) while simulating {where} for {designs}; results "
            "finished before are kept in the store. If the object is an imported mesh, "
            "re-import it (objects import) or report the mesh"
        )

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        shutil.rmtree(self._markers, ignore_errors=True)
