"""How fast the explorer's Live S_GAS panel answers a design change, seen in a real browser.

For each design of ``--designs`` this starts ``handbench serve`` on ``--port`` with a fresh,
empty store (nothing cached), opens the page in headless chromium (playwright) at CMC 0° and
the design's MCP, waits until that start-up design shows its first estimate (the process pool
is then warm), types the design's CMC into its box (Enter: one commit, no intermediate
design) and follows the panel. It prints, from t0 = the Enter:

- ON SCREEN: when the page painted the panel's header naming the new design, its first
  estimate (an object row with "95 % CI") and its complete total. A script in the page
  (``SCREEN_JS``) stamps every change of the panel's state with the end of the frame that
  painted it; these are what a user sees.
- polled: the same read by polling the panel's text every 50 ms (every change goes to
  ``<out>/trace_<n>.txt``), with the estimated total and per object its first estimate and
  its final value. A poll waits for the page's main thread, which a software-WebGL frame
  holds for 0.1-0.5 s, so these can be later than the painted times.
- server: the server's own latency trace (``HANDBENCH_LATENCY_LOG``, app.explorer.latency_log):
  slider value received, header sent, first sample started and shown, scene sent.

``--cancel A;B`` adds a run: commit design A, wait for A's first estimate, commit design B
(A is still computing), then report B's times as above, plus the stored outcome counts of A
and B (read from the store file) over time: A's count must stop growing once B is committed.

``--series N`` adds a run on one server and page: N new designs in a row, each changing one
box, each committed 0.5-2.5 s after the one before is complete (or, with
``--series-overlap``, as soon as the one before shows its first estimate), then the median
and the worst of each latency.

The server's output goes to ``<out>/server_<n>.log``; ``uptime``'s load average is printed
before each run. ``--shots`` saves ``first_estimate.png`` (while the first interval is shown)
and ``full.png`` (after the full value) of the first run under ``--out``. Nothing is asserted.

Usage:
    .venv/bin/python benchmarks/bench_live_score.py --port 8123 \
        --designs "20,50;35,65" --cancel "25,55;40,55" --series 12 --out /tmp/live_timing --shots
    .venv/bin/python benchmarks/bench_live_score.py --designs "" --cancel "" \
        --series 12 --series-overlap
"""

from __future__ import annotations

import argparse
import math
import os
import re
import signal
import sqlite3
import subprocess
import sys
import threading
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
POLL_S = 0.05
ENTER_WALL: list[float] = []
"""Wall-clock time of every Enter (to align the server's latency trace)."""
HEADER = re.compile(r"CMC ([\d.]+)°, MCP ([\d.]+)° — ([a-z]+)")
TOTAL = re.compile(r"total ([\d.]+) \(your store\)")
PANEL_JS = """() => {
  const el = [...document.querySelectorAll('table')].find(t => t.innerText.includes('progress'));
  const box = el ? el.parentElement : null;
  return box ? box.innerText : '';
}"""


SCREEN_JS = r"""() => {
  if (window.__hbScreen) return;
  const log = (window.__hbScreen = []);
  let last = "";
  const panel = () => {
    const tables = [...document.querySelectorAll("table")];
    const el = tables.find((t) => t.textContent.includes("progress"));
    return el ? el.parentElement.textContent : "";
  };
  new MutationObserver(() => {
    const txt = panel();
    const m = txt.match(/CMC ([\d.]+)°, MCP ([\d.]+)° — ([a-z]+)/);
    if (!m) return;
    const est = txt.includes("95 % CI") ? 1 : 0;
    const total = /total [\d.]+ \(your store\)/.test(txt) ? 1 : 0;
    const key = `${m[1]},${m[2]},${m[3]},${est},${total}`;
    if (key === last) return;
    last = key;
    const e = { key, screen: null };
    log.push(e);
    // a change made in a frame's animation callbacks (viser applies most messages there) is
    // painted by that frame, one made in any other task by the next frame; a message posted
    // in a frame's task is handled once that frame (its paint and commit) is done
    const afterTask = () => {
      const ch = new MessageChannel();
      ch.port1.onmessage = () => { e.screen = performance.now(); };
      ch.port2.postMessage(0);
    };
    if (inFrame) afterTask();
    else requestAnimationFrame(afterTask);
  }).observe(document.body, { subtree: true, childList: true, characterData: true });
  // inFrame: within a frame's task. This loop's callback is registered before the viewer's
  // on-demand loop wakes, so it runs first in every frame; the message ends the frame's task.
  let inFrame = false;
  const ch = new MessageChannel();
  ch.port1.onmessage = () => { inFrame = false; };
  const tick = () => {
    inFrame = true;
    ch.port2.postMessage(0);
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}"""
"""Installed in the page: every change of the panel's state (design, state word, estimate
shown, total shown) with the page's time of the end of the frame that painted it. The polls
of ``watch`` wait for the page's main thread, which a software-WebGL frame holds for
0.1-0.5 s; these times do not."""


