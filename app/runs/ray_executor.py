"""Run sweep tasks on Ray: a local Ray instance or a Ray cluster (``--executor ray``).

The executor only moves work: each ``app.runs.tasks.Task`` runs ``app.runs.tasks.run_task``
in a Ray worker and its results come back to the driver, which stays the only writer of the SQLite
results store. A sweep on Ray therefore fills the same store, with the same keys and the same
rows, as one on the local process pool, and resumes the same way.

Where the workers get the code
------------------------------
- ``address`` None or ``"local"``: a new Ray instance on this machine (``num_cpus`` =
  ``workers``). Its workers run on this machine's Python and import ``app`` from the same
  installation as the driver; nothing is shipped.
- any other address (``HOST:PORT`` of a cluster's head, ``"auto"``, ``ray://HOST:PORT``): the
  driver ships a snapshot of the code and data it runs with -- ``app/``, ``hand_models/`` and
  ``objects/`` (and the saved imported objects of ``$HANDBENCH_USER_OBJECTS``, if set) -- as
  the job's ``runtime_env={"working_dir": ...}``. Ray unpacks it on every node and starts the
  workers inside it, so they run exactly the driver's hand model, objects and code even on
  nodes where handbench is not installed. The nodes still need the dependencies (numpy,
  pinocchio, python-fcl, trimesh, ...) and the same Python version: install handbench (or
  ``pip install -r`` its dependencies) on every node. Pass ``ship_code=False`` when every
  node already has an identical installation.

In flight and cancellation
--------------------------
At most ``2 ×`` (the cluster's CPUs) tasks are submitted at a time; results are yielded as they
finish (``ray.wait``). When ``cancel`` is set (or the consumer stops early) ``run`` returns at
once and submits nothing more; the tasks already submitted finish on the cluster and their
results are dropped. They are not ``ray.cancel``-ed: a cancel that crosses the task's own
completion aborts the driver in Ray's task manager ("Check failed: it !=
submissible_tasks_.end() Tried to complete task that was not pending", Ray 2.60; the race of
ray-project/ray#54798), which a clean-clone test run hit once.
A task whose worker process or node dies is resubmitted by Ray (``max_retries``); a task that
still fails stops the sweep with a ``HandbenchError``, and a rerun computes only what is
missing from the store.
"""

from __future__ import annotations

import os
import shutil
import socket
import tempfile
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from app.errors import HandbenchError, SettingsError, WorkerCrashError
from app.model.hand.data import data_root
from app.model.objects.spec import user_dir
from app.quality.outcome import GraspOutcome
from app.runs.executors import Executor
from app.runs.tasks import Task, run_task

#: How long to wait for the cluster's head to accept a TCP connection before giving up (s).
#: ray.init itself retries an unreachable address for minutes.
CONNECT_TIMEOUT_S = 5.0
#: How many times Ray resubmits a task whose worker process or node died.
MAX_RETRIES = 3
#: Seconds between checks of the cancel flag while waiting for results.
POLL_S = 0.2
#: Folder name, inside the shipped working_dir, of the saved imported objects.
_USER_OBJECTS = "user_objects"

Results = list[tuple[int, str, GraspOutcome]]


def _is_local(address: str | None) -> bool:
    return address is None or address.strip() in ("", "local")


