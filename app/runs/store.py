"""The embedded results store: every grasp-hypothesis (GH) outcome, in one SQLite file.

A row is keyed by ``(design_key, object_key, settings_key, gh_id)``:

- ``design_key``: hash of the hand design (hand-model file content hash, cmc_deg, mcp_deg and
  any design option), built by the caller with :func:`stable_hash`;
- ``object_key``: hash of the object's definition (mesh and grasp set-up);
- ``settings_key``: hash of the simulation settings (``SimSettings.key()``);
- ``gh_id``: the stable id of the hypothesis, e.g. ``"chips_can/r07/d00/t03"``.

So a repeated or interrupted sweep asks the store which GHs are present and computes only
the rest; changing the hand file, an object or a setting changes a key and nothing stale is
reused.

Durability and concurrency
--------------------------
The database runs in WAL journal mode with ``synchronous=NORMAL``: a committed transaction
survives the process being killed (``kill -9``); only a power loss can drop the last few
commits, never corrupt the file. A batch written by :meth:`ResultStore.put_many` (or several
calls inside one :meth:`ResultStore.transaction`) lands whole or not at all.

Any number of processes and threads may read while one writes (WAL readers never block).
Writers queue on SQLite's lock (``busy_timeout``, default 60 s), so **writers should batch**:
one transaction per finished work unit (e.g. one object × a chunk of GHs × the designs of a
task), not one per row — a commit costs a WAL append, a row costs almost nothing.
One ``ResultStore`` may be shared by threads (calls are serialised by a lock); a process pool
must not share one: each process opens its own, or (as ``app.runs.sweep`` does) only the parent
writes.

Grasp quality measures
----------------------
The brute-force comparison (``app.runs.gqm_compare``) keeps each scored grasp's ten GQMs in a
second table, ``gqms``, keyed by ``(design_key, object_key, settings_key, gqm_key, gh_id)``
(``gqm_key``: hash of the GQM settings and the GQMs' code version), so a rerun scores only
the grasps it lacks. The table is optional: it is created on the first GQM write, a store
without it is still a valid schema-1 store (no GQMs yet), and an older handbench ignores it.

Errors
------
A path that is not a handbench results database — not SQLite at all, SQLite of another
application, a newer schema, or a corrupt file — raises :class:`~app.errors.StoreError`
with a message that says which and what to do, never a raw ``sqlite3`` traceback.
:meth:`ResultStore.check` runs SQLite's ``quick_check`` on demand. It reads the whole file
(measured: 0.06 s for a 105 MB store of 50 400 outcomes, warm page cache, against 0.6 ms to
open), so it is not done on every open; a damaged file is still caught on open or on the
first read that meets the damage.
"""

from __future__ import annotations

import json
import math
import os
import sqlite3
import threading
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from app.errors import StoreError
from app.model.contact_set import ContactSet
from app.quality.outcome import GraspOutcome

APPLICATION = "handbench"
"""Value of ``meta.application`` in every handbench results database."""
SCHEMA_VERSION = 1
"""Schema version this code writes and reads (``meta.schema_version``)."""
APPLICATION_ID = 0x48424E43
"""SQLite ``PRAGMA application_id`` of handbench stores ("HBNC"), a second identity mark."""
BUSY_TIMEOUT_S = 60.0
"""How long a call waits for another process's write lock before giving up (s)."""

_SQLITE_MAGIC = b"SQLite format 3\x00"
_MAX_VARS = 500  # ids per IN (...) query, well below SQLITE_MAX_VARIABLE_NUMBER
_HINT = "delete it or choose another --store path"