def clock_offset(page: Any) -> float:
    """perf_counter() - the page's performance.now() / 1000, from the quickest of 7 round
    trips."""
    best = (math.inf, 0.0)
    for _ in range(7):
        a = time.perf_counter()
        p = page.evaluate("() => performance.now()")
        b = time.perf_counter()
        best = min(best, (b - a, (a + b) / 2 - p / 1000.0))
        time.sleep(0.02)
    return best[1]


def screen_times(page: Any, design: tuple[float, float], t0: float, offset: float) -> Timeline:
    """When the page painted the design's header, first estimate and total (s after t0)."""
    tl = Timeline()
    for e in page.evaluate("() => window.__hbScreen || []"):
        c, m, state, est, total = e["key"].split(",")
        if (float(c), float(m)) != design or e["screen"] is None:
            continue
        t = e["screen"] / 1000.0 + offset - t0
        if t < -0.05:
            continue  # an earlier visit of the same design
        if tl.t_hdr is None:
            tl.t_hdr = t
        if est == "1" and tl.t_first is None:
            tl.t_first = t
        if total == "1" and state == "complete" and tl.t_full is None:
            tl.t_full = t
    return tl


def parse_designs(text: str) -> list[tuple[float, float]]:
    """'20,50;35,65' -> [(20, 50), (35, 65)]."""
    out = []
    for part in text.split(";"):
        if part.strip():
            c, m = part.split(",")
            out.append((float(c), float(m)))
    return out


def loadavg() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


@dataclass
class Timeline:
    """What the panel showed after t0 (seconds since t0)."""

    t_hdr: float | None = None
    t_first: float | None = None
    screen: Timeline | None = None
    """The same times, painted (``SCREEN_JS``): what a user sees."""
    t_total_est: float | None = None
    """The estimated total (with bounds from every object's sample) first shown."""
    total_est: str = ""
    first_text: str = ""
    t_full: float | None = None
    total: str | None = None
    per_object_first: dict[str, float] = field(default_factory=dict)
    per_object_done: dict[str, float] = field(default_factory=dict)
    states: list[tuple[float, str]] = field(default_factory=list)
    odd: list[str] = field(default_factory=list)


def object_rows(text: str, objects: list[str]) -> dict[str, str]:
    """object -> its table row's text."""
    rows = {}
    for line in text.splitlines():
        head = line.split("\t")[0].strip()
        if head in objects:
            rows[head] = line
    return rows


