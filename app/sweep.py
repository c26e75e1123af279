"""Run designs × objects × hypotheses, resumably, in parallel; aggregate S_GAS.

Work unit (a *task*): one object, a chunk of its hypotheses, and the designs that still lack
results for them. A worker computes each hypothesis' ``BaseGrasp`` once per CMC angle and
then closes the thumb of every listed design on it (docs/cost-model.md). The parent
process is the only writer of the results store: one transaction per finished task, so a
killed sweep loses at most the tasks in flight and never leaves half a task behind.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, replace
from functools import lru_cache
from multiprocessing import get_context

from app.bruteforce import ALL_FINGERS, BF_SETS, BruteForceHypotheses, bf_store_suffix
from app.bruteforce import brute_force_hypotheses as _bf_hypotheses
from app.design import ThumbDesign
from app.hand.data import load_hand_dims
from app.hand.model import Hand
from app.hypotheses import Hypotheses, hypotheses_for
from app.judge import judge
from app.objects import OBJECT_KEYS, load_object
from app.scores import DesignScore, ObjectScore
from app.settings import SimSettings
from app.simulate import BaseGrasp, HandKit, simulate_base, simulate_thumb
from app.store import GraspOutcome, ResultStore, stable_hash

#: Hypotheses per task: small enough for a live progress bar, large enough to amortise.
DEFAULT_CHUNK = 60


def design_key(design: ThumbDesign) -> str:
    """Store key of a design: the hand model file's hash + the thumb design."""
    return stable_hash({"hand": load_hand_dims().content_hash, **design.as_dict()})


@lru_cache(maxsize=32)
def object_key(key: str) -> str:
    """Store key of an object: hash of its mesh and grasp set-up."""
    obj = load_object(key)
    s = obj.spec
    return stable_hash(
        {
            "key": s.key,
            "grasp_type": s.grasp_type,
            "target": s.target_object,
            "normal": s.normal_object,
            "grip": s.grip_axis_object,
            "hint": s.palm_y_hint_object,
            "setup": vars(s.setup),
            "mesh": stable_hash({"v": obj.mesh.vertices.round(6), "f": obj.mesh.faces}),
        }
    )


@lru_cache(maxsize=32)
def cached_hypotheses(key: str) -> Hypotheses:
    """The anthropomorphic hypotheses of an object (per process)."""
    return hypotheses_for(load_object(key))


#: Hypothesis sets: the benchmark's (METHOD §3a) and the brute-force ones (§3b).
HYPOTHESIS_SETS: tuple[str, ...] = ("anthropomorphic", *BF_SETS)


def _check_set(hypothesis_set: str) -> None:
    if hypothesis_set not in HYPOTHESIS_SETS:
        from app.errors import SettingsError

        raise SettingsError(
            f"unknown hypothesis set {hypothesis_set!r}; choose one of {HYPOTHESIS_SETS}"
        )


@lru_cache(maxsize=32)
def hypotheses_of(key: str, hypothesis_set: str = "anthropomorphic") -> Hypotheses:
    """The hypotheses of an object in a set of ``HYPOTHESIS_SETS`` (per process)."""
    _check_set(hypothesis_set)
    if hypothesis_set == "anthropomorphic":
        return cached_hypotheses(key)
    return _bf_hypotheses(load_object(key), BF_SETS[hypothesis_set])


def set_object_key(key: str, hypothesis_set: str = "anthropomorphic") -> str:
    """Store object key of an object's hypothesis set: ``object_key`` for the benchmark,
    with a suffix (``':bf'``) for a brute-force set, so the two never mix."""
    _check_set(hypothesis_set)
    if hypothesis_set == "anthropomorphic":
        return object_key(key)
    return object_key(key) + bf_store_suffix(BF_SETS[hypothesis_set])


@lru_cache(maxsize=64)
def _kit(cmc_deg: float, mcp_deg: float, tilt: str) -> HandKit:
    return HandKit(Hand(ThumbDesign(cmc_deg, mcp_deg, tilt), load_hand_dims()))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Task:
    """Hypotheses ``gh`` of ``object_name`` for the designs in ``designs``."""

    object_name: str
    """Object key, e.g. 'chips_can'."""
    gh: tuple[int, ...]
    """Hypothesis indices."""
    designs: tuple[ThumbDesign, ...]
    """Designs to evaluate on every listed hypothesis."""
    settings: SimSettings
    """Simulation settings."""
    hypothesis_set: str = "anthropomorphic"
    """One of ``HYPOTHESIS_SETS``."""


