"""Server memory over a session: open 8 explorer tabs at once, close them, 10 times; print the
server's RSS (and its children's) after each round. Issue: RSS returns to within 10 % of its
starting level after the tabs close.

Usage: PYTHONPATH=. .venv/bin/python benchmarks/bench_explorer_rss.py [--tabs 8] [--rounds 10]

The server is ``handbench serve`` in a subprocess (port 0, a fresh store under build/, the
S_GAS panel on chips_can only and computed in a thread, so the figures are the server's own);
it is stopped with SIGTERM at the end, and the script checks nothing it started is left.

Two start levels are printed, and the rounds are compared with both:

- *process start*: the RSS once the server listens (``open http://... in a browser``).
- *ready*: the RSS once the server has loaded its warm engine in the background (the
  compiled kernels and the objects' meshes, hypotheses, arrays and signed distances, what
  every tab uses and the server keeps when the last tab closes). The script waits for the
  server's own ``engine ready in X s`` line (printed when that thread has finished and the
  freed heap was returned), then for the thread count to stay unchanged for ``--settle``
  seconds, and reads the RSS: the server's level with nothing but itself running. It waits
  for a log line, not for the RSS to stop growing, so a slow machine cannot make it read the
  level half-way through the loading.

The issue's target is the ready level: a tab should not leave anything behind, but the engine
loaded for the first tab is meant to stay. Numba's on-disk cache is warmed first
(``python -m app.sim.warm``, what ``make setup`` does), so the figures never include a compile.
"""

from __future__ import annotations

import argparse
import os
import queue
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def rss_mb(pid: int) -> float:
    """Resident set size of ``pid`` (MB), from /proc."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def threads(pid: int) -> int:
    """Threads of ``pid``, from /proc."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    return 0


def settle(pid: int, quiet_s: float, max_s: float) -> float:
    """Wait until the server's thread count has not changed for ``quiet_s`` (its sessions'
    threads have ended), at most ``max_s``; the seconds waited."""
    t0 = time.monotonic()
    last, since = threads(pid), time.monotonic()
    while time.monotonic() - t0 < max_s:
        time.sleep(0.25)
        n = threads(pid)
        if n != last:
            last, since = n, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            break
    return time.monotonic() - t0


def children(pid: int) -> list[int]:
    """Direct child processes of ``pid``."""
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--tabs", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=10)
    ap.add_argument(
        "--settle", type=float, default=3.0,
        help="after closing the tabs, wait until the server's thread count is steady this long",
    )  # fmt: skip
    ap.add_argument("--settle-max", type=float, default=60.0, help="... but at most this long")
    ap.add_argument(
        "--ready-max", type=float, default=300.0,
        help="how long the server may take to listen and load its engine",
    )  # fmt: skip
    args = ap.parse_args()

    from app.explorer.browser import browser_context

    build = ROOT / "build" / "bench_rss"
    build.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, HANDBENCH_EXPLORER_OBJECTS="chips_can", HANDBENCH_EXPLORER_WORKERS="0")
    env["PYTHONPATH"] = str(ROOT)
    warm = subprocess.run(
        [sys.executable, "-m", "app.sim.warm"], env=env, capture_output=True, text=True
    )
    print(f"numba cache: {warm.stdout.strip() or warm.stderr.strip()[-300:]}", flush=True)
    store = Path(tempfile.mkdtemp(dir=build)) / "store.sqlite"
    cmd = [sys.executable, "-m", "app.cli", "serve", "--port", "0", "--store", str(store)]
    srv = subprocess.Popen(
        cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    lines: queue.Queue[str] = queue.Queue()

    def drain() -> None:  # the server's output, read to its end (a full pipe would block it)
        assert srv.stdout is not None
        for line in srv.stdout:
            lines.put(line)

    threading.Thread(target=drain, daemon=True).start()
    url = start = ready_s = None
    t_end = time.monotonic() + args.ready_max
    while (url is None or ready_s is None) and time.monotonic() < t_end:
        try:
            line = lines.get(timeout=1.0)
        except queue.Empty:
            if srv.poll() is not None:
                break
            continue
        if m := re.search(r"open (http://\S+) in a browser", line):
            url, start = m.group(1), rss_mb(srv.pid)
        elif m := re.search(r"engine ready in ([0-9.]+) s", line):
            ready_s = float(m.group(1))
        elif "engine preload failed" in line:
            print(line.strip(), file=sys.stderr)
            break
    if url is None or start is None or ready_s is None:
        print("the server did not start, or did not report its engine ready", file=sys.stderr)
        srv.kill()
        srv.wait()
        return 1
    settle(srv.pid, args.settle, args.settle_max)
    ready = rss_mb(srv.pid)
    print(
        f"server pid {srv.pid} at {url}; RSS at process start {start:.0f} MB, "
        f"ready {ready:.0f} MB (engine loaded in {ready_s:.1f} s)",
        flush=True,
    )
    rows = []
    try:
        with browser_context(900, 600, build / "profiles") as ctx:
            for r in range(args.rounds):
                t0 = time.perf_counter()
                pages = [ctx.new_page() for _ in range(args.tabs)]
                for k, page in enumerate(pages):
                    page.goto(f"{url}/?cmc=0&mcp={45 + 5 * (k % 4)}", wait_until="commit")
                for page in pages:
                    page.get_by_text("CMC (°)", exact=True).wait_for(timeout=120_000)
                opened = rss_mb(srv.pid)
                for page in pages:
                    page.close()
                settle(srv.pid, args.settle, args.settle_max)
                closed = rss_mb(srv.pid)
                rows.append((r + 1, opened, closed, time.perf_counter() - t0))
                print(
                    f"round {r + 1:2d}: {args.tabs} tabs open {opened:6.0f} MB, "
                    f"closed {closed:6.0f} MB ({time.perf_counter() - t0:.1f} s)",
                    flush=True,
                )
    finally:
        kids = children(srv.pid)
        srv.send_signal(signal.SIGTERM)
        try:
            srv.wait(timeout=30)
        except subprocess.TimeoutExpired:
            srv.kill()
            print("the server ignored SIGTERM", file=sys.stderr)
        left = [p for p in kids if Path(f"/proc/{p}").exists()]
        print(f"after SIGTERM: server exit code {srv.returncode}; children left: {left}")
    if not rows:
        return 1
    first, last = rows[0][2], rows[-1][2]
    worst = max(r[2] for r in rows)
    print(
        f"RSS after closing: first round {first:.0f} MB, last round {last:.0f} MB "
        f"({100 * (last - first) / first:+.1f} % vs the first round); "
        f"highest {worst:.0f} MB = {100 * (worst - ready) / ready:+.1f} % vs the ready level "
        f"({ready:.0f} MB), {100 * (worst - start) / start:+.1f} % vs the process start "
        f"({start:.0f} MB)"
    )
    print(
        "per round vs ready: "
        + " ".join(f"{100 * (r[2] - ready) / ready:+.1f}" for r in rows)
        + " %"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