def watch(
    page: Any,
    design: tuple[float, float],
    objects: list[str],
    t0: float,
    timeout_s: float,
    stop_at_first: bool = False,
    on_first: Any = None,
    trace: Any = None,
    offset: float | None = None,
) -> Timeline:
    """Poll the panel until the design is complete (or the first estimate, or timeout);
    with the page's ``clock_offset``, also when each step was painted (``Timeline.screen``)."""

    def done(tl: Timeline) -> Timeline:
        if offset is None:
            return tl
        want = ("first" if stop_at_first else "full") if tl.t_first or tl.t_full else None
        t_end = time.perf_counter() + 3.0
        while True:  # the painted time comes once the frame that painted it is done
            tl.screen = screen_times(page, design, t0, offset)
            got = tl.screen.t_first if want == "first" else tl.screen.t_full
            if want is None or got is not None or time.perf_counter() > t_end:
                return tl
            time.sleep(0.1)

    tl = Timeline()
    want = (design[0], design[1])
    last_state = None
    seen_new = False
    last_text = None
    while time.perf_counter() - t0 < timeout_s:
        text = page.evaluate(PANEL_JS)
        t = time.perf_counter() - t0
        if trace is not None and text != last_text:
            trace.write(f"--- {t:.3f} s\n{text}\n")
            last_text = text
        m = HEADER.search(text)
        if m:
            d = (float(m.group(1)), float(m.group(2)))
            state = f"{d[0]:g}/{d[1]:g} {m.group(3)}"
            if state != last_state:
                tl.states.append((t, state))
                last_state = state
            if d != want:
                if seen_new:
                    tl.odd.append(f"{t:.2f} s: header back to {state} after the new design")
                time.sleep(POLL_S)
                continue
            seen_new = True
            if tl.t_hdr is None:
                tl.t_hdr = t
            rows = object_rows(text, objects)
            for k, row in rows.items():
                if "95 % CI" in row and k not in tl.per_object_first:
                    tl.per_object_first[k] = t
                if "done" in row.split("\t")[-1] and k not in tl.per_object_done:
                    tl.per_object_done[k] = t
                if "≈" in row and "95 % CI" not in row:
                    tl.odd.append(f"{t:.2f} s: estimate without an interval: {row!r}")
            if tl.t_total_est is None and "total ≈" in text:
                tl.t_total_est = t
                tl.total_est = text[text.index("total ≈") :].split(" —")[0]
            if tl.t_first is None and any("95 % CI" in r for r in rows.values()):
                tl.t_first = t
                tl.first_text = text
                if on_first is not None:
                    on_first()
                if stop_at_first:
                    return done(tl)
            if m.group(3) == "complete":
                tot = TOTAL.search(text.replace("**", ""))
                if tot:
                    tl.t_full = t
                    tl.total = tot.group(1)
                    tl.first_text = tl.first_text or text
                    return done(tl)
        time.sleep(POLL_S)
    return done(tl)


def store_counts(path: Path) -> dict[str, int]:
    """design_key -> stored outcomes (read-only, no lock held)."""
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1.0)
        try:
            rows = con.execute(
                "SELECT design_key, COUNT(*) FROM outcomes GROUP BY design_key"
            ).fetchall()
        finally:
            con.close()
    except sqlite3.Error:
        return {}
    return {str(k): int(n) for k, n in rows}


def sample_counts(
    store: Path, t0: float, out: list[tuple[float, dict[str, int]]], stop: threading.Event
) -> None:
    """Append (seconds since t0, store counts) every second until ``stop``."""
    while True:
        out.append((time.perf_counter() - t0, store_counts(store)))
        if stop.wait(1.0):
            return


class Server:
    """``handbench serve`` in a subprocess with a fresh store."""

    def __init__(self, port: int, store: Path, log: Path, trace: Path) -> None:
        store.unlink(missing_ok=True)
        for suffix in ("-wal", "-shm"):
            Path(str(store) + suffix).unlink(missing_ok=True)
        self.log = log.open("w")
        self.store = store
        self.trace = trace
        trace.unlink(missing_ok=True)
        from app.explorer.latency_log import ENV

        env = {**os.environ, ENV: str(trace)}
        self.proc = subprocess.Popen(
            [str(ROOT / ".venv" / "bin" / "handbench"), "serve", "--port", str(port),
             "--store", str(store)],
            cwd=ROOT, stdout=self.log, stderr=subprocess.STDOUT, env=env,
        )  # fmt: skip
        self.url = f"http://127.0.0.1:{port}"
        t_end = time.monotonic() + 60
        while time.monotonic() < t_end:
            try:
                urllib.request.urlopen(self.url, timeout=1).close()
                return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError(f"the server did not answer on {self.url}")

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self.log.close()


def commit(page: Any, design: tuple[float, float], current: tuple[float, float]) -> float:
    """Type the values that differ from ``current`` into their boxes (Enter each); returns
    t0 (the last Enter). One box changed means one commit: no intermediate design."""
    rows = page.locator("div:has(> .mantine-Slider-root)")
    t0 = time.perf_counter()
    for i, (v, cur) in enumerate(zip(design, current, strict=True)):
        if v == cur:
            continue
        box = rows.nth(i).locator("input[type=text]")
        box.click()
        box.press("Control+A")
        box.press_sequentially(f"{v:g}")
        t0 = time.perf_counter()
        ENTER_WALL.append(time.time())
        box.press("Enter")
    return t0


