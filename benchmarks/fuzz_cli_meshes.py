"""Fuzz the command line and the mesh importer; print outcome counts.

Every case runs ``app.cli.main`` in a forked child (so a segfault, a hang or a traceback is
seen as such), with stdout/stderr captured:

- flag cases (``tests/fuzz_cases.flag_cases``): all are user errors; wanted: exit 2, one
  line, no traceback. Reaching the simulation counts as "accepted silently" (the child's
  executors are stubbed so nothing is simulated);
- ``--help``/``-h`` of every subcommand: wanted exit 0;
- mesh cases (``tests/fuzz_cases.mesh_cases``): ``objects import`` then, if accepted, a quick
  ``evaluate`` (inline, a handful of hypotheses) of the imported object.

Usage (from the repository root)::

    python benchmarks/fuzz_cli_meshes.py                     # the code of this checkout
    python benchmarks/fuzz_cli_meshes.py --app-root /tmp/old # another checkout's app/
    python benchmarks/fuzz_cli_meshes.py --huge              # + a 200 MB sparse STL

Flags the tested checkout's ``objects import`` does not know (e.g. ``--allow-open`` before
it existed) are dropped from a mesh case, so the same files are tried both times.
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import math
import os
import resource
import signal
import sys
import tempfile
import time
import traceback
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
TIMEOUT_S = 20.0
EVAL_TIMEOUT_S = 180.0


class _Accepted(BaseException):
    """Raised in the child when a command reaches the simulation."""


def _load_cases():  # noqa: ANN202
    spec = importlib.util.spec_from_file_location("fuzz_cases", HERE / "tests" / "fuzz_cases.py")
    assert spec and spec.loader
    mod = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_cases"] = mod
    spec.loader.exec_module(mod)
    return mod


def _stub_simulation() -> None:
    """Make any command that gets as far as simulating raise _Accepted instead."""
    import concurrent.futures

    import app.runs.executors as ex

    def accepted(*_a: object, **_k: object) -> None:
        raise _Accepted

    ex.run_task = accepted  # type: ignore[assignment]  # InlineExecutor
    concurrent.futures.ProcessPoolExecutor.submit = accepted  # type: ignore[method-assign]


def run_child(
    argv: list[str], timeout: float, env: dict[str, str] | None = None, stub: bool = False
) -> dict[str, object]:
    """Run ``main(argv)`` in a forked child. Returns code/out/err/status/rss_mb/seconds."""
    out_f = tempfile.TemporaryFile()
    err_f = tempfile.TemporaryFile()
    t0 = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # child
        code = 1
        try:
            os.setsid()
            fd = os.open(os.devnull, os.O_RDONLY)
            os.dup2(fd, 0)
            os.dup2(out_f.fileno(), 1)
            os.dup2(err_f.fileno(), 2)
            sys.stdout = io.TextIOWrapper(os.fdopen(1, "wb", closefd=False), write_through=True)
            sys.stderr = io.TextIOWrapper(os.fdopen(2, "wb", closefd=False), write_through=True)
            if env:
                os.environ.update(env)
            resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))
            if stub:
                _stub_simulation()
            from app.cli import main

            try:
                code = int(main(argv) or 0)
            except SystemExit as e:
                code = e.code if isinstance(e.code, int) else (0 if e.code is None else 2)
            except _Accepted:
                print("@@ACCEPTED@@")
                code = 0
            except BaseException:
                traceback.print_exc()
                code = 1
        finally:
            try:
                sys.stdout.flush()
                sys.stderr.flush()
            finally:
                os._exit(code)
    status = "done"
    deadline = t0 + timeout
    while True:
        wpid, wstatus, ru = os.wait4(pid, os.WNOHANG)
        if wpid:
            break
        if time.perf_counter() > deadline:
            os.killpg(pid, signal.SIGKILL)
            wpid, wstatus, ru = os.wait4(pid, 0)
            status = "hang"
            break
        time.sleep(0.02)
    code: int | None = None
    if status == "done":
        if os.WIFSIGNALED(wstatus):
            status = f"signal {os.WTERMSIG(wstatus)}"
        else:
            code = os.WEXITSTATUS(wstatus)
    out_f.seek(0)
    err_f.seek(0)
    out, err = out_f.read().decode(errors="replace"), err_f.read().decode(errors="replace")
    out_f.close()
    err_f.close()
    return {
        "code": code,
        "out": out,
        "err": err,
        "status": status,
        "rss_mb": ru.ru_maxrss / 1024,
        "seconds": time.perf_counter() - t0,
    }


def classify(r: dict[str, object]) -> str:
    """clean / multiline / traceback / hang / fatal / accepted / ok."""
    err = str(r["err"])
    if r["status"] == "hang":
        return "hang"
    if str(r["status"]).startswith("signal"):
        return "fatal"
    if "Traceback" in err:
        return "traceback"
    if "@@ACCEPTED@@" in str(r["out"]):
        return "accepted"
    if r["code"] == 0:
        return "ok"
    if r["code"] == 2:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        return "clean" if len(lines) == 1 else "multiline"
    return "traceback"  # any other exit code: an unhandled failure


def _raw_warning(err: str) -> bool:
    return "Warning:" in err and ".py:" in err


def run_flags(cases_mod, tmp: Path, verbose: bool) -> Counter[str]:  # noqa: ANN001
    counts: Counter[str] = Counter()
    for c in cases_mod.flag_cases(tmp / "flags"):
        r = run_child(list(c.argv), TIMEOUT_S, stub=True)
        k = classify(r)
        if k == "ok":
            k = "accepted"  # a bad command that exits 0 was accepted silently
        counts[k] += 1
        if verbose or k not in ("clean",):
            first = (str(r["err"]).strip().splitlines() or [""])[-1][:150]
            print(f"  flags  {k:<10} {c.name:<28} {first}", file=sys.stderr)
    return counts


def run_help(cases_mod) -> Counter[str]:  # noqa: ANN001
    counts: Counter[str] = Counter()
    for path in cases_mod.HELP_PATHS:
        for h in ("--help", "-h"):
            r = run_child([*path, h], TIMEOUT_S)
            ok = r["code"] == 0 and "Traceback" not in str(r["err"]) and str(r["out"]).strip()
            counts["ok" if ok else "broken"] += 1
            if not ok:
                print(f"  help   broken     {' '.join(path)} {h}", file=sys.stderr)
    return counts


def _import_flags() -> set[str]:
    r = run_child(["objects", "import", "--help"], TIMEOUT_S)
    return {w.strip("[],") for w in str(r["out"]).split() if w.startswith(("--", "[--"))}


def run_meshes(cases_mod, tmp: Path, verbose: bool, huge: bool) -> tuple[Counter[str], list[str]]:  # noqa: ANN001
    from app.model.objects import load_object

    known = _import_flags()
    cases = cases_mod.mesh_cases(tmp / "meshes")
    if huge:
        d = tmp / "meshes" / "huge_0"
        d.mkdir(parents=True)
        p = cases_mod.huge_sparse_stl(d / "huge.stl")
        cases.append(cases_mod.MeshCase("huge_0", "huge", p, "coffee_can", ()))
    user = tmp / "user_objects"
    user.mkdir()
    env = {"HANDBENCH_USER_OBJECTS": str(user)}
    counts: Counter[str] = Counter()
    notes: list[str] = []
    for i, c in enumerate(cases):
        extra: list[str] = []
        it = iter(c.extra)
        for f in it:
            takes_value = f in ("--units", "--up", "--rotate")
            v = next(it) if takes_value else None
            if f in known:
                extra += [f] + ([v] if v is not None else [])
        key = f"case{i:03d}"
        argv = ["objects", "import", str(c.path), "--like", c.like, "--key", key]
        argv += ["--save-to", str(user), "--no-palm-stages", *extra]
        r = run_child(argv, 120.0 if c.family == "huge" else TIMEOUT_S, env)
        k = classify(r)
        if _raw_warning(str(r["err"])):
            counts["raw python warnings (cases)"] += 1
        if c.family == "huge":
            notes.append(
                f"huge 200 MB sparse STL: {k}, peak RSS {r['rss_mb']:.0f} MB, "
                f"{r['seconds']:.1f} s: {str(r['err']).strip()[:160]}"
            )
        if k == "ok":
            n_gh = load_object(c.like).spec.setup.n_gh
            stride = str(math.ceil(n_gh / 3))
            ev = ["evaluate", "--cmc", "0", "--mcp", "45", "--object", key, "--gh-stride"]
            ev += [stride, "--executor", "inline", "--store", str(tmp / "eval.sqlite")]
            e = run_child(ev, EVAL_TIMEOUT_S, env)
            ek = classify(e)
            k = {
                "ok": "accepted, evaluated",
                "clean": "accepted, evaluation refused (exit 2)",
                "fatal": "accepted, fatal evaluation",
                "hang": "accepted, evaluation timed out",
            }.get(ek, f"accepted, evaluation {ek}")
            if ek != "ok" or verbose:
                tail = (str(e["err"]).strip().splitlines() or [""])[-1][:150]
                print(f"  mesh   {k:<40} {c.name:<26} {e['status']} {tail}", file=sys.stderr)
        elif k != "clean" or verbose:
            tail = (str(r["err"]).strip().splitlines() or [""])[-1][:150]
            print(f"  mesh   {k:<40} {c.name:<26} {tail}", file=sys.stderr)
        counts[k] += 1
    counts["cases"] = len(cases)
    return counts, notes


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--app-root", default=str(HERE), help="checkout whose app/ is tested")
    ap.add_argument("--only", choices=("flags", "meshes", "help"), help="run one part")
    ap.add_argument("--huge", action="store_true", help="add the 200 MB sparse STL case")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every case")
    a = ap.parse_args()
    sys.path.insert(0, str(Path(a.app_root).resolve()))
    os.environ["PYTHONPATH"] = str(Path(a.app_root).resolve())
    import warnings

    warnings.simplefilter("default")
    import app.cli  # noqa: F401  (import once in the parent: children fork from here)

    print(f"app: {Path(sys.modules['app'].__file__ or '').parent}")
    cases = _load_cases()
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        (tmp / "flags").mkdir()
        if a.only in (None, "help"):
            print("help:", dict(run_help(cases)))
        if a.only in (None, "flags"):
            fc = run_flags(cases, tmp, a.verbose)
            print(f"flags ({sum(fc.values())} cases):", dict(sorted(fc.items())))
        if a.only in (None, "meshes"):
            mc, notes = run_meshes(cases, tmp, a.verbose, a.huge)
            print(f"meshes ({mc.pop('cases')} cases):", dict(sorted(mc.items())))
            for n in notes:
                print(n)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
