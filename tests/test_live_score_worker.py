"""The live S_GAS worker's timing rules, without a browser: a design that follows quiet is
computed at once, one that follows another within the debounce waits for it, and the
first-estimate handle says whether and when the first sample was shown."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from app.explorer.latency_log import ENV, mark
from app.explorer.live_score import FIRST_SAMPLE, FirstEstimate, ScoreSnapshot, ScoreWorker
from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.store import ResultStore

DEBOUNCE_S = 2.0
"""Long against the first sample (~0.1 s), so that 'at once' and 'after the debounce' are
told apart on a busy machine."""
OBJECTS = ("small_marker", "washer")


def test_quiet_design_starts_at_once_and_a_burst_waits_for_the_debounce(tmp_path: Path) -> None:
    seen: list[tuple[float, ThumbDesign, str, dict[str, tuple[int, str]]]] = []

    def on_snapshot(s: ScoreSnapshot) -> None:
        progress = {k: (p.done, p.source) for k, p in s.progress.items()}
        seen.append((time.monotonic(), s.design, s.state, progress))

    def computing(d: ThumbDesign) -> list[float]:
        return [t for t, dd, state, _ in seen if dd == d and state.startswith("computing")]

    store = ResultStore(tmp_path / "store.sqlite")
    worker = ScoreWorker(store, OBJECTS, on_snapshot, lambda _key: None, debounce_s=DEBOUNCE_S)
    try:
        time.sleep(DEBOUNCE_S + 0.05)  # quiet since the worker started
        a, b = ThumbDesign(12.0, 52.0), ThumbDesign(12.0, 57.0)
        t_a = time.monotonic()
        first_a = worker.request(a, SimSettings())
        assert first_a.wait(1.5 * DEBOUNCE_S), "no first estimate for a design after quiet"
        assert computing(a) and computing(a)[0] - t_a < 0.75 * DEBOUNCE_S
        # when the handle says 'shown', the panel has had every object's first sample
        shown = [p for _t, d, _s, p in seen if d == a and len(p) == len(OBJECTS)]
        assert shown and all(v == (FIRST_SAMPLE, "random sample") for v in shown[0].values())

        t_b = time.monotonic()
        first_b = worker.request(b, SimSettings())  # within a's debounce: b waits for its own
        assert first_b.wait(5.0) is False  # none is coming at once: no wait, not shown
        assert time.monotonic() - t_b < 0.5
        time.sleep(0.5 * DEBOUNCE_S)
        assert not computing(b), "a design within the debounce was computed before it passed"
        t_end = time.monotonic() + 10 * DEBOUNCE_S
        while not computing(b) and time.monotonic() < t_end:
            time.sleep(0.05)
        assert computing(b) and computing(b)[0] - t_b >= DEBOUNCE_S - 0.05
    finally:
        worker.close()
        store.close()


def test_replaced_request_gives_up_its_first_estimate(tmp_path: Path) -> None:
    store = ResultStore(tmp_path / "store.sqlite")
    worker = ScoreWorker(store, OBJECTS, lambda _s: None, lambda _key: None, debounce_s=60.0)
    try:
        first_a = worker.request(ThumbDesign(7.0, 42.0), SimSettings())
        assert first_a.wait(0.0) is False  # within 60 s of the worker's start: debounced
        first_b = worker.request(ThumbDesign(7.0, 47.0), SimSettings())
        t = time.monotonic()
        assert first_b.wait(5.0) is False and time.monotonic() - t < 0.5
    finally:
        worker.close()
        store.close()


def test_latency_log_writes_only_when_asked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    log = tmp_path / "latency.txt"
    monkeypatch.delenv(ENV, raising=False)
    mark("apply", "1 2")
    assert not log.exists()
    monkeypatch.setenv(ENV, str(log))
    t0 = time.time()
    mark("apply", "20.0 50.0")
    mark("header_shown")
    lines = log.read_text().splitlines()
    assert [ln.split(" ", 1)[1].strip() for ln in lines] == ["apply 20.0 50.0", "header_shown"]
    stamps = [float(ln.split(" ", 1)[0]) for ln in lines]
    assert t0 - 1 <= stamps[0] <= stamps[1] <= time.time() + 1


def _scene_wait(
    first: FirstEstimate, newer: bool = False, show_after_s: float | None = None
) -> float:
    """Seconds ``Session._wait_for_estimate`` waits (the session's state faked)."""
    import threading
    from types import SimpleNamespace

    from app.explorer.session import Session

    fake = SimpleNamespace(_newer_design_waiting=lambda: newer)
    if show_after_s is not None:
        threading.Timer(show_after_s, first.set_shown).start()
    t0 = time.monotonic()
    Session._wait_for_estimate(fake, first, t0)  # type: ignore[arg-type]  # noqa: SLF001
    return time.monotonic() - t0


def test_scene_waits_for_the_estimate_then_the_paint_unless_a_newer_design_waits() -> None:
    from app.explorer.session import PAGE_PAINT_S, SCENE_AFTER_ESTIMATE_S

    # shown after 0.1 s: the scene follows PAGE_PAINT_S later
    dt = _scene_wait(FirstEstimate(coming=True), show_after_s=0.1)
    assert 0.1 + PAGE_PAINT_S - 0.02 <= dt < 0.1 + PAGE_PAINT_S + 0.4
    # never shown: the scene goes at the cap, without the paint wait
    dt = _scene_wait(FirstEstimate(coming=True))
    assert SCENE_AFTER_ESTIMATE_S - 0.02 <= dt < SCENE_AFTER_ESTIMATE_S + 0.4
    # none coming (stored design, or a drag's debounce), or a newer design waiting: no wait
    assert _scene_wait(FirstEstimate(coming=False)) < 0.1
    assert _scene_wait(FirstEstimate(coming=True), newer=True, show_after_s=0.05) < 0.1
