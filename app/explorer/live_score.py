"""Live S_GAS of the current design: the per-tab background worker
(viser-free: the panel is ``panel_score``).

Cached outcomes (already in the store) show at once; the missing ones are computed object
by object (``run_sweep`` for one design and one object at a time, so each object's row
fills in as soon as it is done) in a thread that a newer design cancels. A short debounce
lets a dragged slider settle before any work starts.

While an object computes, its row shows the hypotheses done, the S_GAS estimate so far with a
95 % Wilson interval, the range the final value is certain to fall in, and the time left
(``ObjectProgress``). The totals (PP, CG, total) appear only once every object is complete:
a mean over the finished objects is not the design's score.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from app.explorer.latency_log import mark
from app.explorer.reference import REFERENCE_DIFF_NOTE, REFERENCE_NOTE, reference_score
from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.scores import DesignScore, ObjectScore
from app.quality.settings import SimSettings
from app.runs.executors import Executor, InlineExecutor
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore
from app.runs.sweep import run_sweep
from app.sim.hypothesis_sets import cached_hypotheses

#: Quiet time before a design's S_GAS is computed (s). A design that follows this much quiet
#: (a typed value, a click, one arrow key) starts at once; one that follows another design
#: sooner (a slider's drag sends its values faster than this) waits until this much quiet has
#: passed, so a drag computes only where it pauses (a newer design cancels the work anyway).
DEBOUNCE_S = 0.3
Z95 = 1.959963984540054
"""The normal quantile of a two-sided 95 % interval."""


#: Seed of the order in which the live score computes an object's hypotheses: a seeded random
#: order, so the hypotheses done at any moment are a simple random sample of the object's.
SAMPLE_SEED = 0
#: Hypotheses of every object computed first, all objects at once, for a first estimate.
FIRST_SAMPLE = 12
#: Hypotheses per task after the first sample (the sweep's chunk: fewer, larger tasks than
#: a progress bar would like, since the panel refreshes from the store on each).
REST_CHUNK = 30
#: The panel is redrawn at most this often while the rest is computed (s): each redraw costs
#: the server an SQL aggregate and the page a layout, on the cores the workers need.
PANEL_REFRESH_S = 0.25


def wilson_interval(successes: float, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a proportion (fractions, 0..1); (0, 1) when n = 0.

    ``successes`` may be fractional (S_GAS counts an FC grasp of the wrong type as ½)."""
    if n <= 0:
        return 0.0, 1.0
    p = min(max(successes / n, 0.0), 1.0)
    z2 = z * z
    denom = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class ObjectProgress:
    """One object's S_GAS while it is computed: what is known so far.

    ``source`` says how the hypotheses done were chosen: 'run order' (the sweep's order,
    ray by ray: not a random sample, so the Wilson interval may not cover early on, while
    the certain range always does) or 'random sample' (a subsample estimate: the
    Wilson interval, narrowed by the finite-population correction, applies)."""

    key: str
    n_gh: int
    """All hypotheses of the object."""
    done: int
    """Hypotheses judged so far."""
    n_fc: int
    n_correct: int
    computed: int = 0
    """Hypotheses computed by this run (the rate of the time estimate)."""
    elapsed_s: float = 0.0
    """Time this run has spent on the object."""
    source: str = "run order"

    @property
    def credit(self) -> float:
        """C + ½ NC of the hypotheses done."""
        return self.n_correct + 0.5 * (self.n_fc - self.n_correct)

    @property
    def estimate_pct(self) -> float:
        """S_GAS of the hypotheses done (%; NaN before the first)."""
        return 100.0 * self.credit / self.done if self.done else math.nan

    @property
    def interval_pct(self) -> tuple[float, float]:
        """95 % Wilson interval of the final S_GAS (%), finite-population corrected, and
        never outside ``certain_pct``."""
        lo, hi = wilson_interval(self.credit, self.done)
        if self.done and self.n_gh > 1:
            p = self.credit / self.done
            f = math.sqrt(max(self.n_gh - self.done, 0) / (self.n_gh - 1))
            lo, hi = p - (p - lo) * f, p + (hi - p) * f
        c_lo, c_hi = self.certain_pct
        return max(100.0 * lo, c_lo), min(100.0 * hi, c_hi)

    @property
    def certain_pct(self) -> tuple[float, float]:
        """Where the final S_GAS must lie (%): every remaining hypothesis failing, or
        every one correct."""
        if self.n_gh <= 0:
            return 0.0, 100.0
        rest = self.n_gh - self.done
        return 100.0 * self.credit / self.n_gh, 100.0 * (self.credit + rest) / self.n_gh

    @property
    def rate_per_s(self) -> float | None:
        """Hypotheses per second of this run (None until measurable)."""
        if self.computed <= 0 or self.elapsed_s <= 0:
            return None
        return self.computed / self.elapsed_s

    @property
    def remaining_s(self) -> float | None:
        """Time left for this object at the current rate (None: not known yet)."""
        r = self.rate_per_s
        return None if r is None else (self.n_gh - self.done) / r


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
    progress: dict[str, ObjectProgress] = field(default_factory=dict)
    """The object being computed (and any with a subsample estimate): progress so far."""
    rate_per_s: float | None = None
    """Hypotheses per second of the latest computation (for the time left of pending objects)."""
    first_sample_s: float | None = None
    """Seconds from the start of the computation to the first sample of every object."""

    def estimates(self) -> dict[str, tuple[float, float, float]] | None:
        """PP, CG and total S_GAS estimates (%) with bounds, once every object has a value or
        a sample: 'pp'/'cg'/'total' -> (estimate, low, high). A complete object counts with
        its value; a sampled one with its estimate and its 95 % interval, and the bounds of
        a mean are the means of the objects' bounds (each object's interval holds with 95 %;
        the mean of the bounds is wider than a 95 % interval of the mean)."""
        score = self.score()
        per: dict[str, tuple[float, float, float]] = {}
        for k in self.n_gh:
            if k in score.objects:
                v = score.objects[k].sgas_pct
                per[k] = (v, v, v)
                continue
            p = self.progress.get(k)
            if p is None or p.done == 0:
                return None
            lo, hi = p.interval_pct if p.source == "random sample" else p.certain_pct
            per[k] = (p.estimate_pct, lo, hi)
        out: dict[str, tuple[float, float, float]] = {}
        groups = {
            "pp": [k for k in per if load_object(k).spec.grasp_type == "PP"],
            "cg": [k for k in per if load_object(k).spec.grasp_type == "CG"],
            "total": list(per),
        }
        for name, keys in groups.items():
            if keys:
                out[name] = tuple(  # type: ignore[assignment]
                    sum(per[k][i] for k in keys) / len(keys) for i in range(3)
                )
        return out

    def remaining_s(self) -> float | None:
        """Time left for every incomplete object at the measured rate (None: unknown)."""
        if self.rate_per_s is None:
            return None
        left = sum(self.n_gh[k] - min(self.counts.get(k, (0, 0, 0))[0], self.n_gh[k])
                   for k in self.n_gh)  # fmt: skip
        return left / self.rate_per_s

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


