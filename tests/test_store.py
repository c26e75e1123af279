"""The SQLite results store: exact round trips, atomic batches, kill -9, foreign files."""

from __future__ import annotations

import math
import os
import pickle
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from app.errors import StoreError
from app.hashing import stable_hash
from app.model.contact_set import ContactSet
from app.quality.outcome import GraspOutcome
from app.runs.store import SCHEMA_VERSION, ResultStore, default_store_path, encode
from tests.utils import make_outcome

ROOT = Path(__file__).resolve().parents[1]
KEYS = ("design0", "object0", "settings0")


# ----------------------------------------------------------------------------- hashing
def test_stable_hash_is_canonical() -> None:
    h = stable_hash({"a": 1.0, "b": [1, 2], "c": {"x": 0.1}})
    assert len(h) == 16 and int(h, 16) >= 0
    assert h == stable_hash({"c": {"x": 0.1 + 1e-13}, "b": (1, 2), "a": np.float64(1.0)})
    assert stable_hash({"v": np.array([[0.5, -0.0]])}) == stable_hash({"v": [[0.5, 0.0]]})
    assert stable_hash({"a": 1.0}) != stable_hash({"a": 1.0 + 1e-6})
    with pytest.raises(TypeError):
        stable_hash({"s": {1, 2}})


def test_default_store_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HANDBENCH_STORE", str(tmp_path / "deep/er/r.sqlite"))
    p = default_store_path()
    assert p == tmp_path / "deep/er/r.sqlite" and p.parent.is_dir()
    monkeypatch.delenv("HANDBENCH_STORE")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_store_path() == tmp_path / "home/.cache/handbench/results.sqlite"


# ----------------------------------------------------------------------------- round trip
def test_round_trip_exact(tmp_path: Path) -> None:
    outs = {f"obj/r{i:02d}": make_outcome(i) for i in range(20)}
    outs["obj/empty"] = make_outcome(100, k=0)
    outs["obj/f32"] = make_outcome(101, k=5, dtype=np.float32)
    outs["obj/nan"] = GraspOutcome(
        np.zeros(15), ContactSet(), False, False, math.nan, ("x",), 3, {"t_ms": 1.5, "n": [1]}
    )
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.put_many(*KEYS, outs)
        got = store.get_many(*KEYS, [*outs, "obj/absent"])
    assert set(got) == set(outs)
    for gh, o in outs.items():
        assert got[gh].same_as(o), gh
    assert got["obj/f32"].contacts.p_object.dtype == np.float32
    assert got["obj/empty"].contacts.p_object.shape == (0, 3)
    assert len(got["obj/empty"].contacts.link) == 0
    c = got["obj/r03"].contacts
    assert c.links == outs["obj/r03"].contacts.links
    assert c.palmar.dtype == bool and c.link.dtype == object
    # reopen read-only: same data
    with ResultStore(tmp_path / "r.sqlite", readonly=True) as ro:
        assert ro.get("design0", "object0", "settings0", "obj/nan") is not None
        assert ro.count(*KEYS) == len(outs)
        with pytest.raises(StoreError, match="read-only"):
            ro.put_many(*KEYS, outs)
    # outcomes a pool worker encoded (and pickled) store the same rows
    encoded = {gh: pickle.loads(pickle.dumps(encode(o))) for gh, o in outs.items()}
    with ResultStore(tmp_path / "e.sqlite") as store:
        store.put_many(*KEYS, encoded)
        got_e = store.get_many(*KEYS, list(outs))
    for gh, o in outs.items():
        assert got_e[gh].same_as(o), gh


def test_put_twice_no_duplicates_and_summary(tmp_path: Path) -> None:
    outs = {f"g{i}": make_outcome(i) for i in range(50)}
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.put_many(*KEYS, outs)
        store.put_many(*KEYS, outs)
        store.put_many("design0", "object1", "settings0", dict(list(outs.items())[:10]))
        store.put_many("design0", "object1", "settings1", outs)  # other settings: separate
        assert store.count(*KEYS) == 50
        assert store.present_ids(*KEYS) == set(outs)
        n_fc = sum(o.is_fc for o in outs.values())
        n_c = sum(o.is_correct for o in outs.values())
        first10 = list(outs.values())[:10]
        assert store.summary("design0", "settings0") == {
            "object0": (50, n_fc, n_c),
            "object1": (10, sum(o.is_fc for o in first10), sum(o.is_correct for o in first10)),
        }
        assert store.summary("nope", "settings0") == {}
        with sqlite3.connect(tmp_path / "r.sqlite") as raw:
            assert raw.execute("SELECT COUNT(*) FROM outcomes").fetchone()[0] == 110


