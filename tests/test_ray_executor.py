"""The Ray executor on a local Ray instance (2 CPUs): same outcomes as the inline executor,
cancellation, and clear errors. Skipped when Ray is not installed (pip install 'handbench[ray]').

One Ray instance serves the whole module (starting one costs several seconds)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

ray = pytest.importorskip("ray", reason="Ray is not installed: pip install 'handbench[ray]'")
pytestmark = pytest.mark.ray

from app.errors import HandbenchError, SettingsError, WorkerCrashError  # noqa: E402
from app.model.design import ThumbDesign  # noqa: E402
from app.quality.outcome import GraspOutcome  # noqa: E402
from app.quality.settings import SimSettings  # noqa: E402
from app.runs.executors import InlineExecutor  # noqa: E402
from app.runs.ray_executor import RayExecutor  # noqa: E402
from app.runs.tasks import Task  # noqa: E402

DESIGNS = (ThumbDesign(0.0, 45.0), ThumbDesign(30.0, 60.0))
OBJECT = "washer"  # the cheapest object to close on (about 0.1 s per grasp)


def _tasks(n_tasks: int = 3, per_task: int = 4) -> list[Task]:
    """A reduced hypothesis set: a few GHs spread over the washer's 1026, in small tasks."""
    step = 1026 // (n_tasks * per_task)
    gh = list(range(0, 1026, step))[: n_tasks * per_task]
    return [Task(OBJECT, tuple(gh[k::n_tasks]), DESIGNS, SimSettings()) for k in range(n_tasks)]


def _by_key(results) -> dict[tuple[str, str], GraspOutcome]:
    """(design, GH id) -> outcome, whatever the order the tasks finished in."""
    out: dict[tuple[str, str], GraspOutcome] = {}
    for task, res in results:
        for di, gh_id, outcome in res:
            out[(repr(task.designs[di]), gh_id)] = outcome
    return out


@pytest.fixture(scope="module")
def executor() -> Iterator[RayExecutor]:
    ex = RayExecutor(workers=2)
    yield ex
    ex.close()
    assert not ray.is_initialized(), "the executor that started Ray must shut it down"


def test_same_outcomes_as_inline(executor: RayExecutor) -> None:
    tasks = _tasks()
    got = _by_key(executor.run(tasks, None))
    want = _by_key(InlineExecutor().run(tasks, None))
    assert got.keys() == want.keys()
    assert len(got) == 2 * 12
    assert ray.cluster_resources().get("CPU") == 2
    for k, w in want.items():
        g = got[k]
        assert (g.is_fc, g.is_correct) == (w.is_fc, w.is_correct), k
        assert (g.q_final_rad == w.q_final_rad).all(), k
    assert any(o.is_fc for o in want.values())  # the comparison is not vacuous


def test_dead_worker_is_a_named_error(executor: RayExecutor) -> None:
    """A Ray worker that dies (here: a segfault in every try) fails with WorkerCrashError
    naming the object and the task's hypotheses, not a raw Ray exception."""

    def segfault(task: Task) -> list:  # defined here, so Ray ships it by value
        import os
        import signal

        os.kill(os.getpid(), signal.SIGSEGV)
        return []

    executor._connect()
    saved = executor._remote
    executor._remote = ray.remote(max_retries=0)(segfault)
    try:
        with pytest.raises(WorkerCrashError, match=r"object 'washer', one of hypotheses"):
            list(executor.run(_tasks(1, 2), None))
    finally:
        executor._remote = saved
    # the executor still works afterwards
    assert len(list(executor.run(_tasks(1, 1), None))) == 1


def test_cancel_stops_early(executor: RayExecutor) -> None:
    tasks = _tasks(n_tasks=12, per_task=2)
    cancel = threading.Event()
    seen = 0
    t0 = time.perf_counter()
    for _task, _res in executor.run(tasks, cancel):
        seen += 1
        cancel.set()  # after the first finished task
    assert 1 <= seen < len(tasks)
    assert time.perf_counter() - t0 < 30
    # Ray is still usable afterwards (the cancelled tasks did not poison it)
    assert len(list(executor.run(_tasks(n_tasks=1, per_task=1), None))) == 1


def test_preset_cancel_and_no_tasks_do_nothing(executor: RayExecutor) -> None:
    cancel = threading.Event()
    cancel.set()
    assert list(executor.run(_tasks(), cancel)) == []
    assert list(executor.run([], None)) == []


def test_does_not_shut_down_a_ray_it_did_not_start(executor: RayExecutor) -> None:
    list(executor.run(_tasks(n_tasks=1, per_task=1), None))  # Ray is up
    other = RayExecutor(workers=2)
    assert len(list(other.run(_tasks(n_tasks=1, per_task=1), None))) == 1
    other.close()
    assert ray.is_initialized()


def test_unreachable_address_is_a_clear_error() -> None:
    t0 = time.perf_counter()
    with pytest.raises(HandbenchError, match=r"127\.0\.0\.1:1"):
        RayExecutor(address="127.0.0.1:1")
    assert time.perf_counter() - t0 < 10  # not Ray's minutes of retries


@pytest.mark.parametrize("address", ["no-port", "host:port", ":6379"])
def test_malformed_address_lists_the_forms(address: str) -> None:
    with pytest.raises(SettingsError, match="HOST:PORT"):
        RayExecutor(address=address)


def test_bad_worker_count() -> None:
    with pytest.raises(SettingsError, match="at least 1"):
        RayExecutor(workers=0)


def test_worker_error_reaches_the_driver(executor: RayExecutor) -> None:
    bad = Task("no_such_object", (0,), DESIGNS, SimSettings())
    with pytest.raises(HandbenchError, match="no_such_object"):
        list(executor.run([bad], None))
