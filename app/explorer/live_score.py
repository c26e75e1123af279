"""Live S_GAS of the current design: the per-tab background worker
(viser-free: the panel is ``panel_score``).

Cached outcomes (already in the store) show at once; the missing ones are computed object
by object (``run_sweep`` for one design and one object at a time, so each object's row
fills in as soon as it is done) in a thread that a newer design cancels. A short debounce
lets a dragged slider settle before any work starts.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from app.explorer.reference import REFERENCE_NOTE, reference_score
from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.scores import DesignScore, ObjectScore
from app.quality.settings import SimSettings
from app.runs.executors import Executor, InlineExecutor
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore
from app.runs.sweep import run_sweep
from app.sim.hypothesis_sets import cached_hypotheses

DEBOUNCE_S = 0.3


@dataclass
class ScoreSnapshot:
    """What the panel shows: per-object counts so far and what is being computed."""

    design: ThumbDesign
    counts: dict[str, tuple[int, int, int]]
    """object -> (stored n, n_fc, n_correct)."""
    n_gh: dict[str, int]
    """object -> its number of hypotheses."""
    running: str | None = None
    """Object being computed now, or None."""
    done: int = 0
    total: int = 0
    state: str = "cached"
    """'cached' | 'waiting' | 'computing' | 'complete' | 'cancelled' | 'error: ...'."""
    seconds: float = 0.0
    extra: dict[str, str] = field(default_factory=dict)
    reference: DesignScore | None = None
    """The shipped reference sweep's score of this design (None: not a shipped design)."""

    def complete(self, key: str) -> bool:
        """All hypotheses of ``key`` are stored."""
        return self.counts.get(key, (0, 0, 0))[0] >= self.n_gh[key]

    def score(self) -> DesignScore:
        """Scores of the complete objects only."""
        objs = {k: ObjectScore(*self.counts[k]) for k in self.n_gh if self.complete(k)}
        types = {k: load_object(k).spec.grasp_type for k in objs}
        return DesignScore(objs, types)


def read_snapshot(
    store: ResultStore,
    design: ThumbDesign,
    objects: Sequence[str],
    settings: SimSettings,
    ref_dir: Path | None = None,
) -> ScoreSnapshot:
    """The stored counts of a design (one SQL aggregate), and its shipped reference score."""
    summ = store.summary(design_key(design), settings.key())
    counts = {k: summ.get(object_key(k), (0, 0, 0)) for k in objects}
    n_gh = {k: len(cached_hypotheses(k)) for k in objects}
    ref = reference_score(
        design.cmc_deg, design.mcp_deg, objects, settings, design.cmc_tilt, ref_dir
    )
    return ScoreSnapshot(design, counts, n_gh, reference=ref)


def _pct(x: float | None) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.1f}"


def snapshot_markdown(s: ScoreSnapshot) -> str:
    """The S_GAS table: one row per object, then PP, CG and total."""
    rows = [
        f"**CMC {s.design.cmc_deg:g}°, MCP {s.design.mcp_deg:g}°** — {s.state}",
        "",
        "| object | type | FC % | C % | S_GAS % |",
        "|---|---|---:|---:|---:|",
    ]
    score = s.score()
    for k in s.n_gh:
        gt = load_object(k).spec.grasp_type
        if k in score.objects:
            o = score.objects[k]
            rows.append(
                f"| {k} | {gt} | {_pct(o.fc_pct)} | {_pct(o.c_pct)} | **{_pct(o.sgas_pct)}** |"
            )
        else:
            n = s.counts.get(k, (0, 0, 0))[0]
            mark = "computing" if s.running == k else "pending"
            rows.append(f"| {k} | {gt} | {mark} {n}/{s.n_gh[k]} | | |")
    complete = len(score.objects) == len(s.n_gh)
    note = "" if complete else " (partial)"
    rows += [
        "",
        f"PP **{_pct(score.pp_sgas_pct)}** · CG **{_pct(score.cg_sgas_pct)}** · "
        f"total **{_pct(score.total_sgas_pct)}**{note}",
    ]
    if s.seconds:
        rows.append(f"computed in {s.seconds:.1f} s")
    if s.reference is not None and not complete:  # the shipped row first: it is complete
        rows[1:1] = ["", reference_markdown(s.reference), "", "**Your store:**"]
    return "\n".join(rows)


