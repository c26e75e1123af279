"""handbench: design explorer and simulation benchmark for anthropomorphic hands.

Layers, bottom to top (docs/architecture.md): base modules (``errors``, ``hashing``,
``config_docs``) ← ``model`` ← ``sim`` ← ``quality`` ← ``runs`` ← ``reports`` / ``explorer`` /
``cli``. The numerical core never imports the UI; only ``app.explorer`` imports viser.
"""

import hashlib
import os
from pathlib import Path

__version__ = "0.1.0"

#: The files whose numba kernels call one another (``@njit(cache=True)``).
NUMBA_SOURCES = (
    "model/objects/distance_field.py",
    "quality/force_closure_compiled.py",
    "sim/closing_compiled.py",
    "sim/closing_settings.py",
    "sim/contacts_compiled.py",
    "sim/gjk.py",
    "sim/mesh_distance.py",
    "sim/sdf_compiled.py",
)


def cache_root() -> Path:
    """Where handbench caches what it computes once: ``$XDG_CACHE_HOME/handbench``
    (``~/.cache/handbench``)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "handbench"


def numba_cache_dir() -> Path:
    """numba's on-disk cache of this source: ``~/.cache/handbench/numba/<hash of the kernels'
    files>``. numba invalidates a cached kernel only when its own file changes, not when a
    kernel it calls (in another file) does, so a cache shared across versions could run a
    stale callee; one directory per version of the kernels' sources cannot."""
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for rel in NUMBA_SOURCES:
        p = root / rel
        h.update(rel.encode())
        h.update(p.read_bytes() if p.is_file() else b"")
    return cache_root() / "numba" / h.hexdigest()[:16]


# before numba is imported anywhere: a user's own NUMBA_CACHE_DIR is respected
os.environ.setdefault("NUMBA_CACHE_DIR", str(numba_cache_dir()))
