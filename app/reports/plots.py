"""The sweep's plots (METHOD §7): lines, contour map, bars. PNG files, never a window.

Figures are built with ``matplotlib.figure.Figure`` and drawn by the Agg canvas directly;
pyplot (and its GUI backends) is never imported, so this works headless and from threads.
Every figure is ``FIG_SIZE_IN`` at ``DPI``: 1000 × 700 pixels.

Input rows: see :mod:`app.reports.report` (one flat dict per design alternative).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from numpy.typing import ArrayLike

from app.model.design import CMC_RANGE_DEG, MCP_RANGE_DEG
from app.reports.design_map import best_design, interpolate_map
from app.reports.report import Row, num, object_keys_of

FIG_SIZE_IN = (10.0, 7.0)
"""Figure size, inches."""
DPI = 100
"""Pixels per inch of the PNGs."""

_LABELS = {
    "total_sgas_pct": "total S_GAS (%)",
    "pp_sgas_pct": "pulp pinch S_GAS (%)",
    "cg_sgas_pct": "cylindrical grip S_GAS (%)",
}


def value_label(value: str) -> str:
    """Axis label of a row column, e.g. 'total S_GAS (%)', 'washer C (%)'."""
    if value in _LABELS:
        return _LABELS[value]
    for suffix, name in (("_sgas_pct", "S_GAS"), ("_fc_pct", "FC"), ("_c_pct", "C")):
        if value.endswith(suffix):
            return f"{value[: -len(suffix)]} {name} (%)"
    return value


def _figure() -> Figure:
    fig = Figure(figsize=FIG_SIZE_IN, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, format="png")
    return path


def png_bytes(fig: Figure) -> bytes:
    """The figure as PNG bytes (for the explorer)."""
    buf = io.BytesIO()
    fig.savefig(buf, dpi=DPI, format="png")
    return buf.getvalue()


def _columns(rows: Sequence[Row], value: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(cmc (N,), mcp (N,), values (N,))``; undefined values are NaN."""
    c = np.array([float(r["cmc_deg"]) for r in rows])
    m = np.array([float(r["mcp_deg"]) for r in rows])
    v = np.array([math.nan if (x := num(r.get(value))) is None else x for r in rows])
    return c, m, v


# ----------------------------------------------------------------------------- lines
def plot_lines(rows: Sequence[Row], path: str | Path, value: str = "total_sgas_pct") -> Path:
    """Total S_GAS % against the MCP angle, one line (with markers) per CMC angle."""
    c, m, v = _columns(rows, value)
    fig = _figure()
    ax = fig.add_subplot()
    for cmc in np.unique(c):
        sel = (c == cmc) & np.isfinite(v)
        if not sel.any():
            continue
        order = np.argsort(m[sel])
        ax.plot(m[sel][order], v[sel][order], marker="o", label=f"CMC = {cmc:g}°")
    ax.set_xlabel("thumb MCP axis angle m (°)")
    ax.set_ylabel(value_label(value))
    ax.set_title(f"{value_label(value)} against the MCP angle")
    ax.set_xlim(MCP_RANGE_DEG[0] - 3, MCP_RANGE_DEG[1] + 3)
    ax.set_xticks(np.unique(m))
    ax.grid(True, alpha=0.4)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(title="thumb CMC axis angle")
    return _save(fig, path)


