"""Sweep tables and plots on a synthetic 28-DA table; the design-map interpolation."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from app.design import CMC_GRID_DEG, MCP_GRID_DEG
from app.design_map import design_grid, interpolate_map
from app.plots import DPI, FIG_SIZE_IN, plot_bars, plot_contour, plot_lines
from app.report import table_columns, write_table_csv, write_table_md

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
def _grid_data() -> tuple[np.ndarray, np.ndarray]:
    C, M = np.meshgrid(CMC_GRID_DEG, MCP_GRID_DEG, indexing="ij")
    return C.ravel().astype(float), M.ravel().astype(float)


def test_design_grid_shape() -> None:
    cg, mg = design_grid(1.0)
    assert cg.shape == (46,) and mg.shape == (91,)
    assert cg[0] == 0 and cg[-1] == 45 and mg[-1] == 90
    c, m = _grid_data()
    cg, mg, Z = interpolate_map(c, m, quadratic(c, m))
    assert Z.shape == (91, 46) and cg.shape == (46,) and mg.shape == (91,)


def test_interpolate_grid_exact_and_smooth() -> None:
    c, m = _grid_data()
    cg, mg, Z = interpolate_map(c, m, quadratic(c, m))
    truth = quadratic(cg[None, :], mg[:, None])
    nodes = np.ix_(np.isin(mg, MCP_GRID_DEG), np.isin(cg, CMC_GRID_DEG))
    assert np.abs(Z[nodes] - truth[nodes]).max() < 1e-6
    assert np.abs(Z - truth).max() < 0.5  # a cubic spline reproduces a quadratic
    assert np.all(np.isfinite(Z)) and Z.min() >= 0 and Z.max() <= 100
    # a non-polynomial function: exact at nodes, close between them
    f = lambda c, m: 50 + 20 * np.sin(np.radians(2 * m)) * np.cos(np.radians(c))  # noqa: E731
    _, _, Z2 = interpolate_map(c, m, f(c, m))
    truth2 = f(cg[None, :], mg[:, None])
    assert np.abs(Z2[nodes] - truth2[nodes]).max() < 1e-6
    assert np.abs(Z2 - truth2).max() < 1.0
    # clipping and smoothing
    _, _, Z3 = interpolate_map(c, m, quadratic(c, m) + 40)
    assert Z3.max() == 100.0
    _, _, Zs = interpolate_map(c, m, quadratic(c, m), smoothing=5.0)
    assert np.abs(Zs - truth).max() < 5.0


def test_interpolate_fallbacks() -> None:
    rng = np.random.default_rng(3)
    # scattered designs: thin-plate spline, exact at the data, close inside their box
    cs = np.concatenate([[0, 45, 0, 45], rng.uniform(0, 45, 36)])
    ms = np.concatenate([[0, 0, 90, 90], rng.uniform(0, 90, 36)])
    cg, mg, Z = interpolate_map(cs, ms, quadratic(cs, ms))
    assert Z.shape == (91, 46) and np.all(np.isfinite(Z))
    assert np.abs(Z - quadratic(cg[None, :], mg[:, None])).max() < 3.0
    i, j = np.searchsorted(cg, 45.0), np.searchsorted(mg, 90.0)
    assert abs(Z[j, i] - quadratic(45, 90)) < 1e-6
    # a sub-range sweep: NaN outside the computed box, or only the box with extent="data"
    c, m = _grid_data()
    sub = c <= 15
    _, _, Zd = interpolate_map(c[sub], m[sub], quadratic(c[sub], m[sub]))
    assert np.all(np.isfinite(Zd[:, :16])) and np.all(np.isnan(Zd[:, 16:]))
    cg2, mg2, Z2 = interpolate_map(c[sub], m[sub], quadratic(c[sub], m[sub]), extent="data")
    assert cg2[-1] == 15 and Z2.shape == (91, 16) and np.all(np.isfinite(Z2))
    # two or three values on an axis: lower spline degree; one axis constant: 1-D spline
    sub3 = c <= 30
    _, _, Z3 = interpolate_map(c[sub3], m[sub3], quadratic(c[sub3], m[sub3]))
    assert np.abs(Z3[:, :31] - quadratic(cg[None, :31], mg[:, None])).max() < 1e-6
    one = c == 15
    _, _, Z1 = interpolate_map(c[one], m[one], quadratic(c[one], m[one]))
    assert np.isfinite(Z1).sum() == 91
    assert np.abs(Z1[:, 15] - quadratic(15.0, mg)).max() < 1e-6
    # a single design, duplicates averaged, NaN values ignored
    _, _, Zp = interpolate_map([15, 15, 30], [60, 60, 0], [40, 50, np.nan])
    assert np.nanmax(Zp) == 45 and np.isfinite(Zp).sum() == 1
    with pytest.raises(ValueError):
        interpolate_map([1.0], [2.0], [np.nan])


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
