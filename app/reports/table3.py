"""Table 3 of the brute-force comparison (METHOD §6): the best design per object and GQM,
the win counts, every scored grasp, and a picture of the most frequent winner's grasps."""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.gqm import GQM_NAMES
from app.reports.scene import render_scene
from app.runs.gqm_compare import ComparisonResult, Scored, Winner, win_counts
from app.sim.simulate import cached_kit


def _fmt(x: float) -> str:
    return f"{x:.4g}" if math.isfinite(x) else "nan"


def write_outputs(
    out: Path,
    scored: Sequence[Scored],
    winners: Sequence[Winner],
    designs: Sequence[ThumbDesign],
    n_gh: dict[str, int],
) -> list[Path]:
    """bruteforce_table.csv/.md, bruteforce_wins.csv and bruteforce_gqms.csv in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [
        out / n
        for n in (
            "bruteforce_table.csv",
            "bruteforce_table.md",
            "bruteforce_wins.csv",
            "bruteforce_gqms.csv",
        )
    ]
    with paths[0].open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["object", "gqm", "cmc_deg", "mcp_deg", "gh_id", "value", "correct", "reasons"])
        for x in winners:
            d = x.best.design
            w.writerow(
                [
                    x.object_name,
                    x.gqm,
                    d.cmc_deg,
                    d.mcp_deg,
                    x.best.gh_id,
                    _fmt(x.best.values[x.gqm]),
                    int(x.correct),
                    "; ".join(x.reasons),
                ]
            )
    names = list(dict.fromkeys(x.object_name for x in winners))
    cell = {(x.object_name, x.gqm): x for x in winners}
    lines = [
        "# Brute-force grasps: best design per GQM (METHOD §6, published Table 3 form)",
        "",
        "Cell: winning design `CMC/MCP` in degrees, its best value, and ✓ when that grasp "
        "meets the object's PP/CG correctness criteria (✗ otherwise).",
        "",
        "| GQM | " + " | ".join(f"{n} (N_GH {n_gh.get(n, 0)})" for n in names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for g in GQM_NAMES:
        cells = []
        for n in names:
            x = cell[(n, g)]
            d = x.best.design
            mark = "✓" if x.correct else "✗"
            cells.append(f"{d.cmc_deg:g}/{d.mcp_deg:g} ({_fmt(x.best.values[g])}) {mark}")
        lines.append(f"| {g} | " + " | ".join(cells) + " |")
    wins = win_counts(winners, designs)
    lines += [
        "",
        "## Wins per design",
        "",
        "| CMC (°) | MCP (°) | wins | correct wins |",
        "|---|---|---|---|",
    ]
    for r in sorted(wins, key=lambda r: -r["wins"]):
        if r["wins"]:
            lines.append(
                f"| {r['cmc_deg']:g} | {r['mcp_deg']:g} | {r['wins']} | {r['correct_wins']} |"
            )
    paths[1].write_text("\n".join(lines) + "\n")
    with paths[2].open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["cmc_deg", "mcp_deg", "wins", "correct_wins"])
        w.writeheader()
        w.writerows(wins)
    with paths[3].open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["object", "cmc_deg", "mcp_deg", "gh_id", "is_correct", *GQM_NAMES])
        for s in scored:
            w.writerow(
                [
                    s.object_name,
                    s.design.cmc_deg,
                    s.design.mcp_deg,
                    s.gh_id,
                    int(s.outcome.is_correct),
                    *(_fmt(s.values[g]) for g in GQM_NAMES),
                ]
            )
    return paths


def render_winners(path: Path, winners: Sequence[Winner], designs: Sequence[ThumbDesign]) -> Path:
    """One picture, a panel per object, of the most frequent winner's winning grasps."""
    import matplotlib.pyplot as plt

    wins = win_counts(winners, designs)
    top = max(wins, key=lambda r: r["wins"])
    design = next(d for d in designs if (d.cmc_deg, d.mcp_deg) == (top["cmc_deg"], top["mcp_deg"]))
    mine: dict[str, Winner] = {}
    for w in winners:
        if w.best.design == design and w.object_name not in mine:
            mine[w.object_name] = w
    hand = cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt).hand
    tiles = []
    for name, w in mine.items():
        gqms = ", ".join(x.gqm for x in winners if x.best is w.best)
        tile = path.with_name(f"{path.stem}_{name}.png")
        render_scene(
            tile,
            hand=hand,
            q=w.best.outcome.q_final_rad,
            T_object_palm=np.asarray(w.best.outcome.extra["T_object_palm"], float),
            obj=load_object(name),
            contacts=w.best.outcome.contacts,
            show_axes=False,
            title=f"{name}: {w.best.gh_id.split('/', 1)[1]} — best {gqms}",
            size=(700, 560),
        )
        tiles.append(tile)
    cols = min(3, len(tiles))
    rows = math.ceil(len(tiles) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(7 * cols, 5.6 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, tile in zip(axes.ravel(), tiles, strict=False):
        ax.imshow(plt.imread(tile))
    fig.suptitle(
        f"Winning brute-force grasps of the most frequent winner, "
        f"CMC {design.cmc_deg:g}°, MCP {design.mcp_deg:g}° ({top['wins']} wins)",
        fontsize=16,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    for tile in tiles:
        tile.unlink()
    return path


def write_comparison(
    result: ComparisonResult, designs: Sequence[ThumbDesign], out: Path, picture: bool = True
) -> list[Path]:
    """Every output of a comparison in ``out``: the tables, and the winners' picture."""
    paths = write_outputs(out, result.scored, result.winners, designs, result.n_gh)
    if picture and result.winners:
        paths.append(render_winners(out / "bruteforce_winners.png", result.winners, designs))
    return paths
