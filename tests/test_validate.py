"""handbench validate: reading both table forms, rank agreement, and named errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from app.errors import TableError
from app.reports.validate import agreement, agreement_markdown, read_score_table

OBJS = ("small_marker", "plastic_pear", "washer", "chips_can", "coffee_can", "power_drill")
DESIGNS = [(c, m) for c in (0.0, 30.0) for m in (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)]


def _table(path: Path, values, *, pct: bool, summaries: bool = True, comment: str = "") -> Path:
    """A table of ``values[d][obj]`` S_GAS; FC = S_GAS + 5, C = S_GAS - 5."""
    sfx = "_pct" if pct else ""
    cols = ["cmc_deg", "mcp_deg"] + [f"{k}_{m}{sfx}" for k in OBJS for m in ("fc", "c", "sgas")]
    if summaries:
        cols += [f"{s}{sfx}" for s in ("pp_sgas", "cg_sgas", "total_sgas")]
    lines = [comment] if comment else []
    lines.append(",".join(cols))
    for d in DESIGNS:
        v = values[d]
        row = [f"{d[0]:g}", f"{d[1]:g}"]
        for k in OBJS:
            row += [f"{v[k] + 5:.2f}", f"{v[k] - 5:.2f}", f"{v[k]:.2f}"]
        if summaries:
            row += [f"{np.mean([v[k] for k in OBJS[:3]]):.4f}",
                    f"{np.mean([v[k] for k in OBJS[3:]]):.4f}",
                    f"{np.mean([v[k] for k in OBJS]):.4f}"]  # fmt: skip
        lines.append(",".join(row))
    path.write_text("\n".join(lines) + "\n")
    return path


def _values(seed: int, f=None):
    rng = np.random.default_rng(seed)
    f = f or (lambda c, m: 20 + c + m / 100)  # no ties among the 14 designs
    return {d: {k: float(f(*d) + i + rng.uniform(-0.01, 0.01)) for i, k in enumerate(OBJS)}
            for d in DESIGNS}  # fmt: skip


def test_identical_rankings_agree_fully(tmp_path: Path) -> None:
    ours = read_score_table(_table(tmp_path / "a.csv", _values(1), pct=True))
    ref = read_score_table(_table(tmp_path / "b.csv", _values(2), pct=False, comment="# pub"))
    ag = agreement(ours, ref)
    assert len(ag.common) == 14 and ag.only_ours == () and ag.only_ref == ()
    t = ag.get("total_sgas")
    assert t.spearman == pytest.approx(1.0) and t.kendall == pytest.approx(1.0)
    assert t.mad < 0.05
    assert t.best_ours is not None and t.best_ours[0] == (30.0, 90.0)
    assert t.baseline_rank_ours == (11, 14)
    assert t.baseline_rank_ours == t.baseline_rank_ref


def test_reversed_rankings_and_the_baseline_rank(tmp_path: Path) -> None:
    up = _values(1, lambda c, m: 10 + c + m / 100)
    down = _values(1, lambda c, m: 200 - c - m / 100)
    ag = agreement(read_score_table(_table(tmp_path / "a.csv", up, pct=True)),
                   read_score_table(_table(tmp_path / "b.csv", down, pct=True)))  # fmt: skip
    t = ag.get("total_sgas")
    assert t.spearman == pytest.approx(-1.0)
    # baseline 0/45: in `up`, 0/60, 0/75, 0/90 and the seven CMC 30 designs rank above it
    n_above = 10
    assert t.baseline_rank_ours == (n_above + 1, 14)
    assert t.baseline_rank_ref == (14 - n_above, 14)


def test_summaries_are_recomputed_when_absent(tmp_path: Path) -> None:
    v = _values(3)
    with_s = read_score_table(_table(tmp_path / "a.csv", v, pct=False))
    without = read_score_table(_table(tmp_path / "b.csv", v, pct=False, summaries=False))
    for s in ("pp_sgas", "cg_sgas", "total_sgas"):
        for d in DESIGNS:
            assert without.values[s][d] == pytest.approx(with_s.values[s][d], abs=0.01)


def test_designs_in_one_table_are_reported(tmp_path: Path) -> None:
    a = _table(tmp_path / "a.csv", _values(1), pct=True)
    lines = (tmp_path / "a.csv").read_text().splitlines()
    b = tmp_path / "b.csv"
    b.write_text("\n".join(lines[:-3]) + "\n")  # the reference lacks 30/60, 30/75, 30/90
    ag = agreement(read_score_table(b), read_score_table(a))
    assert ag.only_ref == ((30.0, 60.0), (30.0, 75.0), (30.0, 90.0))
    assert "designs only in the reference (3): 30/60, 30/75, 30/90" in agreement_markdown(ag)


def test_published_reference_reads(tmp_path: Path) -> None:
    ref = Path(__file__).resolve().parents[1] / "docs/reference/published_sgas_cmc0_cmc30.csv"
    t = read_score_table(ref)
    assert len(t.designs) == 14 and t.objects == OBJS
    assert t.values["total_sgas"][(30.0, 75.0)] == pytest.approx(47.43)
    assert math.isfinite(t.values["washer_fc"][(0.0, 0.0)])


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("mcp_deg,total_sgas\n45,3\n", "missing column.*cmc_deg"),
        ("cmc,mcp,foo\n0,45,1\n", "no S_GAS column"),
        ("cmc,mcp,total_sgas\n0,45,abc\n", "line 2: 'abc' is not a number"),
        ("cmc,mcp,total_sgas\n0,45,1\n0,45,2\n", "appears twice"),
        ("cmc,mcp,total_sgas\n", "no rows"),
        ("cmc,mcp,mug_sgas\n0,45,3\n", "grasp type of mug is unknown"),
    ],
)
def test_bad_tables_name_what_is_wrong(tmp_path: Path, text: str, match: str) -> None:
    p = tmp_path / "t.csv"
    p.write_text(text)
    with pytest.raises(TableError, match=match):
        read_score_table(p)


def test_no_common_design_is_an_error(tmp_path: Path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("cmc,mcp,total_sgas\n0,45,1\n0,60,2\n")
    b.write_text("cmc,mcp,total_sgas\n15,45,1\n")
    with pytest.raises(TableError, match="no design in common"):
        agreement(read_score_table(a), read_score_table(b))


def test_cli_prints_and_writes_pictures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a = _table(tmp_path / "a.csv", _values(1), pct=True)
    out = tmp_path / "out"
    assert main(["validate", str(a), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "| total_sgas | 14 |" in text and "median per-object Spearman" in text
    for name in ("agreement.md", "agreement.csv", "contour_pair.png", "lines_overlay.png"):
        assert (out / name).stat().st_size > 0
    assert main(["validate", str(tmp_path / "nope.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"handbench: error: {tmp_path / 'nope.csv'}: no such file"]
