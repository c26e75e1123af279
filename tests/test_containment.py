"""A pool worker that dies fails its task with a named error; finished tasks stay stored."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from app.errors import WorkerCrashError
from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.executors import LocalExecutor, run_task_marked
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore, StoredOutcome
from app.runs.sweep import execute_tasks
from app.runs.tasks import Task
from app.sim.hypothesis_sets import cached_hypotheses

CRASH_INDEX = 7


def crash_at_index(task: Task, marker_dir: str) -> list[tuple[int, str, StoredOutcome]]:
    """The real worker, but its simulation segfaults on hypothesis CRASH_INDEX (after the
    worker's own marking of it)."""
    import app.runs.tasks as tasks_mod

    real = tasks_mod.simulate_base

    def crashing(*args, **kwargs):  # noqa: ANN202
        if args[3] == CRASH_INDEX:
            os.kill(os.getpid(), signal.SIGSEGV)
        return real(*args, **kwargs)

    tasks_mod.simulate_base = crashing  # type: ignore[assignment]
    try:
        return run_task_marked(task, marker_dir)
    finally:
        tasks_mod.simulate_base = real


class CrashingExecutor(LocalExecutor):
    worker_fn = staticmethod(crash_at_index)


@pytest.mark.pool
def test_worker_crash_is_named_and_finished_tasks_stay(tmp_path: Path) -> None:
    s = SimSettings()
    d = ThumbDesign(0.0, 45.0)
    tasks = [Task("washer", (0,), (d,), s), Task("washer", (3, CRASH_INDEX), (d,), s)]
    ex = CrashingExecutor(workers=1)
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(WorkerCrashError) as e:
            execute_tasks(tasks, store, s.key(), object_key, ex, progress=False)
        ex.close()
        msg = str(e.value)
        gh_id = cached_hypotheses("washer").ids[CRASH_INDEX]
        assert "'washer'" in msg and f"index {CRASH_INDEX}" in msg and gh_id in msg
        assert "SIGSEGV" in msg and "CMC 0° MCP 45°" in msg
        have = store.present_ids(design_key(d), object_key("washer"), s.key())
        assert cached_hypotheses("washer").ids[0] in have and gh_id not in have


def test_one_local_worker_is_a_process_too() -> None:
    """``--workers 1`` on the local executor still runs tasks in a child process (the
    containment above), not in the caller; only ``--executor inline`` runs in-process."""
    from app.runs.executors import InlineExecutor
    from app.runs.sweep import make_executor

    ex = make_executor("local", 1)
    assert isinstance(ex, LocalExecutor) and not isinstance(ex, InlineExecutor)
    assert isinstance(make_executor("inline", 1), InlineExecutor)
