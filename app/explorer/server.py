"""Start the explorer: one viser server, one ``Session`` per browser tab.

``serve()`` blocks (the ``handbench serve`` command); ``ExplorerServer`` runs in the
background for tests and the screenshot command.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import viser

from app.explorer.live_score import DEBOUNCE_S
from app.explorer.session import ExplorerContext, Session, warm_up
from app.model.objects import OBJECT_KEYS, load_object
from app.runs.executors import Executor, InlineExecutor, LocalExecutor
from app.runs.store import ResultStore, default_store_path
from app.sim.resident import drop_hand_caches, load_engine

OBJECTS_ENV = "HANDBENCH_EXPLORER_OBJECTS"
"""Comma list of object keys for the S_GAS panel and the map (default: all six)."""
#: How much lower the S_GAS workers' CPU priority is than the server's (``os.nice``).
WORKER_NICE = 10
WORKERS_ENV = "HANDBENCH_EXPLORER_WORKERS"
"""Processes for the S_GAS computation; 0 runs it in a thread of the server."""
SESSION_JOIN_S = 60.0
"""How long a tab's disconnect waits for its threads (a running S_GAS task, the first scene)
to end before the server releases memory."""


class _SharedLocalExecutor(LocalExecutor):
    """A process pool shared by the tabs (pool creation guarded against a race); closing
    it ends its workers at once instead of waiting for their running tasks."""

    def __init__(self, workers: int | None = None, warm_objects: Sequence[str] = ()) -> None:
        super().__init__(workers, warm_objects)
        self._create_lock = threading.Lock()

    def _get_pool(self) -> ProcessPoolExecutor:
        with self._create_lock:
            if self._pool is None:
                # workers leave Ctrl-C to the server (which then stops them: no traceback per
                # worker in the terminal) and run at a lower priority, so that the server (the
                # page's input, the panel's updates) is not starved while they use every core
                self._pool = self._new_pool(ignore_sigint=True, nice=WORKER_NICE)
            return self._pool

    def worker_pids(self) -> list[int]:
        """Process ids of the pool's workers (none before the first computation)."""
        pool = self._pool
        procs = getattr(pool, "_processes", None) or {}
        return [p.pid for p in procs.values() if p.pid is not None]

    def close(self) -> None:
        with self._create_lock:
            pool, self._pool = self._pool, None
        if pool is None:
            return
        procs = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:  # a task may run for seconds: do not wait for it
            proc.terminate()
        for proc in procs:
            proc.join(timeout=5.0)


def _objects_from_env() -> tuple[str, ...]:
    env = os.environ.get(OBJECTS_ENV, "").strip()
    return tuple(k.strip() for k in env.split(",") if k.strip()) if env else OBJECT_KEYS


def release_memory() -> None:
    """Hand freed heap back to the OS (glibc ``malloc_trim``; a no-op elsewhere).

    A tab's numpy and mesh buffers are freed when it closes, but glibc keeps freed pages in
    the arenas of the threads that used them (viser runs callbacks on a thread pool), so the
    server's RSS would stay at its peak without this."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


M_TRIM_THRESHOLD = -1
"""glibc's ``mallopt`` parameter number of the trim threshold (malloc.h)."""


