"""An opt-in trace of the explorer's latencies: wall-clock stamps of a design change's steps
(slider value received, panel header sent, first sample started and shown, ...).

Off unless ``HANDBENCH_LATENCY_LOG`` names a file; then every ``mark`` appends one line
``<unix time> <event> <detail>`` to it. ``benchmarks/bench_live_score.py`` sets it for its
server and splits the browser's latency into the server's steps and the page's."""

from __future__ import annotations

import os
import threading
import time

ENV = "HANDBENCH_LATENCY_LOG"
_lock = threading.Lock()


def mark(event: str, detail: str = "") -> None:
    """Append ``event`` (one word) with the current time, if the trace is on."""
    path = os.environ.get(ENV)
    if not path:
        return
    line = f"{time.time():.6f} {event} {detail}\n"
    with _lock, open(path, "a") as f:
        f.write(line)
