"""The command line: angle lists, and bad input through ``app.cli.main`` (exit 2, a message
that says what is valid, no traceback). Error paths only: nothing here simulates a grasp."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from app.cli import main
from app.cli.flags import parse_angle_list
from app.errors import SettingsError
from app.model.objects import OBJECT_KEYS

FORMS = r"comma list .*start:stop:step"


# ----------------------------------------------------------------------------- parse_angle_list
@pytest.mark.parametrize(
    ("text", "want"),
    [
        ("0,15,30,45", [0.0, 15.0, 30.0, 45.0]),
        ("0, 15 ,30", [0.0, 15.0, 30.0]),  # spaces around items
        ("7.5", [7.5]),
        ("0:45:5", [float(v) for v in range(0, 46, 5)]),  # stop included
        ("0:90:15", [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0]),
        ("45:45:5", [45.0]),  # start == stop: one value
        ("0:10:3", [0.0, 3.0, 6.0, 9.0]),  # stop off the grid: not exceeded
        ("0:11:3", [0.0, 3.0, 6.0, 9.0]),
        ("10:20:2.5", [10.0, 12.5, 15.0, 17.5, 20.0]),
    ],
)
def test_parse_angle_list(text: str, want: list[float]) -> None:
    assert parse_angle_list(text, "cmc") == want


@pytest.mark.parametrize(
    "text",
    ["0:x:5", "a,b", "0:45", "0:45:5:1", "0:45:0", "0:45:-5", "45:0:5", "nan:45:5", "0;15"],
)
def test_parse_angle_list_bad_input_lists_the_forms(text: str) -> None:
    with pytest.raises(SettingsError, match=FORMS) as e:
        parse_angle_list(text, "mcp")
    assert "--mcp" in str(e.value) and repr(text) in str(e.value)


@pytest.mark.parametrize("text", ["0,,15", "0,15,", ",15"])
def test_parse_angle_list_empty_item_refused(text: str) -> None:
    with pytest.raises(SettingsError, match=r"item \d is empty"):
        parse_angle_list(text, "cmc")


def test_parse_angle_list_range_count_capped() -> None:
    with pytest.raises(SettingsError, match="at most 100000") as e:
        parse_angle_list("0:90:1e-9", "mcp")
    assert "step of at least" in str(e.value)
    assert len(parse_angle_list("0:99999:1", "mcp")) == 100_000  # the cap itself is allowed


@pytest.mark.parametrize("text", ["", ",", " , "])
def test_parse_angle_list_empty(text: str) -> None:
    with pytest.raises(SettingsError, match="--cmc is empty"):
        parse_angle_list(text, "cmc")


def test_parse_angle_list_infinite_bound() -> None:
    with pytest.raises(SettingsError):
        parse_angle_list("0:inf:5", "cmc")


def test_parse_angle_list_fractional_step_is_exact() -> None:
    assert parse_angle_list("0:0.3:0.1", "cmc") == [0.0, 0.1, 0.2, 0.3]


# ----------------------------------------------------------------------------- main()
def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _store(tmp_path: Path) -> list[str]:
    return ["--store", str(tmp_path / "results.sqlite")]


def _ray_sweep(tmp_path: Path) -> list[str]:
    """A one-design, one-object sweep on the Ray executor."""
    return [
        "sweep",
        "--executor",
        "ray",
        "--cmc",
        "0",
        "--mcp",
        "45",
        "--object",
        "washer",
        "--out",
        str(tmp_path / "out"),
        *_store(tmp_path),
    ]


def test_evaluate_nan_angle(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, out, err = _run(capsys, "evaluate", "--cmc", "nan", "--mcp", "45", *_store(tmp_path))
    assert code == 2
    assert "finite" in err and "Traceback" not in err
    assert out == ""


def test_evaluate_angle_out_of_range(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, _, err = _run(capsys, "evaluate", "--cmc", "50", "--mcp", "45", *_store(tmp_path))
    assert code == 2
    assert "50" in err and "[0, 45]" in err


def test_evaluate_unknown_object_lists_keys(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, _, err = _run(
        capsys, "evaluate", "--cmc", "0", "--mcp", "45", "--object", "banana", *_store(tmp_path)
    )
    assert code == 2
    assert "banana" in err
    assert all(k in err for k in OBJECT_KEYS)


def test_sweep_bad_range(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, out, err = _run(
        capsys, "sweep", "--cmc", "0:x:5", "--out", str(tmp_path / "out"), *_store(tmp_path)
    )
    assert code == 2
    assert "0:x:5" in err and "start:stop:step" in err
    assert out == ""
    assert not (tmp_path / "out").exists()  # rejected before anything is written


@pytest.mark.ray
def test_sweep_unreachable_ray_cluster(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    pytest.importorskip("ray", reason="Ray is not installed: pip install 'handbench[ray]'")
    code, _, err = _run(capsys, *_ray_sweep(tmp_path), "--address", "127.0.0.1:1")
    assert code == 2
    assert "127.0.0.1:1" in err and "Traceback" not in err


def test_import_missing_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    missing = tmp_path / "missing.stl"
    code, _, err = _run(capsys, "objects", "import", str(missing), "--like", "chips_can")
    assert code == 2
    assert "missing.stl" in err and "not found" in err


def test_objects_list(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "objects", "list")
    assert code == 0
    lines = out.splitlines()
    assert len(lines) == 6
    assert [ln.split()[0] for ln in lines] == list(OBJECT_KEYS)


def test_unknown_executor_is_rejected_by_argparse(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["sweep", "--executor", "spark"])
    assert e.value.code == 2
    assert "local" in capsys.readouterr().err


def test_ray_executor_without_ray(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError
    code, _, err = _run(capsys, *_ray_sweep(tmp_path))
    assert code == 2
    assert "pip install 'handbench[ray]'" in err
