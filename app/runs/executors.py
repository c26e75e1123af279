"""Executors run tasks and yield their results as they finish: in this process, or in a
local process pool. (The Ray executor is ``app.runs.ray_executor``.)
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from multiprocessing import get_context

from app.quality.outcome import GraspOutcome
from app.runs.tasks import Task, run_task


class Executor:
    """Runs tasks and yields their results as they finish."""

    def run(
        self, tasks: Sequence[Task], cancel: threading.Event | None
    ) -> Iterator[tuple[Task, list[tuple[int, str, GraspOutcome]]]]:
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


class LocalExecutor(Executor):
    """A pool of local processes (spawned: safe beside threads such as the web server)."""

    def __init__(self, workers: int | None = None) -> None:
        self.workers = workers or os.cpu_count() or 1
        self._pool: ProcessPoolExecutor | None = None

    def _get_pool(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(self.workers, mp_context=get_context("spawn"))
        return self._pool

    def run(self, tasks, cancel):  # type: ignore[override]
        pool = self._get_pool()
        pending: dict[Future, Task] = {}
        queue = list(tasks)[::-1]
        while queue or pending:
            while queue and len(pending) < 2 * self.workers:
                t = queue.pop()
                pending[pool.submit(run_task, t)] = t
            done, _ = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
            if cancel is not None and cancel.is_set():
                for f in pending:
                    f.cancel()
                return
            for f in done:
                yield pending.pop(f), f.result()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
