"""Sweep tables and plots on a synthetic 28-DA table."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from app.model.design import CMC_GRID_DEG, MCP_GRID_DEG
from app.reports.plots import DPI, FIG_SIZE_IN, plot_bars, plot_contour, plot_lines
from app.reports.report import table_columns, write_table_csv, write_table_md

KEYS = ("small_marker", "plastic_pear", "washer", "chips_can", "coffee_can", "power_drill")
TYPES = {k: ("PP" if i < 3 else "CG") for i, k in enumerate(KEYS)}
NAMES = {k: k.replace("_", " ").capitalize() for k in KEYS}
N_GH = {k: 100 + 10 * i for i, k in enumerate(KEYS)}


def quadratic(c: np.ndarray | float, m: np.ndarray | float) -> np.ndarray:
    """A smooth score in (10, 80) % over the design range, no ties among the 28 DAs."""
    c, m = np.asarray(c, float), np.asarray(m, float)
    return 70.0 - 0.02 * (c - 21.0) ** 2 - 0.006 * (m - 52.0) ** 2 + 0.003 * c * m


def synthetic_rows() -> list[dict[str, float | None]]:
    """28 DA rows in shuffled order: the analytic function plus object offsets."""
    rows = []
    for c in CMC_GRID_DEG:
        for m in MCP_GRID_DEG:
            row: dict[str, float | None] = {"cmc_deg": c, "mcp_deg": m}
            s = {}
            for i, k in enumerate(KEYS):
                s[k] = float(np.clip(quadratic(c, m) + 4.0 * (i - 2.5), 0, 100))
                row[f"{k}_fc_pct"] = min(100.0, s[k] + 12.0)
                row[f"{k}_c_pct"] = s[k] - 6.0
                row[f"{k}_sgas_pct"] = s[k]
            row["pp_sgas_pct"] = float(np.mean([s[k] for k in KEYS[:3]]))
            row["cg_sgas_pct"] = float(np.mean([s[k] for k in KEYS[3:]]))
            row["total_sgas_pct"] = float(np.mean(list(s.values())))
            rows.append(row)
    order = np.random.default_rng(1).permutation(len(rows))
    return [rows[i] for i in order]


@pytest.fixture(scope="module")
def rows() -> list[dict[str, float | None]]:
    return synthetic_rows()


# ----------------------------------------------------------------------------- tables
def test_csv(tmp_path: Path, rows: list[dict[str, float | None]]) -> None:
    path = write_table_csv(rows, tmp_path / "t.csv", object_keys=KEYS)
    with path.open() as f:
        table = list(csv.reader(f))
    header, body = table[0], table[1:]
    assert header == table_columns(KEYS)
    assert header[:5] == ["cmc_deg", "mcp_deg", "small_marker_fc_pct", "small_marker_c_pct",
                          "small_marker_sgas_pct"]  # fmt: skip
    assert header[-3:] == ["pp_sgas_pct", "cg_sgas_pct", "total_sgas_pct"]
    assert len(header) == 2 + 3 * len(KEYS) + 3 and len(body) == 28
    keys = [(float(r[0]), float(r[1])) for r in body]
    assert keys == sorted(keys)
    by_key = {(float(r["cmc_deg"] or 0), float(r["mcp_deg"] or 0)): r for r in rows}
    for line in body:
        src = by_key[(float(line[0]), float(line[1]))]
        for col, cell in zip(header, line, strict=True):
            assert cell == f"{src[col]:.2f}"
            assert abs(float(cell) - float(src[col] or 0)) <= 0.005 + 1e-9
    # default object order = the rows' columns; None -> empty cell
    odd = [dict(rows[0], pp_sgas_pct=None)]
    write_table_csv(odd, tmp_path / "u.csv")
    with (tmp_path / "u.csv").open() as f:
        h, line = list(csv.reader(f))
    assert h == header and line[h.index("pp_sgas_pct")] == ""


def test_markdown(tmp_path: Path, rows: list[dict[str, float | None]]) -> None:
    text = write_table_md(rows, tmp_path / "t.md", NAMES, TYPES, N_GH).read_text()
    lines = [ln for ln in text.splitlines() if ln.startswith("|")]
    header, sep, sub, data = lines[0], lines[1], lines[2], lines[3:]
    assert "Small marker (PP, N_GH = 100)" in header and "Power drill (CG, N_GH = 150)" in header
    assert set(sep.replace("|", "").split()) == {"---:"}
    assert "**FC %**" in sub and "**total S_GAS %**" in sub
    assert len(data) == 28
    assert all(ln.count("|") == header.count("|") for ln in lines)
    best = max(rows, key=lambda r: r["total_sgas_pct"] or 0)
    bolded = [ln for ln in data if "**" in ln]
    assert len(bolded) == 1
    cells = [c.strip() for c in bolded[0].strip("|").split("|")]
    assert (float(cells[0]), float(cells[1])) == (best["cmc_deg"], best["mcp_deg"])
    assert cells[-1] == f"**{best['total_sgas_pct']:.1f}**"
    assert f"Best design: CMC {best['cmc_deg']:g}°, MCP {best['mcp_deg']:g}°" in text
    totals = sorted((r["total_sgas_pct"] or 0.0 for r in rows), reverse=True)
    base = next(r for r in rows if (r["cmc_deg"], r["mcp_deg"]) == (0.0, 45.0))
    rank = totals.index(base["total_sgas_pct"] or 0.0) + 1
    assert f"rank {rank} of 28" in text


# ----------------------------------------------------------------------------- design map
# ----------------------------------------------------------------------------- plots
def _check_png(path: Path) -> None:
    assert path.stat().st_size > 10_000
    img = imread(path)
    w, h = FIG_SIZE_IN
    assert img.shape[:2] == (round(h * DPI), round(w * DPI))
    assert img[..., :3].std() > 0.05  # not a blank canvas


def test_plots(tmp_path: Path, rows: list[dict[str, float | None]]) -> None:
    _check_png(plot_lines(rows, tmp_path / "lines.png"))
    _check_png(plot_contour(rows, tmp_path / "contour.png"))
    _check_png(plot_contour(rows, tmp_path / "c2.png", "washer_c_pct", current=(20.0, 33.0)))
    _check_png(plot_bars(rows, tmp_path / "bars.png", NAMES, N_GH))
    partial = [dict(r, pp_sgas_pct=None) for r in rows[:5]]  # scattered, some undefined
    _check_png(plot_contour(partial, tmp_path / "p.png", "pp_sgas_pct"))
    _check_png(plot_contour(partial, tmp_path / "p2.png"))