def test_metadata(tmp_path: Path) -> None:
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.put_design_meta("dk1", {"cmc_deg": 15.0, "mcp_deg": 60.0})
        store.put_design_meta("dk0", {"cmc_deg": 0.0, "mcp_deg": 45.0})
        store.put_design_meta("dk1", {"cmc_deg": 15.0, "mcp_deg": 60.0})
        store.put_object_meta("ok", {"key": "washer"})
        store.put_settings_meta("sk", {"mu": 0.4})
        assert store.designs() == [
            ("dk0", {"cmc_deg": 0.0, "mcp_deg": 45.0}),
            ("dk1", {"cmc_deg": 15.0, "mcp_deg": 60.0}),
        ]
        assert store.objects() == [("ok", {"key": "washer"})]
        assert store.settings() == [("sk", {"mu": 0.4})]
        store.check()


def test_transaction_is_atomic(tmp_path: Path) -> None:
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(RuntimeError), store.transaction():
            store.put_many(*KEYS, {"a": make_outcome(1)})
            store.put_many("design1", "object0", "settings0", {"a": make_outcome(1)})
            raise RuntimeError("worker died")
        assert store.count(*KEYS) == 0
        with store.transaction():
            store.put_many(*KEYS, {"a": make_outcome(1)})
            store.put_many("design1", "object0", "settings0", {"a": make_outcome(1)})
        assert store.count(*KEYS) == 1 and store.count("design1", "object0", "settings0") == 1


# ----------------------------------------------------------------------------- processes
WRITER = """
import sys, time
sys.path.insert(0, sys.argv[5])
from app.runs.store import ResultStore
from tests.utils import make_outcome
path, batch, n_batches, delay = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
with ResultStore(path) as store:
    have = store.present_ids("design0", "object0", "settings0")
    for b in range(n_batches):
        ids = [f"gh/{b:04d}/{i:03d}" for i in range(batch)]
        if have.issuperset(ids):
            continue
        store.put_many("design0", "object0", "settings0",
                       {gh: make_outcome(b * batch + i, k=3) for i, gh in enumerate(ids)})
        print(b, flush=True)
        time.sleep(delay)
"""

READER = """
import sys
from app.runs.store import ResultStore
path, batch, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
import time
t_end, last, n = time.monotonic() + seconds, 0, 0
with ResultStore(path) as store:
    while time.monotonic() < t_end:
        c = store.count("design0", "object0", "settings0")
        assert c % batch == 0 and c >= last, (c, last)
        last = c
        store.summary("design0", "settings0")
        store.get_many("design0", "object0", "settings0", [f"gh/0000/{i:03d}" for i in range(5)])
        n += 1
print(n, last)
"""


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


def _writer(path: Path, batch: int, n_batches: int, delay: float) -> subprocess.Popen[str]:
    args = [str(path), str(batch), str(n_batches), str(delay), str(ROOT)]
    return subprocess.Popen(
        [sys.executable, "-c", WRITER, *args],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.PIPE,
        text=True,
    )


@pytest.mark.subprocess
def test_kill_9_then_resume(tmp_path: Path) -> None:
    path, batch, n_batches = tmp_path / "r.sqlite", 40, 150
    for stop_after in (5, 17, 60):
        proc = _writer(path, batch, n_batches, delay=0.002)
        assert proc.stdout is not None
        for _ in range(stop_after):
            if not proc.stdout.readline():
                break
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        assert proc.returncode == -signal.SIGKILL
        with ResultStore(path) as store:
            n = store.count(*KEYS)
            store.check()
        assert n % batch == 0 and n >= stop_after * batch, n
        assert n < n_batches * batch
    proc = _writer(path, batch, n_batches, delay=0.0)
    proc.communicate(timeout=60)
    assert proc.returncode == 0
    expected = {f"gh/{b:04d}/{i:03d}" for b in range(n_batches) for i in range(batch)}
    with ResultStore(path) as store:
        assert store.count(*KEYS) == len(expected)
        assert store.present_ids(*KEYS) == expected
        got = store.get_many(*KEYS, ["gh/0007/003", "gh/0149/039"])
    assert got["gh/0007/003"].same_as(make_outcome(7 * batch + 3, k=3))
    assert got["gh/0149/039"].same_as(make_outcome(149 * batch + 39, k=3))
    with sqlite3.connect(path) as raw:
        assert raw.execute("SELECT COUNT(*) FROM outcomes").fetchone()[0] == len(expected)