def open_page(ctx: Any, url: str, timeout_s: float) -> tuple[Any, float]:
    """Open the page; wait until its start-up design shows a first estimate (warm pool)."""
    page = ctx.new_page()
    t = time.perf_counter()
    page.goto(url)
    page.get_by_text("CMC (°)", exact=True).wait_for(timeout=60_000)
    page.add_style_tag(content=".mantine-Notifications-root { display: none !important; }")
    page.evaluate(SCREEN_JS)
    while time.perf_counter() - t < timeout_s:
        if "95 % CI" in page.evaluate(PANEL_JS):
            return page, time.perf_counter() - t
        time.sleep(POLL_S)
    return page, float("nan")


def server_steps(trace: Path, t_wall: float, until_s: float = 30.0) -> str:
    """The server's latency trace after the Enter at ``t_wall`` (s since it)."""
    try:
        lines = trace.read_text().splitlines()
    except OSError:
        return "no trace"
    out = []
    for line in lines:
        t, _, rest = line.partition(" ")
        dt = float(t) - t_wall
        if -0.05 <= dt <= until_s:
            out.append(f"{dt:.3f} {rest.strip()}")
    return "; ".join(out[:20])


def report(name: str, tl: Timeline, objects: list[str]) -> None:
    def f(x: float | None) -> str:
        return "not seen" if x is None else f"{x:.2f} s"

    sc = tl.screen or Timeline()
    print(f"  {name}: ON SCREEN header {f(sc.t_hdr)}, first estimate {f(sc.t_first)}, "
          f"complete {f(sc.t_full)}")  # fmt: skip
    print(f"    polled: header {f(tl.t_hdr)}, first estimate with interval {f(tl.t_first)}, "
          f"estimated total {f(tl.t_total_est)} ({tl.total_est}), "
          f"complete {f(tl.t_full)} (total {tl.total})")  # fmt: skip
    for k in objects:
        print(f"    {k:13s} first estimate {f(tl.per_object_first.get(k))}, "
              f"done {f(tl.per_object_done.get(k))}")  # fmt: skip
    print("    states: " + ", ".join(f"{t:.2f} s {s}" for t, s in tl.states))
    if tl.first_text:
        rows = object_rows(tl.first_text, objects)
        for k in objects:
            if "95 % CI" in rows.get(k, ""):
                print("    first estimate row: " + rows[k].replace("\t", " | "))
                break
    for o in tl.odd[:10]:
        print("    ODD: " + o)