_TABLES = {"meta", "designs", "objects", "settings", "outcomes"}
_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (
    key   TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS designs (
    design_key TEXT PRIMARY KEY,
    meta       TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS objects (
    object_key TEXT PRIMARY KEY,
    meta       TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS settings (
    settings_key TEXT PRIMARY KEY,
    meta         TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS outcomes (
    design_key   TEXT NOT NULL,
    object_key   TEXT NOT NULL,
    settings_key TEXT NOT NULL,
    gh_id        TEXT NOT NULL,
    is_fc        INTEGER NOT NULL,
    is_correct   INTEGER NOT NULL,
    epsilon      REAL,              -- NULL encodes NaN (SQLite has no NaN)
    n_queries    INTEGER NOT NULL,
    q_final      BLOB NOT NULL,     -- float64 little-endian, (n_joints,)
    n_contacts   INTEGER NOT NULL,
    c_dtype      TEXT NOT NULL,     -- '<f4' or '<f8': dtype of points and normals
    c_points     BLOB NOT NULL,     -- (K, 3) row-major
    c_normals    BLOB NOT NULL,     -- (K, 3) row-major
    c_links      TEXT NOT NULL,     -- JSON list of K link names
    c_palmar     BLOB NOT NULL,     -- (K,) one byte per flag
    reasons      TEXT NOT NULL,     -- JSON list of strings
    extra        TEXT,              -- JSON object or NULL
    PRIMARY KEY (design_key, object_key, settings_key, gh_id)
);
"""


def default_store_path() -> Path:
    """``$HANDBENCH_STORE`` if set, else ``~/.cache/handbench/results.sqlite``.

    The parent folder is created.
    """
    env = os.environ.get("HANDBENCH_STORE")
    path = Path(env).expanduser() if env else Path.home() / ".cache/handbench/results.sqlite"
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def _contact_dtype(c: ContactSet) -> np.dtype:
    """float32 when points and normals both are, else float64 (no precision is ever lost)."""
    dts = {np.asarray(c.p_object).dtype, np.asarray(c.n_object).dtype}
    return np.dtype("<f4") if dts == {np.dtype(np.float32)} else np.dtype("<f8")


def _encode(o: GraspOutcome) -> tuple[Any, ...]:
    """The column values of ``o`` after the four keys (order of the ``outcomes`` table)."""
    c = o.contacts
    dt = _contact_dtype(c)
    k = len(c)
    return (
        int(o.is_fc),
        int(o.is_correct),
        None if math.isnan(o.epsilon) else o.epsilon,
        o.n_queries,
        o.q_final_rad.astype("<f8").tobytes(),
        k,
        dt.str,
        np.ascontiguousarray(c.p_object, dtype=dt).tobytes(),
        np.ascontiguousarray(c.n_object, dtype=dt).tobytes(),
        json.dumps([str(s) for s in c.link]),
        np.ascontiguousarray(c.palmar, dtype=bool).tobytes(),
        json.dumps(list(o.reasons)),
        json.dumps(o.extra) if o.extra else None,
    )


class EncodedOutcome:
    """An outcome already in the ``outcomes`` table's column layout (``encode``): pool
    workers send these, so that the parent (the store's only writer, sharing the cores with
    the workers) only inserts rows instead of unpickling arrays and encoding them."""

    __slots__ = ("row",)

    def __init__(self, row: tuple[Any, ...]) -> None:
        self.row = row
        """The column values after the four keys (``_encode``)."""

    def __reduce__(self) -> tuple[Any, ...]:
        return (EncodedOutcome, (self.row,))


#: What ``ResultStore.put_many`` takes: an outcome, or one already encoded.
StoredOutcome = GraspOutcome | EncodedOutcome


def encode(o: GraspOutcome) -> EncodedOutcome:
    """``o`` in the store's column layout (decoded by every read as the same outcome)."""
    return EncodedOutcome(_encode(o))


def _decode(row: Sequence[Any]) -> GraspOutcome:
    """Inverse of :func:`_encode` (``row`` = the same columns)."""
    is_fc, is_c, eps, nq, q, k, dts, pts, nrm, links, palmar, reasons, extra = row
    dt = np.dtype(dts)
    native = np.float32 if dt.itemsize == 4 else np.float64
    link = np.empty((k,), dtype=object)
    link[:] = json.loads(links)
    contacts = ContactSet(
        np.frombuffer(pts, dtype=dt).reshape(k, 3).astype(native),
        np.frombuffer(nrm, dtype=dt).reshape(k, 3).astype(native),
        link,
        np.frombuffer(palmar, dtype=bool).copy(),
    )
    return GraspOutcome(
        q_final_rad=np.frombuffer(q, dtype="<f8").astype(np.float64),
        contacts=contacts,
        is_fc=bool(is_fc),
        is_correct=bool(is_c),
        epsilon=math.nan if eps is None else float(eps),
        reasons=tuple(json.loads(reasons)),
        n_queries=int(nq),
        extra=json.loads(extra) if extra else {},
    )


_OUT_COLS = (
    "is_fc, is_correct, epsilon, n_queries, q_final, n_contacts, c_dtype, c_points, "
    "c_normals, c_links, c_palmar, reasons, extra"
)

#: The optional table of grasp quality measures (module docstring), created on first write.
_GQM_SCHEMA = """
CREATE TABLE IF NOT EXISTS gqms (
    design_key   TEXT NOT NULL,
    object_key   TEXT NOT NULL,
    settings_key TEXT NOT NULL,
    gqm_key      TEXT NOT NULL,
    gh_id        TEXT NOT NULL,
    gqm_values   TEXT NOT NULL,     -- JSON object: GQM name -> value (float repr: exact)
    PRIMARY KEY (design_key, object_key, settings_key, gqm_key, gh_id)
)
"""


# --------------------------------------------------------------------------- store
class ResultStore:
    """The results database at ``path`` (created with its parents if missing).

    Use as a context manager or call :meth:`close`. ``readonly=True`` never writes (the file
    must exist and be a handbench store). See the module docstring for concurrency.

    Raises:
        StoreError: the file is not SQLite, belongs to another application, has a newer
            schema, is corrupt, or cannot be opened.
    """

    def __init__(self, path: str | Path, *, readonly: bool = False) -> None:
        self.path = Path(path).expanduser()
        """Location of the database file."""
        self.readonly = readonly
        """True when opened read-only."""
        self._lock = threading.RLock()
        self._depth = 0  # nesting of transaction()
        self._conn: sqlite3.Connection | None = None
        self._sniff()
        try:
            self._conn = self._connect()
            self._init_schema()
        except sqlite3.Error as e:
            self.close()
            raise self._error(e) from None
        except StoreError:
            self.close()
            raise

    # ------------------------------------------------------------------ opening
    def _sniff(self) -> None:
        """Reject, before SQLite sees it, a path that is a folder or not an SQLite file."""
        p = self.path
        if p.is_dir():
            raise StoreError(f"{p} is a folder, not a handbench results database; {_HINT}")
        if not p.exists():
            if self.readonly:
                raise StoreError(f"{p} does not exist (no results stored there yet)")
            p.parent.mkdir(parents=True, exist_ok=True)
            return
        try:
            with p.open("rb") as f:
                head = f.read(len(_SQLITE_MAGIC))
        except OSError as e:
            raise StoreError(f"cannot read {p}: {e}") from None
        if head and head != _SQLITE_MAGIC:  # an empty file is a valid empty database
            raise StoreError(
                f"{p} is not a handbench results database (not SQLite): its first bytes are "
                f"{head[:16]!r}; {_HINT}"
            )

    def _connect(self) -> sqlite3.Connection:
        if self.readonly:
            uri = f"{self.path.resolve().as_uri()}?mode=ro"
            conn = sqlite3.connect(
                uri, uri=True, timeout=BUSY_TIMEOUT_S, isolation_level=None,
                check_same_thread=False,
            )  # fmt: skip
        else:
            conn = sqlite3.connect(
                self.path, timeout=BUSY_TIMEOUT_S, isolation_level=None, check_same_thread=False
            )
        conn.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT_S * 1000)}")
        if not self.readonly:
            mode = conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            if str(mode).lower() != "wal":
                raise StoreError(f"{self.path}: cannot switch to WAL journal mode (got {mode})")
        conn.execute("PRAGMA synchronous = NORMAL")
        return conn

    def _tables(self) -> set[str]:
        rows = self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")
        return {r[0] for r in rows if not str(r[0]).startswith("sqlite_")}

    def _init_schema(self) -> None:
        tables = self._tables()
        if not tables:
            if self.readonly:
                raise StoreError(f"{self.path} is an empty database, not a handbench store yet")
            with self.transaction():
                if not self._tables():  # another process may have created it meanwhile
                    for stmt in _SCHEMA.split(";"):
                        if stmt.strip():
                            self._db.execute(stmt)
                    self._db.executemany(
                        "INSERT OR IGNORE INTO meta (key, value) VALUES (?, ?)",
                        [("application", APPLICATION), ("schema_version", str(SCHEMA_VERSION))],
                    )
                    self._db.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            tables = self._tables()
        self._validate(tables)

    def _validate(self, tables: set[str]) -> None:
        p = self.path
        if "meta" not in tables:
            raise StoreError(
                f"{p} is an SQLite database of another application (tables: "
                f"{', '.join(sorted(tables))}), not a handbench results database; {_HINT}"
            )
        meta = dict(self._db.execute("SELECT key, value FROM meta").fetchall())
        app = meta.get("application")
        if app != APPLICATION:
            raise StoreError(
                f"{p} is an SQLite database of another application (meta.application = "
                f"{app!r}, expected {APPLICATION!r}), not a handbench results database; {_HINT}"
            )
        try:
            version = int(meta.get("schema_version", ""))
        except ValueError:
            raise StoreError(
                f"{p} has an unreadable schema_version {meta.get('schema_version')!r}; {_HINT}"
            ) from None
        if version > SCHEMA_VERSION:
            raise StoreError(
                f"{p} was written by a newer handbench (results schema {version}; this version "
                f"reads schema {SCHEMA_VERSION}): upgrade handbench, or choose another --store "
                "path"
            )
        if version < SCHEMA_VERSION:
            raise StoreError(
                f"{p} has an old results schema {version} (this version reads "
                f"{SCHEMA_VERSION}) that cannot be upgraded; {_HINT} (results will be "
                "recomputed)"
            )
        missing = _TABLES - tables
        if missing:
            raise StoreError(
                f"{p} is an incomplete handbench results database (missing tables: "
                f"{', '.join(sorted(missing))}); {_HINT}"
            )

    def _error(self, e: sqlite3.Error) -> StoreError:
        """A helpful StoreError for a sqlite3 error raised while using this store."""
        msg = str(e)
        low = msg.lower()
        if "file is not a database" in low or "file is encrypted" in low:
            return StoreError(
                f"{self.path} is not a handbench results database (not SQLite, or its header "
                f"is damaged): {msg}; {_HINT}"
            )
        if "malformed" in low or "corrupt" in low:
            return StoreError(
                f"{self.path} is corrupt ({msg}): {_HINT} (its results will be recomputed)"
            )
        if "locked" in low or "busy" in low:
            return StoreError(
                f"{self.path} stayed locked by another process for more than "
                f"{BUSY_TIMEOUT_S:g} s ({msg}); try again when the other sweep finishes"
            )
        if "readonly" in low or "read-only" in low:
            return StoreError(f"{self.path} is read-only ({msg})")
        if "unable to open" in low:
            return StoreError(f"cannot open {self.path} ({msg}); choose another --store path")
        return StoreError(f"{self.path}: database error: {msg}")

    @property
    def _db(self) -> sqlite3.Connection:
        if self._conn is None:
            raise StoreError(f"the results store {self.path} is closed")
        return self._conn

    @contextmanager
    def _guard(self) -> Iterator[sqlite3.Connection]:
        """Hold the lock and turn sqlite3 errors into StoreError."""
        with self._lock:
            try:
                yield self._db
            except sqlite3.Error as e:
                raise self._error(e) from None

    # ------------------------------------------------------------------ lifecycle
    def close(self) -> None:
        """Close the connection (idempotent)."""
        with self._lock:
            if self._conn is not None:
                self._conn.close()
                self._conn = None

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"ResultStore({str(self.path)!r}{', readonly=True' if self.readonly else ''})"

    @contextmanager
    def transaction(self) -> Iterator[None]:
        """Group writes into one atomic transaction (nestable; the outermost commits).

        Takes SQLite's write lock at once (``BEGIN IMMEDIATE``), so a batch never fails half
        way on a lock; on any exception the whole batch is rolled back.
        """
        with self._lock:
            if self._depth:
                self._depth += 1
                try:
                    yield
                finally:
                    self._depth -= 1
                return
            try:
                self._db.execute("BEGIN IMMEDIATE")
            except sqlite3.Error as e:
                raise self._error(e) from None
            self._depth = 1
            try:
                yield
            except BaseException:
                self._depth = 0
                if self._conn is not None and self._conn.in_transaction:
                    self._conn.rollback()
                raise
            self._depth = 0
            try:
                self._db.execute("COMMIT")
            except sqlite3.Error as e:
                if self._conn is not None and self._conn.in_transaction:
                    self._conn.rollback()
                raise self._error(e) from None

    def check(self) -> None:
        """Run SQLite's ``PRAGMA quick_check`` over the whole file.

        Reads every page (about 0.06 s per 100 MB, warm cache), so it is not done on open.

        Raises:
            StoreError: the file is corrupt.
        """
        with self._guard() as db:
            rows = [r[0] for r in db.execute("PRAGMA quick_check(5)")]
        if rows != ["ok"]:
            raise StoreError(f"{self.path} is corrupt ({'; '.join(rows)}): {_HINT}")

    # ------------------------------------------------------------------ outcomes
    def get_many(
        self, design_key: str, object_key: str, settings_key: str, gh_ids: Sequence[str]
    ) -> dict[str, GraspOutcome]:
        """The stored outcomes among ``gh_ids`` (absent ids are simply left out)."""
        out: dict[str, GraspOutcome] = {}
        ids = list(dict.fromkeys(gh_ids))
        with self._guard() as db:
            for i in range(0, len(ids), _MAX_VARS):
                chunk = ids[i : i + _MAX_VARS]
                rows = db.execute(
                    f"SELECT gh_id, {_OUT_COLS} FROM outcomes WHERE design_key = ? AND "
                    f"object_key = ? AND settings_key = ? AND gh_id IN "
                    f"({', '.join('?' * len(chunk))})",
                    (design_key, object_key, settings_key, *chunk),
                ).fetchall()
                for r in rows:
                    out[r[0]] = _decode(r[1:])
        return out

    def get(
        self, design_key: str, object_key: str, settings_key: str, gh_id: str
    ) -> GraspOutcome | None:
        """One stored outcome, or None."""
        return self.get_many(design_key, object_key, settings_key, [gh_id]).get(gh_id)

    def present_ids(self, design_key: str, object_key: str, settings_key: str) -> set[str]:
        """Ids of the GHs stored for this design, object and settings (no decoding)."""
        with self._guard() as db:
            rows = db.execute(
                "SELECT gh_id FROM outcomes WHERE design_key = ? AND object_key = ? AND "
                "settings_key = ?",
                (design_key, object_key, settings_key),
            )
            return {r[0] for r in rows}

    def put_many(
        self,
        design_key: str,
        object_key: str,
        settings_key: str,
        outcomes: Mapping[str, StoredOutcome],
    ) -> None:
        """Store ``outcomes`` (gh_id → outcome, or one already ``encode``d) in one
        transaction; existing rows are replaced.

        Atomic: all rows land or none (also when called inside :meth:`transaction`, the
        outer transaction decides).
        """
        self._writable()
        rows = [
            (
                design_key,
                object_key,
                settings_key,
                str(gh),
                *(o.row if isinstance(o, EncodedOutcome) else _encode(o)),
            )
            for gh, o in outcomes.items()
        ]
        with self.transaction(), self._guard() as db:
            db.executemany(
                f"INSERT OR REPLACE INTO outcomes (design_key, object_key, settings_key, gh_id, "
                f"{_OUT_COLS}) VALUES ({', '.join('?' * 17)})",
                rows,
            )

    def count(self, design_key: str, object_key: str, settings_key: str) -> int:
        """Number of outcomes stored for this design, object and settings."""
        with self._guard() as db:
            return int(
                db.execute(
                    "SELECT COUNT(*) FROM outcomes WHERE design_key = ? AND object_key = ? AND "
                    "settings_key = ?",
                    (design_key, object_key, settings_key),
                ).fetchone()[0]
            )

    def summary(self, design_key: str, settings_key: str) -> dict[str, tuple[int, int, int]]:
        """object_key → ``(n, n_fc, n_correct)`` over the stored outcomes of a design.

        One SQL aggregate (no contact decoding): the fast path of the design map.
        """
        with self._guard() as db:
            rows = db.execute(
                "SELECT object_key, COUNT(*), SUM(is_fc), SUM(is_correct) FROM outcomes "
                "WHERE design_key = ? AND settings_key = ? GROUP BY object_key",
                (design_key, settings_key),
            ).fetchall()
        return {r[0]: (int(r[1]), int(r[2] or 0), int(r[3] or 0)) for r in rows}

    # ------------------------------------------------------------------ GQMs
    _gqm_table_ready: bool = False  # set per instance once the gqms table is known to exist

    def _has_gqm_table(self, create: bool) -> bool:
        """Whether the ``gqms`` table exists; ``create`` makes it (writable stores only)."""
        if self._gqm_table_ready:
            return True
        with self._guard() as db:
            found = db.execute(
                "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'gqms'"
            ).fetchone()
        if found is None and create:
            self._writable()
            with self.transaction(), self._guard() as db:
                db.execute(_GQM_SCHEMA)
            found = (1,)
        self._gqm_table_ready = found is not None
        return self._gqm_table_ready

    def put_gqms(
        self,
        design_key: str,
        object_key: str,
        settings_key: str,
        gqm_key: str,
        values: Mapping[str, Mapping[str, float]],
    ) -> None:
        """Store the GQMs of grasps (gh_id → {GQM name → value}) in one transaction; existing
        rows are replaced. Values are kept exactly (NaN and ±inf included)."""
        self._writable()
        self._has_gqm_table(create=True)
        rows = [
            (
                design_key, object_key, settings_key, gqm_key, str(gh),
                json.dumps({str(k): float(v) for k, v in vals.items()}),
            )
            for gh, vals in values.items()
        ]  # fmt: skip
        with self.transaction(), self._guard() as db:
            db.executemany(
                "INSERT OR REPLACE INTO gqms (design_key, object_key, settings_key, gqm_key, "
                "gh_id, gqm_values) VALUES (?, ?, ?, ?, ?, ?)",
                rows,
            )

    def get_gqms(
        self,
        design_key: str,
        object_key: str,
        settings_key: str,
        gqm_key: str,
        gh_ids: Sequence[str],
    ) -> dict[str, dict[str, float]]:
        """The stored GQMs among ``gh_ids`` (gh_id → {GQM name → value}; absent ids left out)."""
        if not self._has_gqm_table(create=False):
            return {}
        out: dict[str, dict[str, float]] = {}
        ids = list(dict.fromkeys(gh_ids))
        with self._guard() as db:
            for i in range(0, len(ids), _MAX_VARS):
                chunk = ids[i : i + _MAX_VARS]
                rows = db.execute(
                    "SELECT gh_id, gqm_values FROM gqms WHERE design_key = ? AND object_key = ? "
                    f"AND settings_key = ? AND gqm_key = ? AND gh_id IN "
                    f"({', '.join('?' * len(chunk))})",
                    (design_key, object_key, settings_key, gqm_key, *chunk),
                ).fetchall()
                for gh, text in rows:
                    out[gh] = {str(k): float(v) for k, v in json.loads(text).items()}
        return out

    def count_gqms(self, gqm_key: str | None = None) -> int:
        """Number of stored GQM rows (of one ``gqm_key``, or all)."""
        if not self._has_gqm_table(create=False):
            return 0
        with self._guard() as db:
            if gqm_key is None:
                return int(db.execute("SELECT COUNT(*) FROM gqms").fetchone()[0])
            return int(
                db.execute("SELECT COUNT(*) FROM gqms WHERE gqm_key = ?", (gqm_key,)).fetchone()[0]
            )

    # ------------------------------------------------------------------ metadata
    def _writable(self) -> None:
        if self.readonly:
            raise StoreError(f"{self.path} was opened read-only")

    def _put_meta(self, table: str, col: str, key: str, meta: Mapping[str, Any]) -> None:
        self._writable()
        text = json.dumps(dict(meta), sort_keys=True)
        with self.transaction(), self._guard() as db:
            db.execute(f"INSERT OR REPLACE INTO {table} ({col}, meta) VALUES (?, ?)", (key, text))

    def _list_meta(self, table: str, col: str) -> list[tuple[str, dict[str, Any]]]:
        with self._guard() as db:
            rows = db.execute(f"SELECT {col}, meta FROM {table} ORDER BY {col}").fetchall()
        return [(r[0], json.loads(r[1])) for r in rows]

    def put_design_meta(self, design_key: str, meta: Mapping[str, Any]) -> None:
        """Describe a design key, e.g. ``{"cmc_deg": 15.0, "mcp_deg": 60.0, ...}``."""
        self._put_meta("designs", "design_key", design_key, meta)

    def put_object_meta(self, object_key: str, meta: Mapping[str, Any]) -> None:
        """Describe an object key, e.g. ``{"key": "chips_can"}``."""
        self._put_meta("objects", "object_key", object_key, meta)

    def put_settings_meta(self, settings_key: str, meta: Mapping[str, Any]) -> None:
        """Describe a settings key (the settings as a dict)."""
        self._put_meta("settings", "settings_key", settings_key, meta)

    def designs(self) -> list[tuple[str, dict[str, Any]]]:
        """Every described design: ``(design_key, meta)``, sorted by key."""
        return self._list_meta("designs", "design_key")

    def objects(self) -> list[tuple[str, dict[str, Any]]]:
        """Every described object: ``(object_key, meta)``, sorted by key."""
        return self._list_meta("objects", "object_key")

    def settings(self) -> list[tuple[str, dict[str, Any]]]:
        """Every described settings: ``(settings_key, meta)``, sorted by key."""
        return self._list_meta("settings", "settings_key")