def check_reachable(address: str, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Raise HandbenchError unless ``HOST:PORT`` (optionally ``ray://``) accepts a connection.

    ``"auto"`` (the cluster ``ray start`` started on this machine) is left to Ray.
    """
    addr = address.strip()
    if addr == "auto":
        return
    hostport = addr.split("://", 1)[1] if "://" in addr else addr
    host, sep, port_text = hostport.rpartition(":")
    if not sep or not host or not port_text.isdigit():
        raise SettingsError(
            f"Ray address {address!r}: expected HOST:PORT (e.g. 10.0.0.5:6379), "
            "ray://HOST:PORT, 'auto' or 'local'"
        )
    try:
        with socket.create_connection((host.strip("[]"), int(port_text)), timeout=timeout_s):
            pass
    except OSError as e:
        raise HandbenchError(
            f"cannot reach the Ray cluster at {address!r} ({e}); start its head with "
            "'ray start --head' and pass its address (HOST:6379), or use "
            "--executor local"
        ) from None


def ship_dir() -> Path:
    """A temporary folder holding the code and data the workers need (the working_dir)."""
    root = Path(tempfile.mkdtemp(prefix="handbench-ray-"))
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(Path(__file__).resolve().parents[1], root / "app", ignore=ignore)
    data = data_root()
    for name in ("hand_models", "objects"):
        shutil.copytree(data / name, root / name, ignore=ignore)
    users = user_dir()
    if users is not None and users.is_dir():
        shutil.copytree(users, root / _USER_OBJECTS, ignore=ignore)
    return root


class RayExecutor(Executor):
    """Runs sweep tasks on a local Ray instance or a Ray cluster (see the module docstring).

    address: None / "local" (start Ray on this machine), "HOST:PORT" of a running cluster's
    head, "auto" or "ray://HOST:PORT". workers: CPUs of a local instance (default: all);
    ignored for a cluster. ship_code: send app/, hand_models/, objects/ as the runtime_env
    working_dir (default: only for a cluster).
    """

    def __init__(
        self,
        address: str | None = None,
        workers: int | None = None,
        *,
        ship_code: bool | None = None,
    ) -> None:
        try:
            import ray
        except ImportError:
            raise SettingsError(
                "the Ray executor needs Ray: pip install 'handbench[ray]' "
                "(or choose --executor local)"
            ) from None
        self._ray: Any = ray
        self.address = None if _is_local(address) else (address or "").strip()
        if workers is not None and workers < 1:
            raise SettingsError(f"--workers must be at least 1, got {workers}")
        self.workers = workers
        self.ship_code = (self.address is not None) if ship_code is None else ship_code
        if self.address is not None:
            check_reachable(self.address)
        self._owns_ray = False
        self._ship: Path | None = None
        self._remote: Any = None

    # ------------------------------------------------------------------ connection
    def _connect(self) -> None:
        ray = self._ray
        if self._remote is None:
            self._remote = ray.remote(max_retries=MAX_RETRIES)(run_task)
        if ray.is_initialized():
            return  # somebody else (a test, a notebook) started Ray: use it, leave it
        kwargs: dict[str, Any] = {
            "include_dashboard": False,
            "log_to_driver": False,
            "ignore_reinit_error": True,
        }
        if self.address is None:
            kwargs["address"] = "local"  # a new instance, never a stray `ray start` cluster
            kwargs["num_cpus"] = self.workers or os.cpu_count() or 1
        else:
            kwargs["address"] = self.address
        if self.ship_code:
            self._ship = ship_dir()
            env: dict[str, Any] = {"working_dir": str(self._ship)}
            if (self._ship / _USER_OBJECTS).is_dir():
                # relative: resolved in the worker's cwd, the unpacked working_dir
                env["env_vars"] = {"HANDBENCH_USER_OBJECTS": _USER_OBJECTS}
            kwargs["runtime_env"] = env
        try:
            ray.init(**kwargs)
        except BaseException as e:
            self.close()  # remove the shipped folder
            if not isinstance(e, ConnectionError):
                raise
            raise HandbenchError(
                f"cannot connect to the Ray cluster at {self.address!r}: {e} (a cluster "
                "started with token authentication also needs RAY_AUTH_MODE=token here; "
                "see docs/cluster.md)"
            ) from None
        self._owns_ray = True

    def in_flight(self) -> int:
        """Tasks kept submitted at once: twice the cluster's CPUs."""
        cpus = int(self._ray.cluster_resources().get("CPU", 1))
        return max(2, 2 * cpus)

    # ------------------------------------------------------------------ Executor
    def run(  # type: ignore[override]
        self, tasks: Sequence[Task], cancel: threading.Event | None
    ) -> Iterator[tuple[Task, Results]]:
        queue = list(tasks)[::-1]
        if not queue or (cancel is not None and cancel.is_set()):
            return
        self._connect()
        ray = self._ray
        limit = self.in_flight()
        pending: dict[Any, Task] = {}
        # cancelled, failed, or the consumer stopped early: what was submitted finishes on the
        # cluster and is dropped with ``pending`` (never ray.cancel: see the module docstring)
        while queue or pending:
            while queue and len(pending) < limit:
                t = queue.pop()
                pending[self._remote.remote(t)] = t
            done, _ = ray.wait(list(pending), num_returns=1, timeout=POLL_S)
            if cancel is not None and cancel.is_set():
                return
            for ref in done:
                task = pending.pop(ref)
                yield task, self._result(ref, task)

    def _result(self, ref: Any, task: Task) -> Results:
        ray = self._ray
        try:
            return ray.get(ref)
        except ray.exceptions.RayTaskError:
            raise  # an exception inside run_task: re-raised with the worker's traceback
        except ray.exceptions.WorkerCrashedError as e:
            # Ray retried the task and its worker died each time (segfault, out of memory)
            designs = ", ".join(f"CMC {d.cmc_deg:g}° MCP {d.mcp_deg:g}°" for d in task.designs[:3])
            gh = list(task.gh)
            raise WorkerCrashError(
                f"a Ray worker died while simulating object {task.object_name!r}, one of "
                f"hypotheses {gh[:5]}{'...' if len(gh) > 5 else ''} (indices), for {designs}; "
                "results finished before are kept in the store. If the object is an imported "
                "mesh, re-import it (objects import) or report the mesh"
            ) from e
        except ray.exceptions.RayError as e:
            raise HandbenchError(
                f"a Ray task failed ({type(e).__name__}: {e}); finished results are in the "
                "store, rerun the same command to compute the rest"
            ) from e

    def close(self) -> None:
        """Disconnect from Ray (stopping a local instance) if this executor started it."""
        if self._owns_ray:
            self._ray.shutdown()
            self._owns_ray = False
        if self._ship is not None:
            shutil.rmtree(self._ship, ignore_errors=True)
            self._ship = None