def reference_markdown(ref: DesignScore) -> str:
    """The shipped reference sweep's row of a design (shown until the store has it)."""
    rows = [
        f"**Shipped reference** — {REFERENCE_NOTE}.",
        "",
        "| object | FC % | C % | S_GAS % |",
        "|---|---:|---:|---:|",
    ]
    for k, o in ref.objects.items():
        rows.append(f"| {k} | {_pct(o.fc_pct)} | {_pct(o.c_pct)} | {_pct(o.sgas_pct)} |")
    rows += [
        "",
        f"reference: PP {_pct(ref.pp_sgas_pct)} · CG {_pct(ref.cg_sgas_pct)} · "
        f"total **{_pct(ref.total_sgas_pct)}**",
    ]
    return "\n".join(rows)


class ScoreWorker:
    """One background thread per tab; ``request`` replaces (and cancels) any older design."""

    def __init__(
        self,
        store: ResultStore,
        objects: Sequence[str],
        on_snapshot: Callable[[ScoreSnapshot], None],
        on_object_done: Callable[[str], None],
        executor: Executor | None = None,
        debounce_s: float = DEBOUNCE_S,
        ref_dir: Path | None = None,
    ) -> None:
        self.store = store
        self.ref_dir = ref_dir
        self.objects = tuple(objects)
        self.on_snapshot = on_snapshot
        self.on_object_done = on_object_done
        self.executor = executor or InlineExecutor()
        self.debounce_s = debounce_s
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._cancel = threading.Event()
        self._pending: tuple[ThumbDesign, SimSettings, float] | None = None
        self._closed = False
        self.idle = threading.Event()
        self.idle.set()
        self.last_complete_s: float | None = None
        self._thread = threading.Thread(target=self._loop, name="sgas-worker", daemon=True)
        self._thread.start()

    def request(self, design: ThumbDesign, settings: SimSettings) -> None:
        """Show the stored scores of ``design`` now; compute the rest after the debounce."""
        snap = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
        missing = any(not snap.complete(k) for k in self.objects)
        snap.state = "waiting" if missing else "complete"
        self.on_snapshot(snap)
        with self._lock:
            self._cancel.set()  # a stale computation stops at its next task
            self._pending = (
                (design, settings, time.monotonic() + self.debounce_s) if missing else None
            )
            if missing:
                self.idle.clear()
            self._wake.set()

    def close(self) -> None:
        """Cancel any work and stop the thread (a closed tab)."""
        with self._lock:
            self._closed = True
            self._cancel.set()
            self._pending = None
            self._wake.set()
        self._thread.join(timeout=5.0)

    def _loop(self) -> None:
        while True:
            self._wake.wait()
            with self._lock:
                if self._closed:
                    return
                job = self._pending
                if job is None:
                    self._wake.clear()
                    self.idle.set()
                    continue
                delay = job[2] - time.monotonic()
                if delay <= 0:
                    self._pending = None
                    self._cancel = threading.Event()
                    cancel = self._cancel
            if delay > 0:
                time.sleep(min(delay, 0.05))
                continue
            self._compute(job[0], job[1], cancel)

    def _compute(self, design: ThumbDesign, settings: SimSettings, cancel: threading.Event) -> None:
        t0 = time.perf_counter()
        snap = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
        snap.state = "computing"
        try:
            for key in self.objects:
                if cancel.is_set():
                    return
                if snap.complete(key):
                    continue
                snap.running = key
                have = snap.counts.get(key, (0, 0, 0))[0]
                snap.done, snap.total = 0, snap.n_gh[key] - have
                self.on_snapshot(snap)

                def progress(
                    done: int,
                    total: int,
                    snap: ScoreSnapshot = snap,
                    key: str = key,
                    have: int = have,
                ) -> None:
                    snap.done, snap.total = done, total
                    if not cancel.is_set():
                        counts = snap.counts[key]
                        snap.counts[key] = (have + done, counts[1], counts[2])
                        self.on_snapshot(snap)

                res = run_sweep(
                    [design], [key], settings=settings, store=self.store,
                    executor=self.executor, chunk=30, progress=progress, cancel=cancel,
                )  # fmt: skip
                if res is None or cancel.is_set():
                    return
                fresh = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
                snap.counts[key] = fresh.counts[key]
                self.on_object_done(key)
            snap.running = None
            snap.state = "complete"
            snap.seconds = time.perf_counter() - t0
            self.last_complete_s = snap.seconds
            self.on_snapshot(snap)
        except Exception as e:  # shown in the panel; the tab stays usable
            snap.state = f"error: {e}"
            self.on_snapshot(snap)
        finally:
            with self._lock:
                if self._pending is None:
                    self.idle.set()
