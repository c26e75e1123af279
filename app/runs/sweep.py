"""Run designs × objects × hypotheses, resumably, in parallel; aggregate S_GAS.

Work unit (a *task*): one object, a chunk of its hypotheses, and the designs that still lack
results for them. A worker computes each hypothesis' ``BaseGrasp`` once per CMC angle and
then closes the thumb of every listed design on it (docs/cost-model.md). The parent
process is the only writer of the results store: one transaction per finished task, so a
killed sweep loses at most the tasks in flight and never leaves half a task behind.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from app.errors import SettingsError
from app.model.design import ThumbDesign
from app.model.objects import OBJECT_KEYS, load_object
from app.quality.scores import DesignScore, ObjectScore
from app.quality.settings import SimSettings
from app.runs.executors import Executor, InlineExecutor, LocalExecutor
from app.runs.keys import design_key, object_key
from app.runs.progress import Progress
from app.runs.store import ResultStore, StoredOutcome
from app.runs.tasks import DEFAULT_CHUNK, Task, plan_tasks
from app.sim.hypothesis_sets import cached_hypotheses


def make_executor(name: str, workers: int | None = None, address: str | None = None) -> Executor:
    """'local' (process pool; one worker process too, so that a crash in native code fails
    its task with a named error instead of killing the caller), 'inline' (this process: no
    containment; for debugging and profiling) or 'ray'."""
    if name == "local":
        return LocalExecutor(workers)
    if name == "inline":
        return InlineExecutor()
    if name == "ray":
        from app.runs.ray_executor import RayExecutor

        return RayExecutor(address=address, workers=workers)

    raise SettingsError(f"unknown executor {name!r}; choose one of ('local', 'inline', 'ray')")


@dataclass
class SweepResult:
    """Scores of every design, in the order asked."""

    designs: list[ThumbDesign]
    """The designs."""
    scores: list[DesignScore]
    """Their scores."""
    computed: int
    """Outcomes computed in this run (the rest came from the store)."""
    seconds: float
    """Wall time of this run."""


def execute_tasks(
    tasks: Sequence[Task],
    store: ResultStore,
    settings_key: str,
    object_key_of: Callable[[str], str],
    executor: Executor | None = None,
    progress: bool | Callable[[int, int], None] = True,
    cancel: threading.Event | None = None,
    label: str = "grasps",
) -> int:
    """Run ``tasks`` and store each one's outcomes in one transaction; returns how many.

    ``object_key_of(name)`` gives the store key of an object (the hypothesis set's key).
    ``progress`` is True (terminal bar), False, or a callback ``(done, total)``. An executor
    made here is closed here.
    """
    total = sum(len(t.gh) * len(t.designs) for t in tasks)
    bar = Progress(total, label) if progress is True and total else None
    own = executor is None
    executor = executor or LocalExecutor()
    done = 0
    try:
        for task, results in executor.run(tasks, cancel):
            okey = object_key_of(task.object_name)
            by_design: dict[int, dict[str, StoredOutcome]] = {}
            for di, gh_id, outcome in results:
                by_design.setdefault(di, {})[gh_id] = outcome
            with store.transaction():
                for di, outs in by_design.items():
                    store.put_many(design_key(task.designs[di]), okey, settings_key, outs)
            done += len(results)
            if bar:
                bar.update(len(results))
            elif callable(progress):
                progress(done, total)
    finally:
        if bar:
            bar.close()
        if own:
            executor.close()
    return done


def run_sweep(
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str] = OBJECT_KEYS,
    *,
    settings: SimSettings | None = None,
    store: ResultStore,
    executor: Executor | None = None,
    chunk: int = DEFAULT_CHUNK,
    progress: bool | Callable[[int, int], None] = True,
    cancel: threading.Event | None = None,
    gh_stride: int = 1,
    shuffle_seed: int | None = None,
    first_n: int | None = None,
) -> SweepResult | None:
    """Evaluate every design on every object; resumes from and writes to ``store``.

    Returns None when cancelled. ``progress`` is True (terminal bar), False, or a callback
    ``(done, total)``. ``gh_stride`` > 1 previews on every k-th hypothesis of each object
    (scores are then over that subset: the published numbers need ``gh_stride=1``).
    ``shuffle_seed``: compute the hypotheses in a seeded random order (``plan_tasks``), so a
    run stopped early holds a random sample. ``first_n``: only the first n hypotheses of each
    object's order (``plan_tasks``; the scores are then over that subset).
    """
    if gh_stride < 1:
        from app.errors import SettingsError

        raise SettingsError(f"gh_stride must be >= 1, got {gh_stride}")
    t0 = time.perf_counter()
    settings = settings or SimSettings()
    skey = settings.key()
    store.put_settings_meta(skey, settings.as_dict())
    for d in designs:
        store.put_design_meta(design_key(d), d.as_dict())
    for name in object_names:
        store.put_object_meta(object_key(name), {"key": name})
    tasks = plan_tasks(
        store, designs, object_names, settings, chunk, gh_stride, shuffle_seed=shuffle_seed,
        first_n=first_n,
    )  # fmt: skip
    done = execute_tasks(tasks, store, skey, object_key, executor, progress, cancel)
    if cancel is not None and cancel.is_set():
        return None
    if first_n is not None:  # a first sample: the designs are not complete, no scores yet
        return SweepResult(list(designs), [], done, time.perf_counter() - t0)
    scores = [score_design(store, d, object_names, settings, gh_stride) for d in designs]
    return SweepResult(list(designs), scores, done, time.perf_counter() - t0)


def score_design(
    store: ResultStore,
    design: ThumbDesign,
    object_names: Iterable[str],
    settings: SimSettings,
    gh_stride: int = 1,
) -> DesignScore:
    """S_GAS of a design from the stored outcomes (all its hypotheses must be present)."""
    dkey, skey = design_key(design), settings.key()
    summary = store.summary(dkey, skey) if gh_stride == 1 else {}
    scores: dict[str, ObjectScore] = {}
    types: dict[str, str] = {}
    for name in object_names:
        if gh_stride == 1:
            n, n_fc, n_c = summary.get(object_key(name), (0, 0, 0))
            n_gh = len(cached_hypotheses(name))
        else:
            ids = cached_hypotheses(name).ids[::gh_stride]
            got = store.get_many(dkey, object_key(name), skey, ids)
            n, n_gh = len(got), len(ids)
            n_fc = sum(o.is_fc for o in got.values())
            n_c = sum(o.is_correct for o in got.values())
        assert n == n_gh, f"{name}: {n} of {n_gh} outcomes stored"
        scores[name] = ObjectScore(n_gh, n_fc, n_c)
        types[name] = load_object(name).spec.grasp_type
    return DesignScore(scores, types)
