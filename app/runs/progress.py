"""A terminal progress bar for long runs."""

from __future__ import annotations

import sys
import time


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