def main() -> None:
    ap = argparse.ArgumentParser(
        description=(__doc__ or "").splitlines()[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=(__doc__ or "").split("Usage:")[-1],
    )
    ap.add_argument("--designs", default="20,50;35,65;10,40", help="'CMC,MCP;CMC,MCP;...'")
    ap.add_argument(
        "--cancel",
        default="25,55;40,55",
        help="'A;B' ('' skips the run); A and B share the MCP (one commit each)",
    )
    ap.add_argument("--port", type=int, default=8123)
    ap.add_argument("--out", default="/tmp/live_timing")
    ap.add_argument("--shots", action="store_true", help="screenshots of the first run")
    ap.add_argument("--timeout", type=float, default=900.0, help="per design (s)")
    ap.add_argument("--settle", type=float, default=3.0, help="re-read the total after (s)")
    ap.add_argument(
        "--series",
        type=int,
        default=0,
        help="then N new designs in a row on one server and page (each changes one box, off "
        "the shipped grid), each committed once the one before is complete; prints the "
        "median and the worst of each latency",
    )
    ap.add_argument(
        "--series-overlap",
        action="store_true",
        help="in --series, commit each design once the one before shows its first estimate "
        "(it is then still computing) instead of once it is complete",
    )
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(ROOT))
    from app.explorer.browser import browser_context
    from app.model.design import ThumbDesign
    from app.model.objects import OBJECT_KEYS
    from app.runs.keys import design_key

    env_objs = os.environ.get("HANDBENCH_EXPLORER_OBJECTS", "")
    objects = [k for k in env_objs.split(",") if k] or list(OBJECT_KEYS)
    runs: list[tuple[str, list[tuple[float, float]]]] = [
        (f"run {i + 1}", [d]) for i, d in enumerate(parse_designs(a.designs))
    ]
    if a.cancel.strip():
        runs.append(("cancel", parse_designs(a.cancel)))
    print(f"objects: {', '.join(objects)}; polling every {POLL_S * 1000:.0f} ms")
    for n, (name, designs) in enumerate(runs):
        print(f"\n{name}: {' then '.join(f'CMC {c:g} MCP {m:g}' for c, m in designs)}")
        print(f"  load before: {loadavg()}")
        trace: Any = None
        srv = Server(a.port, out / f"store_{n}.sqlite", out / f"server_{n}.log",
                     out / f"latency_{n}.txt")  # fmt: skip
        try:
            with browser_context(1400, 900, out / "profiles") as ctx:
                # the page starts at CMC 0 and the first design's MCP: a commit then
                # changes the CMC only (one box, one design change)
                start = (0.0, designs[0][1])
                page, warm = open_page(ctx, f"{srv.url}/?cmc=0&mcp={start[1]:g}", a.timeout)
                offset = clock_offset(page)
                print(f"  page open at CMC 0 MCP {start[1]:g} -> its first estimate: "
                      f"{warm:.2f} s (includes the process pool's start)")  # fmt: skip
                shots = a.shots and n == 0
                trace = (out / f"trace_{n}.txt").open("w")
                if name != "cancel":
                    t_type = time.perf_counter()
                    t0 = commit(page, designs[0], start)
                    print(f"  typing took {t0 - t_type:.2f} s before the Enter (t0)")

                    def shot_first(page: Any = page) -> None:
                        page.screenshot(path=str(out / "first_estimate.png"))

                    tl = watch(page, designs[0], objects, t0, a.timeout, trace=trace,
                               on_first=shot_first if shots else None,
                               offset=offset)  # fmt: skip
                    report(f"CMC {designs[0][0]:g} MCP {designs[0][1]:g}", tl, objects)
                    print("    server: " + server_steps(srv.trace, ENTER_WALL[-1], 3.0))
                    if tl.total is not None:
                        time.sleep(a.settle)
                        again = TOTAL.search(page.evaluate(PANEL_JS).replace("**", ""))
                        print(f"  total {a.settle:g} s after complete: "
                              f"{again.group(1) if again else 'not shown'}")  # fmt: skip
                    if shots:
                        page.screenshot(path=str(out / "full.png"))
                        print(f"  screenshots: {out / 'first_estimate.png'}, {out / 'full.png'}")
                    continue
                first, second = designs[0], designs[1]
                ka = design_key(ThumbDesign(*first))
                kb = design_key(ThumbDesign(*second))
                t0a = commit(page, first, start)
                tla = watch(page, first, objects, t0a, a.timeout, stop_at_first=True,
                            trace=trace, offset=offset)  # fmt: skip
                report(f"A = CMC {first[0]:g} MCP {first[1]:g} (until its first estimate)",
                       tla, objects)  # fmt: skip
                t_type = time.perf_counter()
                t0b = commit(page, second, first)
                print(f"  B committed {t0b - t0a:.2f} s after A (typing took "
                      f"{t0b - t_type:.2f} s before the Enter)")  # fmt: skip
                trace.write("=== B committed (times below from B's Enter)\n")
                counts: list[tuple[float, dict[str, int]]] = []
                done = threading.Event()

                sampler = threading.Thread(
                    target=sample_counts, args=(srv.store, t0b, counts, done), daemon=True
                )
                sampler.start()
                tlb = watch(page, second, objects, t0b, a.timeout, trace=trace, offset=offset)
                done.set()
                sampler.join()
                report(f"B = CMC {second[0]:g} MCP {second[1]:g}", tlb, objects)
                print("    server: " + server_steps(srv.trace, ENTER_WALL[-1], 3.0))
                prev = None
                for t, c in counts:
                    now = (c.get(ka, 0), c.get(kb, 0))
                    if now != prev:  # only the changes
                        print(f"  store at B+{t:.1f} s: A {now[0]} outcomes, B {now[1]}")
                    prev = now
                page.close()
        finally:
            srv.stop()
            if trace is not None:
                trace.close()
        print_log(out / f"server_{n}.log")
    if a.series > 0:
        run_series(a, out, objects)