def tune_allocator(trim_threshold: int = 128 * 1024) -> None:
    """Let glibc return the free top of every thread's heap to the OS (a no-op elsewhere).

    glibc raises its trim threshold (up to 64 MB) each time a large block is freed, and the
    free top of a thread's heap below that threshold stays resident: ``malloc_trim`` releases
    free pages inside a heap, not the top of the heaps of threads other than the main one.
    Tabs compute in viser's callback threads and their own, so after every 8 tabs the server
    kept a few MB more. A fixed threshold (which also keeps glibc's default mmap threshold,
    128 KiB: larger blocks are mapped and unmapped directly) returns it. Called by
    ``serve``, for the process's lifetime."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").mallopt(M_TRIM_THRESHOLD, int(trim_threshold))
    except (OSError, AttributeError):
        pass


def warm_up_encoders() -> None:
    """Encode one tiny PNG and JPEG the way viser does, in the calling thread.

    The first image a session adds makes PIL import its format plugins. Tabs opening at once
    build their sessions in parallel threads of viser's pool, and their concurrent first
    imports deadlocked on Python's import locks: those sessions never finished (nor freed
    their memory, nor drew their map). Importing once, up front, takes the race away."""
    import numpy as np
    from PIL import Image

    Image.init()
    try:
        from viser._scene_api import _encode_image_binary  # noqa: PLC2701 - the same path
    except ImportError:  # a viser without it encodes elsewhere; PIL is initialised anyway
        return
    tiny = np.zeros((2, 2, 3), np.uint8)
    for fmt in ("png", "jpeg"):
        _encode_image_binary(tiny, fmt, jpeg_quality=None)  # type: ignore[arg-type]


ICONS = (
    viser.Icon.HAND_FINGER, viser.Icon.PLAYER_PLAY, viser.Icon.MAP, viser.Icon.SHARE,
    viser.Icon.POINTER, viser.Icon.REFRESH, viser.Icon.CAMERA, viser.Icon.UPLOAD,
)  # fmt: skip
"""The icons of the explorer's tabs and buttons (``tests/test_explorer_map.py`` checks the
list against the source)."""


def warm_up_icons() -> None:
    """Read the explorer's icons once. Viser reads an icon's SVG from its zip of 4,285 icons,
    parsing the whole zip directory (~3 MB of Python objects) per icon until its small cache
    has it; tabs opening at once did that in parallel, once per tab, for each icon."""
    try:
        from viser._icons import svg_from_icon  # noqa: PLC2701 - the cache viser reads
    except ImportError:  # a viser without it: nothing to warm
        return
    for icon in ICONS:
        svg_from_icon(icon)


def drop_simulation_caches(keep: Sequence[str] = ()) -> None:
    """Empty the per-process simulation caches that hold the tabs' hands, keep the warm engine
    of the objects ``keep`` (``app.sim.resident``), and return the freed heap to the OS.

    Every hand a tab builds (one per design change) has new link shapes, and the contact
    code caches each shape's surface samples and their k-d tree (``lru_cache`` of 512 shapes,
    held by the shape object): with 8 tabs opened and closed the server's RSS grew ~15 MB a
    round until those caches were full. The kits (``cached_kit``), the compiled engine's
    per-hand arrays and the arrays of objects outside ``keep`` go too. Called when the last
    tab closes; the next tab refills what it uses."""
    import gc

    drop_hand_caches(keep)
    gc.collect()
    release_memory()


def workers_from_env() -> int | None:
    env = os.environ.get(WORKERS_ENV, "").strip()
    return int(env) if env else None


class ExplorerServer:
    """The viser server and the sessions of the connected tabs.

    Once listening, the server loads the warm engine in a background thread (``preload``;
    ``engine_ready`` is set when done, and ``log`` gets an 'engine ready in X s' line), so
    the first tab does not wait for the compiled kernels, the objects' data and the code of
    its first scene. When the last tab closes (and its threads have ended), what the tabs
    built per hand is dropped and the warm engine is kept: the server returns to the level
    it had once ready."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 8080,
        store_path: str | Path | None = None,
        *,
        objects: Sequence[str] | None = None,
        workers: int | None = None,
        shots_dir: str | Path | None = None,
        debounce_s: float = DEBOUNCE_S,
        reference_dir: str | Path | None = None,
        preload: bool = True,
        log: Callable[[str], None] | None = None,
    ) -> None:
        warm_up_encoders()
        objs = tuple(objects) if objects else _objects_from_env()
        for k in objs:
            load_object(k)  # UnknownObjectError lists the valid keys
        workers = workers_from_env() if workers is None else workers
        self.executor: Executor = (
            InlineExecutor() if workers == 0 else _SharedLocalExecutor(workers, objs)
        )
        if isinstance(self.executor, LocalExecutor):
            # the workers load the objects and the engine while the first tab opens, so its
            # first S_GAS estimate does not wait for them
            self.executor.start()
        self.store = ResultStore(Path(store_path) if store_path else default_store_path())
        self.viser = viser.ViserServer(host=host, port=port, label="handbench", verbose=False)
        shown_host = "127.0.0.1" if host in ("0.0.0.0", "::") else host
        self.url = f"http://{shown_host}:{self.viser.get_port()}"
        self.ctx = ExplorerContext(
            store=self.store,
            objects=objs,
            executor=self.executor,
            shots_dir=Path(shots_dir) if shots_dir else Path("out") / "screenshots",
            url_base=self.url,
            server=self.viser,
            default_object="chips_can" if "chips_can" in objs else objs[0],
            debounce_s=debounce_s,
            reference_dir=Path(reference_dir) if reference_dir is not None else None,
        )
        self.sessions: dict[int, Session] = {}
        self._lock = threading.Lock()
        self.viser.on_client_connect(self._connect)
        self.viser.on_client_disconnect(self._disconnect)
        self.warm_keys: tuple[str, ...] = tuple(dict.fromkeys((self.ctx.default_object, *objs)))
        """Objects whose warm engine the server loads at start and keeps (``app.sim.resident``):
        the default object and those of the S_GAS panel and the map."""
        self.engine_ready = threading.Event()
        """Set once the warm engine is loaded (or its loading failed or was not asked for)."""
        self.engine_load_s: float | None = None
        self._log = log
        self._stopping = threading.Event()
        self._preload: threading.Thread | None = None
        if preload:  # the server is listening already: the page is served meanwhile
            self._preload = threading.Thread(
                target=self._load_engine, name="engine-preload", daemon=True
            )
            self._preload.start()
        else:
            self.engine_ready.set()

    def _load_engine(self) -> None:
        """Load the warm engine (compiled kernels, the objects' meshes, hypotheses, arrays and
        signed distances), then what a tab's first scene loads on first use (the icons, the
        quality checks, the map's drawing code and fonts: ``session.warm_up``), in the
        background, so that the first tab does not wait for it. A tab opened meanwhile works:
        it loads what it needs itself (numba's dispatchers and the caches are thread-safe; a
        value computed twice is computed equal)."""
        t0 = time.perf_counter()
        try:
            load_engine(self.warm_keys, cancel=self._stopping)
            if not self._stopping.is_set():
                warm_up_icons()
                warm_up(self.ctx)  # the first scene's other code and the map
        except Exception as e:  # noqa: BLE001 - the tabs load what they need themselves
            msg = f"engine preload failed ({type(e).__name__}: {e}); tabs load it on demand"
        else:
            dt = self.engine_load_s = time.perf_counter() - t0
            msg = f"engine ready in {dt:.1f} s ({', '.join(self.warm_keys)})"
        self._release(idle_only=True)  # the level a last tab closing returns to
        self.engine_ready.set()
        if self._log is not None and not self._stopping.is_set():
            self._log(msg)

    def _connect(self, client: viser.ClientHandle) -> None:
        s = Session(client, self.ctx)
        with self._lock:
            self.sessions[client.client_id] = s
        # viser runs the connect and disconnect callbacks on a thread pool, unordered: a tab
        # closed while its session was being built had its disconnect find no session. The
        # client is gone from viser's list by then, so look again now that it is registered.
        if client.client_id not in self.viser.get_clients():
            self._disconnect(client)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            s = self.sessions.pop(client.client_id, None)
        if s is not None:
            s.close()
            # what its threads still compute goes into the shared caches: release after them
            if not s.join(SESSION_JOIN_S):
                msg = f"a closed tab's threads still ran after {SESSION_JOIN_S:g} s"
                print(f"handbench explorer: {msg}; what they cache stays until the next release",
                      flush=True)  # fmt: skip
            del s
            self._release(idle_only=False)

    def _release(self, idle_only: bool) -> None:
        """Collect garbage and return freed heap to the OS; with no tab left, also drop what
        the tabs' hands left in the simulation caches (the warm engine stays). ``idle_only``:
        nothing at all while a tab is open."""
        import gc

        with self._lock:
            idle = not self.sessions
        if idle:
            drop_simulation_caches(self.warm_keys)
        elif not idle_only:
            gc.collect()  # sessions sit in reference cycles (handles <-> callbacks)
            release_memory()

    def wait_for_session(self, timeout: float = 30.0, count: int = 1) -> list[Session]:
        """Block until ``count`` tabs are connected and have drawn their first scene."""
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            with self._lock:
                ss = list(self.sessions.values())
            if len(ss) >= count and all(s.ready.is_set() for s in ss):
                return ss
            time.sleep(0.05)
        raise TimeoutError(f"{count} explorer tab(s) did not become ready in {timeout:g} s")

    def stop(self) -> None:
        """Close every session, the executor, the store and the server."""
        self._stopping.set()
        if self._preload is not None:  # stops after its current step
            self._preload.join(timeout=10.0)  # (a daemon: a cold numba compile is not awaited)
        with self._lock:
            ss = list(self.sessions.values())
            self.sessions.clear()
        for s in ss:
            s.close()
        self.viser.stop()
        self.executor.close()
        self.store.close()


def serve(
    host: str = "127.0.0.1",
    port: int = 8080,
    store_path: str | Path | None = None,
    *,
    objects: Sequence[str] | None = None,
    workers: int | None = None,
) -> None:
    """Run the explorer until Ctrl-C or SIGTERM; either stops everything it started (the
    sessions' workers, the process pool, the share tunnel, the server)."""
    tune_allocator()
    srv = ExplorerServer(
        host, port, store_path, objects=objects, workers=workers,
        log=lambda msg: print(msg, flush=True),
    )  # fmt: skip
    stop = threading.Event()

    def on_signal(signum: int, _frame: object) -> None:
        stop.set()

    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGTERM, signal.SIGINT)}
    print(f"handbench explorer: open {srv.url} in a browser (Ctrl-C stops)", flush=True)
    if host in ("0.0.0.0", "::"):
        print("listening on every interface: other machines use http://<this machine's IP>:"
              f"{srv.viser.get_port()}", flush=True)  # fmt: skip
    print(f"results store: {srv.store.path}", flush=True)
    try:
        stop.wait()
    finally:
        print("handbench explorer: stopping", flush=True)
        srv.stop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