# ----------------------------------------------------------------------------- contour
def draw_contour(
    ax: Axes,
    cmc_deg: ArrayLike,
    mcp_deg: ArrayLike,
    values: ArrayLike,
    *,
    label: str = "total S_GAS (%)",
    current: tuple[float, float] | None = None,
    step_deg: float = 1.0,
    smoothing: float = 0.0,
) -> None:
    """Draw the interpolated map into ``ax`` (reusable by the explorer).

    Filled contours of :func:`app.reports.design_map.interpolate_map` over (CMC, MCP) with a
    colourbar, the computed designs as dots, the best computed design as a labelled star,
    and ``current = (cmc_deg, mcp_deg)`` as a ring when given.

    Args:
        cmc_deg, mcp_deg, values: (N,) computed designs and their score (%; NaN ignored).
    """
    c, m, v = (np.asarray(a, dtype=float) for a in (cmc_deg, mcp_deg, values))
    fig = ax.get_figure()
    assert fig is not None
    if np.isfinite(v).any():
        cg, mg, Z = interpolate_map(c, m, v, step_deg, smoothing=smoothing)
        zmin, zmax = np.nanmin(Z), np.nanmax(Z)
        if zmax - zmin < 1e-6:
            zmin, zmax = zmin - 0.5, zmax + 0.5
        levels = MaxNLocator(nbins=20).tick_values(zmin, zmax)
        cs = ax.contourf(cg, mg, np.ma.masked_invalid(Z), levels=levels, cmap="viridis")
        ax.contour(cs, levels=levels[::4], colors="k", linewidths=0.4, alpha=0.5)
        fig.colorbar(cs, ax=ax, label=label)
        ok = np.isfinite(v)
        ax.scatter(c[ok], m[ok], s=18, c="white", edgecolors="k", linewidths=0.6, zorder=3,
                   clip_on=False, label="computed designs")  # fmt: skip
        bc, bm, bv = best_design(c, m, v)
        ax.scatter([bc], [bm], marker="*", s=360, c="crimson", edgecolors="k", zorder=4,
                   clip_on=False, label="best computed")  # fmt: skip
        right = bc > sum(CMC_RANGE_DEG) / 2  # keep the label inside the axes
        top = bm > sum(MCP_RANGE_DEG) / 2
        ax.annotate(
            f"best: CMC {bc:g}°, MCP {bm:g}°\n{bv:.1f} %",
            (bc, bm),
            xytext=(-10 if right else 10, -10 if top else 10),
            textcoords="offset points",
            ha="right" if right else "left",
            va="top" if top else "bottom",
            fontsize=9,
            bbox={"boxstyle": "round", "fc": "white", "alpha": 0.8},
            zorder=5,
        )
    else:
        ax.text(0.5, 0.5, "no computed design has a value", transform=ax.transAxes,
                ha="center")  # fmt: skip
    if current is not None:
        ax.scatter([current[0]], [current[1]], marker="o", s=160, facecolors="none",
                   edgecolors="deepskyblue", linewidths=2.5, zorder=6, clip_on=False,
                   label="current design")  # fmt: skip
    ax.set_xlim(*CMC_RANGE_DEG)
    ax.set_ylim(*MCP_RANGE_DEG)
    ax.set_xlabel("thumb CMC axis angle c (°)")
    ax.set_ylabel("thumb MCP axis angle m (°)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right", fontsize=8, framealpha=0.8)


def contour_figure(
    rows: Sequence[Row],
    value: str = "total_sgas_pct",
    *,
    current: tuple[float, float] | None = None,
    smoothing: float = 0.0,
) -> Figure:
    """The contour map of ``value`` over the rows as a figure (see :func:`draw_contour`)."""
    c, m, v = _columns(rows, value)
    fig = _figure()
    ax = fig.add_subplot()
    draw_contour(ax, c, m, v, label=value_label(value), current=current, smoothing=smoothing)
    ax.set_title(f"{value_label(value)} over the thumb design (spline on a 1° grid)")
    return fig


def plot_contour(
    rows: Sequence[Row],
    path: str | Path,
    value: str = "total_sgas_pct",
    *,
    current: tuple[float, float] | None = None,
    smoothing: float = 0.0,
) -> Path:
    """Write the contour map of ``value`` (a row column, default total S_GAS %) as PNG."""
    return _save(contour_figure(rows, value, current=current, smoothing=smoothing), path)


# ----------------------------------------------------------------------------- bars
def bar_stats(rows: Sequence[Row], key: str, metric: str) -> tuple[float, float]:
    """``(mean, sd)`` of ``<key>_<metric>`` across the DAs (sample sd, ddof = 1; 0 for one
    DA; NaN when no DA has a value)."""
    v = np.array([x for r in rows if (x := num(r.get(f"{key}_{metric}"))) is not None])
    if v.size == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0


def plot_bars(
    rows: Sequence[Row],
    path: str | Path,
    names: Mapping[str, str],
    n_gh: Mapping[str, int],
    object_keys: Sequence[str] | None = None,
) -> Path:
    """Per object, mean ± sd across the DAs of FC % and C % (grouped bars, error bars).

    Objects in ``object_keys`` order (default: the rows' column order); each tick label
    gives the display name and N_GH.
    """
    keys = list(object_keys) if object_keys is not None else object_keys_of(rows[0])
    fig = _figure()
    ax = fig.add_subplot()
    x = np.arange(len(keys), dtype=float)
    width = 0.38
    for i, (metric, label) in enumerate((("fc_pct", "FC"), ("c_pct", "C (correct type)"))):
        stats = np.array([bar_stats(rows, k, metric) for k in keys]).reshape(-1, 2)
        ax.bar(
            x + (i - 0.5) * width,
            np.nan_to_num(stats[:, 0]),
            width,
            yerr=np.nan_to_num(stats[:, 1]),
            capsize=4,
            label=f"{label} %",
        )
    ax.set_xticks(x, [f"{names.get(k, k)}\nN_GH = {n_gh.get(k, 0)}" for k in keys])
    ax.set_ylabel("grasps (% of N_GH), mean ± sd across DAs")
    ax.set_ylim(0, 105)
    ax.set_title(f"FC and correct grasps per object over {len(rows)} design alternatives")
    ax.grid(True, axis="y", alpha=0.4)
    ax.legend()
    return _save(fig, path)