def series_designs(n: int) -> list[tuple[float, float]]:
    """``n`` designs after (0, 52), alternately a new CMC and a new MCP, all distinct and off
    the shipped 5° grid (none is in the shipped reference)."""
    cmcs = [12.0, 22.0, 32.0, 42.0, 17.0, 27.0, 37.0, 7.0, 3.0, 44.0]
    mcps = [57.0, 62.0, 67.0, 72.0, 47.0, 42.0, 77.0, 82.0, 37.0, 87.0]
    cur = (0.0, 52.0)
    out = []
    for k in range(n):
        i = k // 2
        cur = (cmcs[i % len(cmcs)], cur[1]) if k % 2 == 0 else (cur[0], mcps[i % len(mcps)])
        out.append(cur)
    assert len(set(out)) == len(out), "designs of a series must differ"
    return out


def run_series(a: argparse.Namespace, out: Path, objects: list[str]) -> None:
    """N designs in a row on one server and page (see ``--series``)."""
    from app.explorer.browser import browser_context

    n = len(list(out.glob("server_*.log")))
    designs = series_designs(a.series)
    when = "first estimate" if a.series_overlap else "complete"
    print(f"\nseries: {a.series} new designs, each committed once the one before is {when}")
    print(f"  load before: {loadavg()}")
    srv = Server(a.port, out / f"store_{n}.sqlite", out / f"server_{n}.log",
                 out / f"latency_{n}.txt")  # fmt: skip
    rows: list[tuple[Timeline, str]] = []
    try:
        with browser_context(1400, 900, out / "profiles") as ctx:
            cur = (0.0, 52.0)
            page, _ = open_page(ctx, f"{srv.url}/?cmc=0&mcp={cur[1]:g}", a.timeout)
            offset = clock_offset(page)
            watch(page, cur, objects, time.perf_counter(), a.timeout,
                  stop_at_first=a.series_overlap)  # fmt: skip
            for k, d in enumerate(designs):
                # 0.5-2.5 s between designs, spread over the page's 1 s redraw heartbeat and
                # its other timers (the ghost thumb hides 4 s after a design change)
                time.sleep(0.5 + (0.37 * k) % 2.0)
                t0 = commit(page, d, cur)
                tl = watch(page, d, objects, t0, a.timeout, stop_at_first=a.series_overlap,
                           offset=offset)  # fmt: skip
                rows.append((tl, server_steps(srv.trace, ENTER_WALL[-1], 3.0)))
                report(f"CMC {d[0]:g} MCP {d[1]:g}", tl, [])
                print(f"    server: {rows[-1][1]}")
                cur = d
            page.close()
    finally:
        srv.stop()
    print(f"  load after: {loadavg()}")

    def stat(name: str, xs: list[float | None]) -> None:
        v = sorted(x for x in xs if x is not None)
        if v:
            print(f"  {name}: median {v[len(v) // 2]:.2f} s, worst {v[-1]:.2f} s "
                  f"({len(v)} of {len(xs)} seen)")  # fmt: skip

    sc = [r.screen or Timeline() for r, _ in rows]
    stat("header on screen", [r.t_hdr for r in sc])
    stat("FIRST ESTIMATE ON SCREEN", [r.t_first for r in sc])
    if not a.series_overlap:
        stat("complete on screen", [r.t_full for r in sc])
    stat("first estimate polled", [r.t_first for r, _ in rows])
    print_log(out / f"server_{n}.log")


def print_log(path: Path) -> None:
    """The last lines of a server's log."""
    log = path.read_text()
    print(f"  server log ({len(log.splitlines())} lines):")
    for line in log.splitlines()[-8:]:
        print("    | " + line)


if __name__ == "__main__":
    main()
