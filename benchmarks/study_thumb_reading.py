"""Agreement of a sweep's table.csv with the published S_GAS table (issue 11).

Usage: python benchmarks/study_thumb_reading.py out/X/table.csv [--published PATH] [--json]

Figures (the published CSV holds 14 designs: CMC 0 and 30 degrees, all MCP angles):
- Spearman and Kendall rank correlation of total S_GAS over the 14 published rows;
- Spearman rho per object (S_GAS) over the 14 rows and their median;
- our best design of the 28 and whether CMC + MCP lies on the published fringe [90, 105];
- the baseline (CMC 0, MCP 45) rank among our 28 (1 = best) and whether it is in the
  bottom half;
- mean absolute difference of total S_GAS over the 14 rows (percentage points).
Only reads the two tables (``app.reports.validate``, as ``handbench validate`` does);
nothing here feeds back into a simulation.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from app.reports.validate import ScoreTable, read_score_table
from app.reports.validate import agreement as table_agreement

OBJECTS = ("small_marker", "plastic_pear", "washer", "chips_can", "coffee_can", "power_drill")
SHORT = dict(zip(OBJECTS, ("marker", "pear", "washer", "chips", "coffee", "drill"), strict=True))
DEFAULT_PUBLISHED = (
    Path(__file__).resolve().parents[1] / "docs" / "reference" / "published_sgas_cmc0_cmc30.csv"
)
BASELINE = (0.0, 45.0)
FRINGE = (90.0, 105.0)


def agreement(ours_csv: Path, published_csv: Path = DEFAULT_PUBLISHED) -> dict:
    """The issue-11 figures: ``handbench validate``'s agreement (``app.reports.validate``)
    plus the fringe, bottom-half and best-per-CMC readings of the study."""
    ours = read_score_table(ours_csv)
    ag = table_agreement(ours, read_score_table(published_csv))
    total = ag.get("total_sgas")
    per = {ob: ag.get(f"{ob}_sgas").spearman for ob in OBJECTS}
    out: dict = {
        "n_ours": len(ours.designs),
        "n_common": len(ag.common),
        "spearman_total": total.spearman,
        "kendall_total": total.kendall,
        "spearman_per_object": per,
        "median_object_rho": float(np.nanmedian(list(per.values()))),
        "mad_total": total.mad,
    }
    assert total.best_ours is not None
    (bc, bm), bv = total.best_ours
    out["best"] = {"cmc": bc, "mcp": bm, "total": bv}
    out["best_on_fringe"] = FRINGE[0] <= bc + bm <= FRINGE[1]
    if total.baseline_rank_ours is not None:
        rank, n = total.baseline_rank_ours
        out["baseline_rank"] = rank
        out["baseline_total"] = ours.values["total_sgas"][BASELINE]
        out["baseline_bottom_half"] = rank > n / 2
    by_c: dict[float, float] = {}
    for (c, _), v in ours.values["total_sgas"].items():
        by_c[c] = max(by_c.get(c, -1.0), v)
    out["best_total_per_cmc"] = {f"{c:g}": v for c, v in sorted(by_c.items())}
    return out


def format_report(a: dict) -> str:
    per = " ".join(f"{SHORT[k]}={v:+.2f}" for k, v in a["spearman_per_object"].items())
    b = a["best"]
    lines = [
        f"rows: ours {a['n_ours']}, common with published {a['n_common']}",
        f"total S_GAS: Spearman {a['spearman_total']:+.3f}  Kendall {a['kendall_total']:+.3f}"
        f"  mean |diff| {a['mad_total']:.1f} pts",
        f"per object Spearman: {per}  median {a['median_object_rho']:+.2f}",
        f"best: {b['cmc']:g}/{b['mcp']:g} ({b['total']:.1f} %), "
        f"CMC+MCP={b['cmc'] + b['mcp']:g} on fringe: {a['best_on_fringe']}",
    ]
    if "baseline_rank" in a:
        lines.append(
            f"baseline 0/45: {a['baseline_total']:.1f} %, rank {a['baseline_rank']} of "
            f"{a['n_ours']}, bottom half: {a['baseline_bottom_half']}"
        )
    lines.append(
        "best total per CMC: "
        + ", ".join(f"{c}: {v:.1f}" for c, v in a["best_total_per_cmc"].items())
    )
    return "\n".join(lines)


def format_grids(ours_csv: Path, published_csv: Path = DEFAULT_PUBLISHED) -> str:
    """Per object and total: our S_GAS on the (CMC rows x MCP columns) grid, published below."""
    ours, pub = read_score_table(ours_csv), read_score_table(published_csv)
    cs = sorted({d[0] for d in ours.designs})
    ms = sorted({d[1] for d in ours.designs})
    out = []
    for name in (
        [f"{o}_sgas" for o in OBJECTS]
        + [f"{o}_fc" for o in OBJECTS[3:]]
        + [f"{o}_c" for o in OBJECTS[3:]]
        + ["total_sgas"]
    ):
        out.append(f"{name:18s} " + " ".join(f"{m:5g}" for m in ms))
        for src, tag in ((ours, "ours"), (pub, "pub")):
            out += _grid_rows(src, tag, name, cs, ms)
    return "\n".join(out)


def _grid_rows(src: ScoreTable, tag: str, name: str, cs: list, ms: list) -> list[str]:
    vals = src.values[name]
    rows = []
    for c in cs:
        if not any((c, m) in vals for m in ms):
            continue
        cells = [f"{vals[(c, m)]:5.1f}" if (c, m) in vals else "    ." for m in ms]
        rows.append(f"  {tag:4s} c={c:<4g}       " + " ".join(cells))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("table", type=Path, help="a sweep's table.csv")
    ap.add_argument("--published", type=Path, default=DEFAULT_PUBLISHED)
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    ap.add_argument("--grids", action="store_true", help="also print per-object grids")
    args = ap.parse_args()
    a = agreement(args.table, args.published)
    print(json.dumps(a, indent=1) if args.json else format_report(a))
    if args.grids:
        print(format_grids(args.table, args.published))


if __name__ == "__main__":
    main()
