"""The sweep's tables (METHOD §7): CSV for machines, Markdown in the published layout.

Input rows are flat dicts, one per design alternative (DA), as ``DesignScore.to_row`` makes
them::

    cmc_deg, mcp_deg, <key>_fc_pct, <key>_c_pct, <key>_sgas_pct (per object, in order),
    pp_sgas_pct, cg_sgas_pct, total_sgas_pct

Percentages may be None (or NaN) when undefined (no object of a grasp type, or N_GH = 0);
they are written as an empty CSV cell and "–" in Markdown. Object keys are data: they come
from the ``object_keys`` argument or, by default, from the row's columns.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from app.model.design import BASELINE_DEG

Row = Mapping[str, Any]
"""One DA's flat row (see the module docstring)."""

METRICS = ("fc_pct", "c_pct", "sgas_pct")
"""Per-object columns, in table order: FC %, C %, S_GAS %."""
SUMMARY_COLUMNS = ("pp_sgas_pct", "cg_sgas_pct", "total_sgas_pct")
"""Columns after the objects."""


def object_keys_of(row: Row) -> list[str]:
    """Object keys in column order, read from a row's ``<key>_fc_pct`` columns."""
    suffix = "_fc_pct"
    return [c[: -len(suffix)] for c in row if c.endswith(suffix)]


def table_columns(object_keys: Sequence[str]) -> list[str]:
    """The table's column names, in order."""
    cols = ["cmc_deg", "mcp_deg"]
    for k in object_keys:
        cols += [f"{k}_{m}" for m in METRICS]
    return cols + list(SUMMARY_COLUMNS)


def num(x: Any) -> float | None:
    """A finite float, or None for None/NaN/inf."""
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def sorted_rows(rows: Sequence[Row]) -> list[Row]:
    """Rows sorted by (cmc_deg, mcp_deg)."""
    return sorted(rows, key=lambda r: (float(r["cmc_deg"]), float(r["mcp_deg"])))


def _keys(rows: Sequence[Row], object_keys: Sequence[str] | None) -> list[str]:
    if object_keys is not None:
        return list(object_keys)
    return object_keys_of(rows[0]) if rows else []


def write_table_csv(
    rows: Sequence[Row], path: str | Path, object_keys: Sequence[str] | None = None
) -> Path:
    """Write the per-DA table as CSV; returns the path.

    Header: :func:`table_columns` (objects in ``object_keys`` order, default the rows'
    column order). Rows sorted by (cmc_deg, mcp_deg); every number with 2 decimals; an
    undefined value is an empty cell.

    Raises:
        KeyError: a row lacks a column of the header.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    cols = table_columns(_keys(rows, object_keys))
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in sorted_rows(rows):
            w.writerow(["" if (x := num(r[c])) is None else f"{x:.2f}" for c in cols])
    return path


def _fmt(x: Any, digits: int = 1) -> str:
    v = num(x)
    return "–" if v is None else f"{v:.{digits}f}"


def _angle(x: Any) -> str:
    return f"{float(x):g}"


def rank_of(rows: Sequence[Row], cmc_deg: float, mcp_deg: float) -> tuple[int, int] | None:
    """``(rank, n)`` of a design by total S_GAS among the rows with a defined total
    (1 = best; ties share the better rank), or None when it is not among them."""
    scored = [r for r in rows if num(r.get("total_sgas_pct")) is not None]
    me = [
        r
        for r in scored
        if abs(float(r["cmc_deg"]) - cmc_deg) < 1e-9 and abs(float(r["mcp_deg"]) - mcp_deg) < 1e-9
    ]
    if not me:
        return None
    t = num(me[0]["total_sgas_pct"])
    assert t is not None
    better = sum(1 for r in scored if (num(r["total_sgas_pct"]) or 0.0) > t + 1e-12)
    return 1 + better, len(scored)


def write_table_md(
    rows: Sequence[Row],
    path: str | Path,
    names: Mapping[str, str],
    grasp_types: Mapping[str, str],
    n_gh: Mapping[str, int],
    object_keys: Sequence[str] | None = None,
) -> Path:
    """Write the per-DA table in the published layout as Markdown; returns the path.

    Layout: a header row naming each object group (display name, grasp type, N_GH), then a
    bold sub-header row (CMC°, MCP°, FC % / C % / S_GAS % per object, PP / CG / total
    S_GAS %), then one row per DA sorted by (CMC, MCP), values with 1 decimal, the best
    total S_GAS in bold (all of them on a tie). A footer names the best design and the rank
    of the baseline (CMC 0°, MCP 45°) among the DAs.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    keys = _keys(rows, object_keys)
    rows = sorted_rows(rows)

    group = ["", ""]
    sub = ["CMC°", "MCP°"]
    for k in keys:
        group += [f"{names.get(k, k)} ({grasp_types.get(k, '?')}, N_GH = {n_gh.get(k, 0)})", "", ""]
        sub += ["FC %", "C %", "S_GAS %"]
    group += ["By grasp type and total", "", ""]
    sub += ["PP S_GAS %", "CG S_GAS %", "total S_GAS %"]

    totals = [num(r.get("total_sgas_pct")) for r in rows]
    best = max((t for t in totals if t is not None), default=None)

    def line(cells: Sequence[str]) -> str:
        return "| " + " | ".join(cells) + " |"

    out = [
        f"# S_GAS per design alternative ({len(rows)} DAs)",
        "",
        line(group),
        line(["---:"] * len(group)),
        line([f"**{s}**" for s in sub]),
    ]
    for r, t in zip(rows, totals, strict=True):
        cells = [_angle(r["cmc_deg"]), _angle(r["mcp_deg"])]
        for k in keys:
            cells += [_fmt(r.get(f"{k}_{m}")) for m in METRICS]
        cells += [_fmt(r.get("pp_sgas_pct")), _fmt(r.get("cg_sgas_pct"))]
        total = _fmt(t)
        is_best = best is not None and t is not None and abs(t - best) < 1e-12
        cells.append(f"**{total}**" if is_best else total)
        out.append(line(cells))

    out.append("")
    if best is None:
        out.append("No design has a defined total S_GAS.")
    else:
        winners = [r for r, t in zip(rows, totals, strict=True) if t is not None and t == best]
        ds = ", ".join(f"CMC {_angle(r['cmc_deg'])}°, MCP {_angle(r['mcp_deg'])}°" for r in winners)
        out.append(f"Best design: {ds} (total S_GAS {best:.1f} %).")
        c0, m0 = BASELINE_DEG
        rank = rank_of(rows, c0, m0)
        base = f"Baseline (CMC {c0:g}°, MCP {m0:g}°)"
        if rank is None:
            out.append(f"{base}: not among the computed designs.")
        else:
            t0 = next(
                num(r["total_sgas_pct"])
                for r in rows
                if abs(float(r["cmc_deg"]) - c0) < 1e-9 and abs(float(r["mcp_deg"]) - m0) < 1e-9
            )
            out.append(f"{base}: total S_GAS {t0:.1f} %, rank {rank[0]} of {rank[1]}.")
    out.append(
        "FC % and C %: force-closure and correct-type grasps over the N_GH hypotheses; "
        "S_GAS = (C + 0.5 · NC) / N_GH; PP/CG: mean over the objects of that grasp type; "
        "total: mean over all objects; – = undefined."
    )
    path.write_text("\n".join(out) + "\n")
    return path