def run_task(task: Task) -> list[tuple[int, str, GraspOutcome]]:
    """Simulate one task; returns (design index in task, GH id, outcome) triples.

    Brute-force sets close all fingers, and their outcomes keep the hand placement in
    ``extra["T_object_palm"]`` (4×4 nested list, mm) for the GQMs and pictures.
    """
    obj = load_object(task.object_name)
    hyps = hypotheses_of(task.object_name, task.hypothesis_set)
    s = task.settings
    kits = [_kit(*d.as_dict().values()) for d in task.designs]  # type: ignore[arg-type]
    out: list[tuple[int, str, GraspOutcome]] = []
    bf = isinstance(hyps, BruteForceHypotheses)
    for i in task.gh:
        # the open thumb (part of the approach) depends on the CMC angle only: one base
        # stage per (CMC angle, tilt), shared by every MCP angle (docs/cost-model.md);
        # unless the hand file's reading bends the open thumb by m (then per design)
        bases: dict[tuple[float, str, float], BaseGrasp] = {}
        per_m = load_hand_dims().thumb.reading.open_thumb_depends_on_mcp
        for di, (d, kit) in enumerate(zip(task.designs, kits, strict=True)):
            open_thumb = (d.cmc_deg, d.cmc_tilt, d.mcp_deg if per_m else 0.0)
            base = bases.get(open_thumb)
            if base is None:
                if isinstance(hyps, BruteForceHypotheses):
                    base = simulate_base(kit, obj, hyps.approach_line(i), i, s, fingers=ALL_FINGERS)
                else:
                    base = simulate_base(kit, obj, hyps, i, s)
                bases[open_thumb] = base
            g = simulate_thumb(kit, obj, base, s)
            o = judge(g, obj, s, base.queries + g.queries)
            if bf:
                o = replace(o, extra={**o.extra, "T_object_palm": g.T_object_palm.tolist()})
            out.append((di, hyps.ids[i], o))
    return out


# ----------------------------------------------------------------------------- executors
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


def make_executor(name: str, workers: int | None = None, address: str | None = None) -> Executor:
    """'local' (process pool), 'inline' (this process) or 'ray'."""
    if name == "local":
        return InlineExecutor() if workers == 1 else LocalExecutor(workers)
    if name == "inline":
        return InlineExecutor()
    if name == "ray":
        from app.ray_executor import RayExecutor

        return RayExecutor(address=address, workers=workers)
    from app.errors import SettingsError

    raise SettingsError(f"unknown executor {name!r}; choose one of ('local', 'inline', 'ray')")


# ----------------------------------------------------------------------------- progress
class Progress:
    """A terminal progress bar on stderr (a line every few seconds when not a TTY)."""

    def __init__(self, total: int, label: str = "grasps", stream=None) -> None:
        self.total, self.done, self.label = total, 0, label
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self._last = 0.0
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def update(self, n: int) -> None:
        self.done += n
        now = time.perf_counter()
        if self.tty or now - self._last > 5 or self.done >= self.total:
            self._last = now
            el = now - self.t0
            rate = self.done / el if el > 0 else 0.0
            frac = self.done / self.total if self.total else 1.0
            bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
            eta = (self.total - self.done) / rate if rate > 0 else float("inf")
            msg = (
                f"[{bar}] {self.done}/{self.total} {self.label} "
                f"{rate:,.0f}/s elapsed {el:.0f}s eta {eta:.0f}s"
            )
            print(
                ("\r" if self.tty else "") + msg,
                end="" if self.tty else "\n",
                file=self.stream,
                flush=True,
            )

    def close(self) -> None:
        if self.tty:
            print(file=self.stream)


# ----------------------------------------------------------------------------- sweep
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


def plan_tasks(
    store: ResultStore,
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    settings: SimSettings,
    chunk: int = DEFAULT_CHUNK,
    gh_stride: int = 1,
    hypothesis_set: str = "anthropomorphic",
) -> list[Task]:
    """Tasks for every (design, object, GH) not yet in the store (every ``gh_stride``-th GH).

    ``hypothesis_set`` (one of ``HYPOTHESIS_SETS``) picks the hypotheses and the store's
    object key (``hypotheses_of``/``set_object_key``); the default is the benchmark's.
    """
    skey = settings.key()
    dkeys = [design_key(d) for d in designs]
    tasks: list[Task] = []
    for name in object_names:
        hyps = hypotheses_of(name, hypothesis_set)
        okey = set_object_key(name, hypothesis_set)
        present = [store.present_ids(dk, okey, skey) for dk in dkeys]
        subset = list(range(0, len(hyps), gh_stride))
        for start in range(0, len(subset), chunk):
            idx = subset[start : start + chunk]
            # group designs by which of these GHs they lack (usually: all or none)
            groups: dict[tuple[int, ...], list[ThumbDesign]] = {}
            for d, have in zip(designs, present, strict=True):
                missing = tuple(i for i in idx if hyps.ids[i] not in have)
                if missing:
                    groups.setdefault(missing, []).append(d)
            for missing, ds in groups.items():
                tasks.append(Task(name, missing, tuple(ds), settings, hypothesis_set))
    return tasks


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
            by_design: dict[int, dict[str, GraspOutcome]] = {}
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
) -> SweepResult | None:
    """Evaluate every design on every object; resumes from and writes to ``store``.

    Returns None when cancelled. ``progress`` is True (terminal bar), False, or a callback
    ``(done, total)``. ``gh_stride`` > 1 previews on every k-th hypothesis of each object
    (scores are then over that subset: the published numbers need ``gh_stride=1``).
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
    tasks = plan_tasks(store, designs, object_names, settings, chunk, gh_stride)
    done = execute_tasks(tasks, store, skey, object_key, executor, progress, cancel)
    if cancel is not None and cancel.is_set():
        return None
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
