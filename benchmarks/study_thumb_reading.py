"""Agreement of a sweep's table.csv with the published S_GAS table (issue 11).

Usage: python benchmarks/study_thumb_reading.py out/X/table.csv [--published PATH] [--json]

Figures (the published CSV holds 14 designs: CMC 0 and 30 degrees, all MCP angles):
- Spearman and Kendall rank correlation of total S_GAS over the 14 published rows;
- Spearman rho per object (S_GAS) over the 14 rows and their median;
- our best design of the 28 and whether CMC + MCP lies on the published fringe [90, 105];
- the baseline (CMC 0, MCP 45) rank among our 28 (1 = best) and whether it is in the
  bottom half;
- mean absolute difference of total S_GAS over the 14 rows (percentage points).
Only reads the two tables; nothing here feeds back into a simulation.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np
from scipy import stats

OBJECTS = ("small_marker", "plastic_pear", "washer", "chips_can", "coffee_can", "power_drill")
SHORT = dict(zip(OBJECTS, ("marker", "pear", "washer", "chips", "coffee", "drill"), strict=True))
DEFAULT_PUBLISHED = Path("/work/shared/reference/published_sgas_cmc0_cmc30.csv")
BASELINE = (0.0, 45.0)
FRINGE = (90.0, 105.0)


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def _col(row: dict[str, str], name: str) -> float:
    """Our table names columns '<x>_pct'; the published one '<x>'."""
    return float(row[name + "_pct"] if name + "_pct" in row else row[name])


def agreement(ours_csv: Path, published_csv: Path = DEFAULT_PUBLISHED) -> dict:
    ours = {(float(r["cmc_deg"]), float(r["mcp_deg"])): r for r in _rows(ours_csv)}
    pub = {(float(r["cmc_deg"]), float(r["mcp_deg"])): r for r in _rows(published_csv)}
    keys = [k for k in pub if k in ours]
    out: dict = {"n_ours": len(ours), "n_common": len(keys)}
    o_tot = np.array([_col(ours[k], "total_sgas") for k in keys])
    p_tot = np.array([_col(pub[k], "total_sgas") for k in keys])
    out["spearman_total"] = float(stats.spearmanr(o_tot, p_tot).statistic)
    out["kendall_total"] = float(stats.kendalltau(o_tot, p_tot).statistic)
    per = {}
    for ob in OBJECTS:
        a = np.array([_col(ours[k], f"{ob}_sgas") for k in keys])
        b = np.array([_col(pub[k], f"{ob}_sgas") for k in keys])
        rho = stats.spearmanr(a, b).statistic if a.std() > 0 and b.std() > 0 else math.nan
        per[ob] = float(rho)
    out["spearman_per_object"] = per
    out["median_object_rho"] = float(np.nanmedian(list(per.values())))
    out["mad_total"] = float(np.mean(np.abs(o_tot - p_tot)))
    ranked = sorted(ours, key=lambda k: -_col(ours[k], "total_sgas"))
    best = ranked[0]
    out["best"] = {"cmc": best[0], "mcp": best[1], "total": _col(ours[best], "total_sgas")}
    out["best_on_fringe"] = FRINGE[0] <= best[0] + best[1] <= FRINGE[1]
    if BASELINE in ours:
        rank = ranked.index(BASELINE) + 1
        out["baseline_rank"] = rank
        out["baseline_total"] = _col(ours[BASELINE], "total_sgas")
        out["baseline_bottom_half"] = rank > len(ours) / 2
    by_c: dict[float, float] = {}
    for k in ours:
        by_c[k[0]] = max(by_c.get(k[0], -1.0), _col(ours[k], "total_sgas"))
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
    ours = {(float(r["cmc_deg"]), float(r["mcp_deg"])): r for r in _rows(ours_csv)}
    pub = {(float(r["cmc_deg"]), float(r["mcp_deg"])): r for r in _rows(published_csv)}
    cs = sorted({k[0] for k in ours})
    ms = sorted({k[1] for k in ours})
    out = []
    for name in (
        [f"{o}_sgas" for o in OBJECTS]
        + [f"{o}_fc" for o in OBJECTS[3:]]
        + [f"{o}_c" for o in OBJECTS[3:]]
        + ["total_sgas"]
    ):
        out.append(f"{name:18s} " + " ".join(f"{m:5g}" for m in ms))
        for src, tag in ((ours, "ours"), (pub, "pub")):
            for c in cs:
                if not any((c, m) in src for m in ms):
                    continue
                vals = [f"{_col(src[(c, m)], name):5.1f}" if (c, m) in src else "    ." for m in ms]
                out.append(f"  {tag:4s} c={c:<4g}       " + " ".join(vals))
    return "\n".join(out)


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
