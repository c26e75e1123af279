"""Fuzz: bad command lines and malformed meshes never crash (fast tier).

Property: every flag case exits 2 with one line and no traceback; every mesh case either
imports to a solid that a quick evaluation (a few hypotheses, inline) scores without error,
or ``objects import`` exits 2 with one line naming the file. Cases: ``tests/fuzz_cases.py``;
the same cases, forked (segfaults, hangs), with counts: ``benchmarks/fuzz_cli_meshes.py``.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from app.errors import MeshImportError
from app.model.design import ThumbDesign
from app.model.objects import import_object, unregister_object
from app.quality.settings import SimSettings
from app.runs.tasks import Task, run_task
from tests import fuzz_cases

with tempfile.TemporaryDirectory() as _d:
    N_FLAGS = len(fuzz_cases.flag_cases(Path(_d)))


def test_flag_table_is_large_enough() -> None:
    assert N_FLAGS >= 60


@pytest.mark.parametrize("i", range(N_FLAGS))
def test_bad_flags_exit_2_one_line(
    i: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    c = fuzz_cases.flag_cases(tmp_path)[i]
    try:
        code = main(list(c.argv))
    except SystemExit as e:
        code = e.code
    out, err = capsys.readouterr()
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, (c.name, code, err)
    assert len(lines) == 1 and lines[0].startswith("handbench: error:"), (c.name, err)
    assert "Traceback" not in err


@pytest.mark.parametrize("path", fuzz_cases.HELP_PATHS)
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_everywhere(
    path: tuple[str, ...], flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as e:
        main([*path, flag])
    assert e.value.code == 0
    assert "usage: handbench" in capsys.readouterr().out


@pytest.fixture(scope="module")
def mesh_cases(tmp_path_factory: pytest.TempPathFactory) -> list[fuzz_cases.MeshCase]:
    return fuzz_cases.mesh_cases(tmp_path_factory.mktemp("meshes"), seed=0)


#: Families whose first accepted case has been simulated (one per family keeps it fast).
_EVALUATED: set[str] = set()


def _quick_evaluation(key: str, family: str) -> None:
    """SDF sanity for every accepted case; one hypothesis of one design, inline, for the
    first accepted case of each family: it must run and give an outcome."""
    from app.model.objects import load_object

    o = load_object(key)
    far = o.mesh.bounds[1] + 50.0
    d = o.sdf(np.vstack([o.spec.target_object, far]))
    assert np.all(np.isfinite(d)) and abs(d[0]) < 1e-3 and d[1] > 0
    if family in _EVALUATED:
        return
    _EVALUATED.add(family)
    t = Task(key, (o.spec.setup.n_gh // 2,), (ThumbDesign(0.0, 45.0),), SimSettings())
    assert len(run_task(t)) == 1


N_MESH = sum(n for _, n in fuzz_cases.FAMILIES.values())


def test_mesh_case_count() -> None:
    assert N_MESH >= 150


@pytest.mark.parametrize("i", range(N_MESH))
def test_mesh_import_refuses_or_scores(
    i: int, mesh_cases: list[fuzz_cases.MeshCase], capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:  # fmt: skip
    c = mesh_cases[i]
    key = f"fuzz_{i:03d}"
    argv = ["objects", "import", str(c.path), "--like", c.like, "--key", key, *c.extra]
    argv += ["--save-to", str(tmp_path), "--no-palm-stages"]  # (the import checks only)
    code = main(argv)
    _, err = capsys.readouterr()
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert all(ln.startswith(("handbench: error:", "handbench: warning:")) for ln in lines)
    assert not any(".py:" in ln for ln in lines), err  # no raw Python warnings
    if code == 2:
        errors = [ln for ln in lines if ln.startswith("handbench: error:")]
        assert len(errors) == 1 and c.path.name in errors[0], err
        return
    assert code == 0, (c.name, err)
    # accepted: a closed solid that a quick evaluation scores
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        o = import_object(c.path, like=c.like, key=key, units=_units(c.extra),
                          allow_open="--allow-open" in c.extra)  # fmt: skip
    try:
        assert o.mesh.is_watertight and o.mesh.volume > 0
        _quick_evaluation(key, c.family)
    finally:
        unregister_object(key)


def _units(extra: tuple[str, ...]) -> str | None:
    return extra[extra.index("--units") + 1] if "--units" in extra else None


def test_huge_file_refused_early(tmp_path: Path) -> None:
    import resource

    p = fuzz_cases.huge_sparse_stl(tmp_path / "huge.stl")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(MeshImportError, match="MB"):
        import_object(p, like="coffee_can", register=False)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # kB
