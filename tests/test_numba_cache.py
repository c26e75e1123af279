"""numba's cache is one directory per version of the kernels' sources (``app.numba_cache_dir``):
numba re-checks only a kernel's own file, so a callee changed in another file would otherwise
run stale from the cache."""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

import app
from app.quality.warm import prune_stale_caches


def test_every_file_with_a_cached_kernel_is_hashed() -> None:
    root = Path(app.__file__).parent
    with_kernels = {
        str(p.relative_to(root))
        for p in root.rglob("*.py")
        if re.search(r"^@(numba\.)?njit\(.*cache=True", p.read_text(), re.MULTILINE)
    }
    assert with_kernels, "no kernels found: the scan is wrong"
    assert with_kernels <= set(app.NUMBA_SOURCES)


def test_cache_dir_follows_the_kernel_sources(tmp_path: Path, monkeypatch) -> None:  # noqa: ANN001
    src = tmp_path / "app"
    for rel in app.NUMBA_SOURCES:
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(f"# {rel}\n")
    (src / "__init__.py").write_text("")
    monkeypatch.setattr(app, "__file__", str(src / "__init__.py"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    a = app.numba_cache_dir()
    assert a == app.numba_cache_dir()
    assert a.parent == tmp_path / "cache" / "handbench" / "numba"
    (src / "sim/gjk.py").write_text("# a callee changed\n")
    assert app.numba_cache_dir() != a


def test_numba_uses_it_unless_the_user_set_one() -> None:
    from numba.core import config

    assert Path(config.CACHE_DIR) == Path(os.environ["NUMBA_CACHE_DIR"])  # type: ignore[attr-defined]


def test_prune_removes_only_old_caches_of_other_sources(tmp_path: Path) -> None:
    cur, old, recent = (tmp_path / n for n in ("cur", "old", "recent"))
    for d in (cur, old, recent):
        d.mkdir()
    week3 = time.time() - 21 * 86400
    os.utime(old, (week3, week3))
    os.utime(cur, (week3, week3))
    assert prune_stale_caches(cur) == [old]
    assert cur.is_dir() and recent.is_dir() and not old.exists()
