"""The palm stages of an object's hypotheses, kept per process and cached on disk.

A hypothesis' palm stage (``app.sim.simulate.PalmGrasp``: the thumbless hand's approach,
back-off, long fingers and their contacts) does not depend on the thumb design, and it is
about half of what one new design costs (docs/cost-model.md). A ``PalmTable`` holds them for
every hypothesis of one object, so that each is computed once per process and every design
(every task, every slider move in the explorer) starts from it.

Disk: ``$XDG_CACHE_HOME/handbench/palms/<key>.npz`` (``~/.cache/...``) holds a complete
table. ``make setup`` builds the tables of the built-in objects and of the saved imports for
the default settings (``python -m app.runs.palm_cache``, a few seconds), and ``handbench
objects import`` builds the imported object's (a 65k-face scan: about 5 s); a run with other
settings or another hand file computes its palm stages as it goes (in memory), and a process
that has computed every row of a table saves it (its first use). The key hashes
everything a palm stage depends on: the hand file, the object (``object_key``), the settings
(``SimSettings.key()``, which carries ``ENGINE_VERSION``) and the source of the simulation
and model code, so that a code change can never serve a stale stage. Files are written
atomically (temp file + rename); an unreadable file is ignored and an unwritable folder
only costs the computation. A cached stage equals a computed one bit for bit (the arrays are
stored as float64; ``tests/test_palm_cache.py``).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import threading
import time
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from app import cache_root
from app.hashing import stable_hash
from app.model.contact_set import LINK_NAMES, ContactSet
from app.model.hand.data import load_hand_dims
from app.model.objects import OBJECT_KEYS, available_keys, load_object
from app.quality.settings import SimSettings
from app.runs.keys import object_key
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import PalmGrasp, cached_kit, simulate_palm

#: Bump when the file layout changes.
PALM_FORMAT = 1
#: Tables kept per process (one per object and settings).
MAX_TABLES = 16
_LINK_CODE = {n: k for k, n in enumerate(LINK_NAMES)}


def cache_dir() -> Path:
    """Where palm tables are cached: ``$XDG_CACHE_HOME/handbench/palms``."""
    return cache_root() / "palms"


@lru_cache(maxsize=1)
def _code_hash() -> str:
    """Hash of the simulation and model sources (app/sim, app/model): a palm stage computed
    by other code is never served."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for folder in ("sim", "model"):
        for p in sorted((root / folder).rglob("*.py")):
            h.update(str(p.relative_to(root)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()[:16]


def palm_key(object_name: str, settings: SimSettings) -> str:
    """Cache key of an object's palm table under ``settings`` (default hand file)."""
    return stable_hash(
        {
            "format": PALM_FORMAT,
            "hand": load_hand_dims().content_hash,
            "object": object_key(object_name),
            "settings": settings.key(),
            "code": _code_hash(),
        }
    )


class PalmTable:
    """The palm stages of one object's anthropomorphic hypotheses (filled as computed)."""

    def __init__(self, object_name: str, settings: SimSettings, n: int) -> None:
        self.object_name = object_name
        self.settings = settings
        self.key = palm_key(object_name, settings)
        self._rows: list[PalmGrasp | None] = [None] * n
        self._lock = threading.Lock()
        self.from_disk = False
        #: rows not yet known; when this process computes the last one, the table is saved
        self._n_missing = n
        self.saved = False

    def __len__(self) -> int:
        return len(self._rows)

    @property
    def complete(self) -> bool:
        """Every hypothesis has its palm stage."""
        return all(r is not None for r in self._rows)

    def get(self, i: int) -> PalmGrasp:
        """Hypothesis ``i``'s palm stage, computed (and kept) when missing."""
        row = self._rows[i]
        if row is None:
            obj, hyps = load_object(self.object_name), cached_hypotheses(self.object_name)
            row = simulate_palm(_palm_kit(), obj, hyps, i, self.settings)
            with self._lock:
                if self._rows[i] is None:
                    self._n_missing -= 1
                self._rows[i] = row
                done = self._n_missing == 0 and not self.from_disk and not self.saved
            if done:  # every row computed here: cache the table for later processes
                self.saved = self.save()
        return row

    # ------------------------------------------------------------------ disk
    def path(self) -> Path:
        """The table's cache file."""
        return cache_dir() / f"{self.key}.npz"

    def load(self) -> bool:
        """Fill the table from its cache file; whether a valid file was read."""
        try:
            with np.load(self.path(), allow_pickle=False) as z:
                rows = _unpack(z, len(self._rows))
        except (OSError, KeyError, ValueError):
            return False
        with self._lock:
            self._rows = list(rows)
            self._n_missing = 0
        self.from_disk = True
        return True

    def save(self) -> bool:
        """Write the complete table to its cache file (atomically); whether it was written."""
        assert self.complete, "only complete tables are cached"
        rows = [r for r in self._rows if r is not None]
        path = self.path()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.tmp")
            with os.fdopen(fd, "wb") as fh:
                packed: dict[str, Any] = _pack(rows)  # (Any: savez's keywords are typed)
                np.savez(fh, **packed)
            os.replace(tmp, path)
        except OSError:
            return False
        return True


def _palm_kit():  # noqa: ANN202 (HandKit)
    """The kit that computes palm stages: any design's gives the same numbers (the thumb
    takes no part); one fixed kit keeps them independent of which design asked."""
    return cached_kit(0.0, 0.0, "ulnar")


def _pack(rows: list[PalmGrasp]) -> dict[str, np.ndarray]:
    """Column arrays of ``rows`` (contacts concatenated, with offsets)."""
    counts = np.array([len(r.contacts) for r in rows], np.int64)
    off = np.concatenate([[0], np.cumsum(counts)])
    cs = [r.contacts for r in rows]
    return {
        "start": np.array([r.start_mm for r in rows], float),
        "s": np.array([r.s_mm for r in rows], float),
        "T": np.stack([r.T_object_palm for r in rows]).astype(float),
        "q": np.stack([r.q for r in rows]).astype(float),
        "queries": np.array([r.queries for r in rows], np.int64),
        "offsets": off,
        "p": np.concatenate([c.p_object for c in cs]).astype(float).reshape(-1, 3),
        "n": np.concatenate([c.n_object for c in cs]).astype(float).reshape(-1, 3),
        "link": np.array([_LINK_CODE[str(x)] for c in cs for x in c.link], np.int64),
        "palmar": np.concatenate([c.palmar for c in cs]).astype(bool),
    }


def _unpack(z: np.lib.npyio.NpzFile, n: int) -> list[PalmGrasp]:
    """Rows of a packed table of ``n`` hypotheses (ValueError when it does not fit)."""
    off = z["offsets"]
    if len(z["start"]) != n or len(off) != n + 1:
        raise ValueError("palm table of another hypothesis count")
    names = np.array(LINK_NAMES, dtype=object)
    p, nn, link, palmar = z["p"], z["n"], names[z["link"]], z["palmar"]
    start, s, T, q, queries = z["start"], z["s"], z["T"], z["q"], z["queries"]
    rows = []
    for i in range(n):
        a, b = int(off[i]), int(off[i + 1])
        cs = ContactSet(p[a:b].copy(), nn[a:b].copy(), link[a:b].copy(), palmar[a:b].copy())
        if a == b:
            cs = ContactSet()
        rows.append(
            PalmGrasp(float(start[i]), float(s[i]), T[i].copy(), q[i].copy(), cs, int(queries[i]))
        )
    return rows


_TABLES: dict[tuple[str, str], PalmTable] = {}
_TABLES_LOCK = threading.Lock()


def palm_table(object_name: str, settings: SimSettings) -> PalmTable:
    """The process' palm table of an object under ``settings``, read from the disk cache on
    first use when there is one."""
    k = (object_name, settings.key())
    with _TABLES_LOCK:
        t = _TABLES.get(k)
        if t is None:
            if len(_TABLES) >= MAX_TABLES:
                _TABLES.clear()
            t = PalmTable(object_name, settings, len(cached_hypotheses(object_name)))
            t.load()
            _TABLES[k] = t
    return t


def clear_tables() -> None:
    """Forget the process' palm tables (the explorer's release of memory; tests)."""
    with _TABLES_LOCK:
        _TABLES.clear()


def build_tables(
    object_names: tuple[str, ...] = OBJECT_KEYS, settings: SimSettings | None = None
) -> list[tuple[str, int, float, bool]]:
    """Compute and cache the complete palm tables of ``object_names``; (object, hypotheses,
    seconds, whether it was already cached) per object."""
    settings = settings or SimSettings()
    out = []
    for name in object_names:
        t0 = time.perf_counter()
        table = palm_table(name, settings)
        cached = table.from_disk
        if not cached:
            for i in range(len(table)):
                table.get(i)
            if not table.saved:
                table.saved = table.save()
        out.append((name, len(table), time.perf_counter() - t0, cached))
    return out


def main() -> None:
    """Build the palm tables of the built-in objects and of the saved imports for the
    default settings (``make setup``)."""
    for name, n, dt, cached in build_tables(available_keys()):
        state = "cached" if cached else "built"
        print(f"palm stages of {name}: {n} hypotheses {state} in {dt:.1f} s")


if __name__ == "__main__":
    main()