def _secs(t: float | None) -> str:
    if t is None:
        return "time left: measuring"
    return f"~{t:.0f} s left" if t < 120 else f"~{t / 60:.0f} min left"


def progress_cell(p: ObjectProgress, running: bool) -> tuple[str, str]:
    """(S_GAS cell, progress cell) of an incomplete object."""
    head = f"{'computing' if running else 'pending'} {p.done}/{p.n_gh}"
    if not p.done:
        return "–", head
    lo, hi = p.interval_pct
    c_lo, c_hi = p.certain_pct
    sgas = f"≈{_pct(p.estimate_pct)} (95 % CI {lo:.1f}–{hi:.1f}; certain {c_lo:.0f}–{c_hi:.0f})"
    tail = f", {_secs(p.remaining_s)}" if running else ""
    src = "" if p.source == "run order" else f" ({p.source})"
    return sgas, head + tail + src


def snapshot_markdown(s: ScoreSnapshot) -> str:
    """The S_GAS table: one row per object, then PP, CG and total (complete designs only)."""
    rows = [
        f"**CMC {s.design.cmc_deg:g}°, MCP {s.design.mcp_deg:g}°** — {s.state}",
        "",
        "| object | type | FC % | C % | S_GAS % | progress |",
        "|---|---|---:|---:|---:|---|",
    ]
    score = s.score()
    for k in s.n_gh:
        gt = load_object(k).spec.grasp_type
        if k in score.objects:
            o = score.objects[k]
            rows.append(
                f"| {k} | {gt} | {_pct(o.fc_pct)} | {_pct(o.c_pct)} | **{_pct(o.sgas_pct)}** "
                "| done |"
            )
        else:
            n, fc, c = s.counts.get(k, (0, 0, 0))
            p = s.progress.get(k) or ObjectProgress(k, s.n_gh[k], n, fc, c)
            sgas, prog = progress_cell(p, s.running == k)
            rows.append(f"| {k} | {gt} | | | {sgas} | {prog} |")
    complete = len(score.objects) == len(s.n_gh)
    rows.append("")
    if complete:
        rows.append(
            f"PP **{_pct(score.pp_sgas_pct)}** · CG **{_pct(score.cg_sgas_pct)}** · "
            f"total **{_pct(score.total_sgas_pct)}** (your store)"
        )
    else:
        est = s.estimates()
        if est is not None:
            parts = [
                f"{name.upper() if name != 'total' else 'total'} ≈{v:.1f} ({lo:.1f}–{hi:.1f})"
                for name, (v, lo, hi) in est.items()
            ]
            rows.append(
                " · ".join(parts) + " — estimates from the objects' samples and 95 % intervals "
                f"({len(score.objects)} of {len(s.n_gh)} objects done; {_secs(s.remaining_s())})"
            )
        else:
            rows.append(
                f"PP, CG and total: once every object has a first sample "
                f"({len(score.objects)} done; {_secs(s.remaining_s())})"
            )
    if s.seconds:
        rows.append(f"computed in {s.seconds:.1f} s")
    if s.reference is not None:
        if not complete:  # the shipped row first: it is complete
            rows[1:1] = ["", reference_markdown(s.reference), "", "**Your store:**"]
        else:
            rows += ["", reference_diff_markdown(score, s.reference)]
    return "\n".join(rows)


