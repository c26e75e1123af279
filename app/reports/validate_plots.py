"""Pictures of ``handbench validate``: our contour map beside the reference's, and the line
plots of both tables overlaid (one colour per CMC angle; ours solid, reference dashed)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from app.model.design import MCP_RANGE_DEG
from app.reports.plots import DPI, draw_contour, value_label
from app.reports.validate import Agreement, ScoreTable


def _arrays(t: ScoreTable, measure: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    c = np.array([d[0] for d in t.designs])
    m = np.array([d[1] for d in t.designs])
    v = np.array([t.values[measure].get(d, math.nan) for d in t.designs])
    return c, m, v


def plot_contour_pair(ag: Agreement, path: str | Path, measure: str = "total_sgas") -> Path:
    """Our contour map (left) beside the reference's (right), on a shared colour scale."""
    fig = Figure(figsize=(16.0, 6.5), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    label = value_label(f"{measure}_pct")
    for k, (t, who) in enumerate(((ag.ours, "ours"), (ag.ref, "reference"))):
        ax = fig.add_subplot(1, 2, k + 1)
        c, m, v = _arrays(t, measure)
        draw_contour(ax, c, m, v, label=label)
        ax.set_title(f"{who}: {label}\n{t.path.name} ({np.isfinite(v).sum()} designs)")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, format="png")
    return path


def plot_lines_overlay(ag: Agreement, path: str | Path, measure: str = "total_sgas") -> Path:
    """The measure against MCP, one colour per CMC angle: ours solid, the reference dashed."""
    fig = Figure(figsize=(10.0, 7.0), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    cmcs = sorted({d[0] for d in ag.ours.designs} | {d[0] for d in ag.ref.designs})
    colours = {c: f"C{i % 10}" for i, c in enumerate(cmcs)}
    for t, style, who in ((ag.ours, "-", "ours"), (ag.ref, "--", "reference")):
        c, m, v = _arrays(t, measure)
        for cmc in cmcs:
            sel = (c == cmc) & np.isfinite(v)
            if not sel.any():
                continue
            order = np.argsort(m[sel])
            ax.plot(m[sel][order], v[sel][order], style, marker="o" if style == "-" else "s",
                    color=colours[cmc], label=f"{who}, CMC {cmc:g}°")  # fmt: skip
    label = value_label(f"{measure}_pct")
    ax.set_xlabel("thumb MCP axis angle m (°)")
    ax.set_ylabel(label)
    a = ag.get(measure)
    rho = "–" if math.isnan(a.spearman) else f"{a.spearman:.2f}"
    ax.set_title(f"{label}: ours (solid) and reference (dashed); Spearman ρ {rho}, "
                 f"mean abs diff {a.mad:.1f} pts on {a.n} designs")  # fmt: skip
    ax.set_xlim(MCP_RANGE_DEG[0] - 3, MCP_RANGE_DEG[1] + 3)
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8, ncol=2)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, format="png")
    return path