@pytest.mark.subprocess
def test_concurrent_readers_while_writing(tmp_path: Path) -> None:
    path, batch = tmp_path / "r.sqlite", 25
    ResultStore(path).close()  # schema exists before the race
    writer = _writer(path, batch, 200, delay=0.0)
    reader = subprocess.Popen(
        [sys.executable, "-c", READER, str(path), str(batch), "1.5"],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    with ResultStore(path, readonly=True) as store:
        t_end = time.monotonic() + 1.0
        while time.monotonic() < t_end:
            assert store.count(*KEYS) % batch == 0
    out, err = reader.communicate(timeout=30)
    assert reader.returncode == 0, err
    assert int(out.split()[0]) > 0
    writer.communicate(timeout=60)
    assert writer.returncode == 0
    with ResultStore(path) as store:
        assert store.count(*KEYS) == 200 * batch


# ----------------------------------------------------------------------------- bad files
def _filled(path: Path, n: int = 400) -> Path:
    with ResultStore(path) as store:
        store.put_many(*KEYS, {f"g{i}": make_outcome(i, k=10) for i in range(n)})
    return path


def test_not_sqlite(tmp_path: Path) -> None:
    rnd = tmp_path / "random.bin"
    rnd.write_bytes(np.random.default_rng(0).bytes(5000))
    txt = tmp_path / "notes.txt"
    txt.write_text("hello, these are my notes\n")
    for p in (rnd, txt):
        with pytest.raises(StoreError, match=r"not a handbench results database \(not SQLite\)"):
            ResultStore(p)
        with pytest.raises(StoreError, match="--store"):
            ResultStore(p, readonly=True)
    assert txt.read_text() == "hello, these are my notes\n"  # untouched
    with pytest.raises(StoreError, match="folder"):
        ResultStore(tmp_path)
    with pytest.raises(StoreError, match="does not exist"):
        ResultStore(tmp_path / "missing.sqlite", readonly=True)


def test_foreign_sqlite(tmp_path: Path) -> None:
    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as raw:
        raw.execute("CREATE TABLE users (name TEXT)")
    with pytest.raises(StoreError, match=r"another application \(tables: users\)"):
        ResultStore(other)
    other2 = tmp_path / "other2.sqlite"
    with sqlite3.connect(other2) as raw:
        raw.execute("CREATE TABLE meta (key TEXT, value TEXT)")
        raw.execute("INSERT INTO meta VALUES ('application', 'photos')")
    with pytest.raises(StoreError, match="another application.*'photos'"):
        ResultStore(other2)


def test_newer_schema(tmp_path: Path) -> None:
    path = _filled(tmp_path / "r.sqlite", 3)
    with sqlite3.connect(path) as raw:
        raw.execute(
            "UPDATE meta SET value = ? WHERE key = 'schema_version'", (str(SCHEMA_VERSION + 1),)
        )
    with pytest.raises(StoreError, match="newer handbench"):
        ResultStore(path)


def test_corrupt(tmp_path: Path) -> None:
    good = _filled(tmp_path / "good.sqlite")
    data = good.read_bytes()
    truncated = tmp_path / "truncated.sqlite"
    truncated.write_bytes(data[: len(data) // 2])
    damaged = tmp_path / "damaged.sqlite"
    damaged.write_bytes(data[:100] + b"\xff" * 3000 + data[3100:])  # page 1 b-tree scrambled
    for p in (truncated, damaged):
        with pytest.raises(StoreError, match=r"corrupt|not a handbench") as info:
            with ResultStore(p) as store:  # may open; then the first read fails
                store.count(*KEYS)
                store.check()
        assert "--store" in str(info.value)