def reference_diff_markdown(store: DesignScore, ref: DesignScore) -> str:
    """Your complete store row against the shipped one: which objects differ, which is used."""
    diff = [
        f"{k} {_pct(ref.objects[k].sgas_pct)} shipped vs {_pct(o.sgas_pct)} yours"
        for k, o in store.objects.items()
        if k in ref.objects and ref.objects[k] != o
    ]
    if not diff:
        return "Same as the shipped reference sweep."
    return (
        "**Differs from the shipped reference** (used here and on the map: your store): "
        + "; ".join(diff)
        + f"; shipped total {_pct(ref.total_sgas_pct)}. "
        + REFERENCE_DIFF_NOTE
    )


def reference_markdown(ref: DesignScore) -> str:
    """The shipped reference sweep's row of a design (used until the store has it)."""
    rows = [
        f"**Shipped reference** (used until your store has this design) — {REFERENCE_NOTE}.",
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


class FirstEstimate:
    """Whether and when a requested design's first estimate is shown (``ScoreWorker.request``)."""

    def __init__(self, coming: bool) -> None:
        """``coming``: the estimate is computed at once (else ``wait`` returns at once)."""
        self.shown = False
        """The estimate was shown."""
        self._done = threading.Event()
        if not coming:
            self._done.set()

    def set_shown(self) -> None:
        self.shown = True
        self._done.set()

    def give_up(self) -> None:
        """No estimate will come (cancelled, replaced, failed, or one object left)."""
        self._done.set()

    @property
    def done(self) -> bool:
        """Shown, or none is coming."""
        return self._done.is_set()

    def wait(self, timeout: float) -> bool:
        """Wait at most ``timeout`` s for the estimate, or for word that none is coming;
        whether it was shown."""
        self._done.wait(max(0.0, timeout))
        return self.shown


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
        self._pending: tuple[ThumbDesign, SimSettings, float, FirstEstimate] | None = None
        self._first = FirstEstimate(coming=False)
        """The latest request's first estimate."""
        self._last_request = time.monotonic()
        """When the latest design was requested (the worker's start before the first)."""
        self._closed = False
        self.idle = threading.Event()
        self.idle.set()
        self.last_complete_s: float | None = None
        self._thread = threading.Thread(target=self._loop, name="sgas-worker", daemon=True)
        self._thread.start()

    def request(self, design: ThumbDesign, settings: SimSettings) -> FirstEstimate:
        """Show the stored scores of ``design`` now; compute the rest at once if nothing was
        requested for ``debounce_s``, else once ``debounce_s`` has passed without a newer
        request. Returns the handle of its first estimate (coming only if computed at once)."""
        now = time.monotonic()
        snap = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
        missing = any(not snap.complete(k) for k in self.objects)
        snap.state = "waiting" if missing else "complete"
        self.on_snapshot(snap)
        mark("header_shown", snap.state)
        with self._lock:
            quiet = now - self._last_request >= self.debounce_s
            self._last_request = now
            self._cancel.set()  # a stale computation stops at its next task
            self._first.give_up()  # the replaced request's estimate will not come
            first = self._first = FirstEstimate(coming=missing and quiet)
            self._pending = (
                (design, settings, now if quiet else now + self.debounce_s, first)
                if missing
                else None
            )
            if missing:
                self.idle.clear()
            self._wake.set()
        return first

    def close(self) -> None:
        """Cancel any work and stop the thread (a closed tab)."""
        with self._lock:
            self._closed = True
            self._cancel.set()
            self._first.give_up()
            self._pending = None
            self._wake.set()
        self._thread.join(timeout=5.0)

    def join(self, timeout: float) -> bool:
        """Wait (after ``close``) for the thread to end, at most ``timeout`` s; whether it did
        (a task that was running when cancelled finishes first)."""
        if self._thread is not threading.current_thread():
            self._thread.join(timeout)
        return not self._thread.is_alive()

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
            try:
                self._compute(job[0], job[1], cancel, job[3])
            finally:
                job[3].give_up()

    def _compute(
        self,
        design: ThumbDesign,
        settings: SimSettings,
        cancel: threading.Event,
        first: FirstEstimate,
    ) -> None:
        mark("compute", f"{design.cmc_deg} {design.mcp_deg}")
        t0 = time.perf_counter()
        snap = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
        snap.state = "computing"
        # stored before this run: 0 means the object's outcomes will be a prefix of its seeded
        # random order (first sample, then the rest in the same order), a simple random sample
        start_have = {k: snap.counts.get(k, (0, 0, 0))[0] for k in self.objects}
        try:
            todo = [k for k in self.objects if not snap.complete(k)]
            if len(todo) > 1:
                # first sample: the first FIRST_SAMPLE hypotheses of every object's order, all
                # objects at once (one task each, in parallel), so that every object and the
                # total have an estimate with an interval within about a second
                snap.state = "computing a first sample of every object"
                self.on_snapshot(snap)
                t_first = time.perf_counter()
                mark("first_start")
                res = run_sweep(
                    [design], todo, settings=settings, store=self.store, executor=self.executor,
                    chunk=FIRST_SAMPLE, progress=False, cancel=cancel, shuffle_seed=SAMPLE_SEED,
                    first_n=FIRST_SAMPLE,
                )  # fmt: skip
                if res is None or cancel.is_set():
                    return
                fresh = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
                dt = time.perf_counter() - t_first
                for k in todo:
                    n, fc, c = fresh.counts.get(k, (0, 0, 0))
                    snap.counts[k] = (n, fc, c)
                    snap.progress[k] = ObjectProgress(
                        k, snap.n_gh[k], n, fc, c, computed=n - start_have[k], elapsed_s=dt,
                        source="random sample" if start_have[k] == 0 else "run order",
                    )  # fmt: skip
                snap.first_sample_s = time.perf_counter() - t0
                snap.state = "computing"
                mark("first_done")
                self.on_snapshot(snap)
                first.set_shown()
                mark("first_shown")
            # the rest of every object in one run (the pool's workers never wait at an
            # object's last task), in the objects' order: the panel follows the store
            rest = [k for k in self.objects if not snap.complete(k)]
            have0 = {k: snap.counts.get(k, (0, 0, 0))[0] for k in rest}
            sampled = {k: "random sample" if start_have[k] == 0 else "run order" for k in rest}
            done_keys: set[str] = set()
            started: dict[str, float] = {}  # object -> when its first task began (about)
            last_redraw = -PANEL_REFRESH_S  # s into this run
            t_rest = time.perf_counter()

            def progress(done: int, total: int) -> None:
                nonlocal last_redraw
                snap.done, snap.total = done, total
                if cancel.is_set():
                    return
                elapsed = time.perf_counter() - t_rest
                if elapsed - last_redraw < PANEL_REFRESH_S and done < total:
                    return  # the panel (and the browser) need not redraw for every task
                # the judged outcomes so far (one SQL aggregate per redraw)
                summary = self.store.summary(design_key(design), settings.key())
                for k in rest:
                    n, fc, c = summary.get(object_key(k), (have0[k], 0, 0))
                    snap.counts[k] = (n, fc, c)
                    if n >= snap.n_gh[k]:
                        snap.progress.pop(k, None)
                        if k not in done_keys:
                            done_keys.add(k)
                            self.on_object_done(k)
                        continue
                    if n > have0[k]:  # the object's own rate: from the redraw before its first
                        started.setdefault(k, max(last_redraw, 0.0))
                    snap.progress[k] = ObjectProgress(
                        k, snap.n_gh[k], n, fc, c, computed=n - have0[k],
                        elapsed_s=elapsed - started.get(k, elapsed), source=sampled[k],
                    )  # fmt: skip
                last_redraw = elapsed
                snap.running = next((k for k in rest if k not in done_keys), None)
                if elapsed > 0 and done:
                    snap.rate_per_s = done / elapsed
                self.on_snapshot(snap)

            first.give_up()  # one object left: its estimate comes with the run's progress
            if rest:
                snap.running = rest[0]
                self.on_snapshot(snap)
                res = run_sweep(
                    [design], rest, settings=settings, store=self.store,
                    executor=self.executor, chunk=REST_CHUNK, progress=progress, cancel=cancel,
                    shuffle_seed=SAMPLE_SEED,
                )  # fmt: skip
                if res is None or cancel.is_set():
                    return
                fresh = read_snapshot(self.store, design, self.objects, settings, self.ref_dir)
                for k in rest:
                    snap.counts[k] = fresh.counts[k]
                    snap.progress.pop(k, None)
                    if k not in done_keys:
                        self.on_object_done(k)
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
