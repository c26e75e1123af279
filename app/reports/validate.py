"""Agreement of our score table with a reference table (``handbench validate``).

A table is one row per design: ``cmc_deg``/``mcp_deg`` (or ``cmc``/``mcp``) and, per object,
FC, C and S_GAS in percent as ``<key>_fc``, ``<key>_c``, ``<key>_sgas`` with or without the
``_pct`` suffix (our sweep writes the suffix, the published table does not), then
``pp_sgas``, ``cg_sgas`` and ``total_sgas`` (optional: recomputed from the objects' S_GAS
when absent and every object's grasp type is known). Lines starting with ``#`` are comments.

For every object's S_GAS and for PP, CG and total, on the designs both tables hold: Spearman
ρ and Kendall τ (rank agreement), the mean absolute difference, each table's best design
(over all of its own designs) and the baseline's rank in each table. Designs present in only
one table are listed, never silently dropped.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import kendalltau, spearmanr

from app.errors import TableError
from app.model.design import BASELINE_DEG
from app.model.objects import OBJECT_KEYS, load_object

SUMMARY = ("pp_sgas", "cg_sgas", "total_sgas")
"""The summary measures, after the objects."""
METRICS = ("fc", "c", "sgas")
"""Per-object columns (percent)."""
_ROUND = 6  # designs are matched on angles rounded to 1e-6 degrees

Design = tuple[float, float]
"""(cmc_deg, mcp_deg)."""


@dataclass(frozen=True)
class ScoreTable:
    """A score table read from CSV: measure name -> {design: value (NaN if empty)}."""

    path: Path
    """The file it was read from."""
    designs: tuple[Design, ...]
    """Its designs, in file order."""
    objects: tuple[str, ...]
    """Object keys with an S_GAS column, in column order."""
    values: dict[str, dict[Design, float]]
    """'<key>_fc', '<key>_c', '<key>_sgas', 'pp_sgas', 'cg_sgas', 'total_sgas' -> values."""

    def measures(self) -> list[str]:
        """The S_GAS measures: each object's, then PP, CG and total."""
        return [f"{k}_sgas" for k in self.objects] + list(SUMMARY)


def _float(text: str, where: str) -> float:
    text = text.strip()
    if text in ("", "-", "–", "nan", "NaN"):
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise TableError(f"{where}: {text!r} is not a number") from None


def read_score_table(path: str | Path) -> ScoreTable:
    """Read a table of the module docstring's form; raises TableError saying what is wrong."""
    path = Path(path)
    if not path.is_file():
        raise TableError(f"{path}: no such file")
    try:
        lines = [ln for ln in path.read_text().splitlines() if not ln.lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError) as e:
        raise TableError(f"{path}: cannot be read as a text table ({e})") from None
    rows = list(csv.DictReader(lines))
    if not rows:
        raise TableError(f"{path}: no rows (expected a header line and one row per design)")
    cols = {c.strip(): c for c in (rows[0].keys() or []) if c is not None}

    def col(name: str) -> str | None:
        for cand in (name, f"{name}_pct", f"{name}_deg"):
            if cand in cols:
                return cols[cand]
        return None

    c_col, m_col = col("cmc"), col("mcp")
    missing = [n for n, c in (("cmc_deg", c_col), ("mcp_deg", m_col)) if c is None]
    if missing:
        raise TableError(f"{path}: missing column(s) {', '.join(missing)}; it has {sorted(cols)}")
    objects = tuple(
        n[: -len(s)]
        for n in cols
        for s in ("_sgas_pct", "_sgas")
        if n.endswith(s) and n[: -len(s)] not in ("pp", "cg", "total")
    )
    if not objects and not any(col(s) for s in SUMMARY):
        raise TableError(
            f"{path}: no S_GAS column: expected <object>_sgas[_pct] and/or "
            f"{', '.join(SUMMARY)}; it has {sorted(cols)}"
        )
    designs: list[Design] = []
    values: dict[str, dict[Design, float]] = {}
    for i, r in enumerate(rows, start=2):
        where = f"{path} line {i}"
        d = (
            round(_float(r[c_col] or "", where), _ROUND),  # type: ignore[index]
            round(_float(r[m_col] or "", where), _ROUND),  # type: ignore[index]
        )
        if not all(math.isfinite(x) for x in d):
            raise TableError(f"{where}: a design needs finite cmc and mcp angles")
        if d in designs:
            raise TableError(f"{where}: design CMC {d[0]:g}°, MCP {d[1]:g}° appears twice")
        designs.append(d)
        for k in objects:
            for m in METRICS:
                c = col(f"{k}_{m}")
                if c is not None:
                    values.setdefault(f"{k}_{m}", {})[d] = _float(r[c] or "", where)
        for s in SUMMARY:
            c = col(s)
            if c is not None:
                values.setdefault(s, {})[d] = _float(r[c] or "", where)
    _fill_summaries(path, objects, designs, values)
    return ScoreTable(path, tuple(designs), objects, values)


def _fill_summaries(
    path: Path, objects: Sequence[str], designs: Sequence[Design], values: dict
) -> None:
    """Recompute absent PP/CG/total columns as means of the objects' S_GAS."""
    absent = [s for s in SUMMARY if s not in values]
    if not absent:
        return
    unknown = [k for k in objects if k not in OBJECT_KEYS]
    if unknown:
        raise TableError(
            f"{path}: no {', '.join(absent)} column(s), and the grasp type of "
            f"{', '.join(unknown)} is unknown, so they cannot be recomputed"
        )
    types = {k: load_object(k).spec.grasp_type for k in objects}
    groups = {
        "pp_sgas": [k for k in objects if types[k] == "PP"],
        "cg_sgas": [k for k in objects if types[k] == "CG"],
        "total_sgas": list(objects),
    }
    for s in absent:
        keys = groups[s]
        values[s] = {
            d: float(np.mean([values[f"{k}_sgas"][d] for k in keys])) if keys else math.nan
            for d in designs
        }


@dataclass(frozen=True)
class MeasureAgreement:
    """Agreement of one measure (an object's S_GAS, PP, CG or total) between two tables."""

    measure: str
    """'<key>_sgas', 'pp_sgas', 'cg_sgas' or 'total_sgas'."""
    n: int
    """Designs with a finite value in both tables."""
    spearman: float
    """Spearman ρ over those designs (NaN when undefined: fewer than 3, or a constant)."""
    kendall: float
    """Kendall τ-b over those designs (NaN when undefined)."""
    mad: float
    """Mean absolute difference, percentage points."""
    best_ours: tuple[Design, float] | None
    """Our best design over all our designs, and its value."""
    best_ref: tuple[Design, float] | None
    """The reference's best design over all its designs, and its value."""
    baseline_rank_ours: tuple[int, int] | None
    """The baseline's (rank, of how many) in our table (1 = best), if it has the baseline."""
    baseline_rank_ref: tuple[int, int] | None
    """The same in the reference table."""


@dataclass(frozen=True)
class Agreement:
    """Everything ``handbench validate`` prints."""

    ours: ScoreTable
    ref: ScoreTable
    common: tuple[Design, ...]
    """Designs in both tables."""
    only_ours: tuple[Design, ...]
    """Designs only in our table."""
    only_ref: tuple[Design, ...]
    """Designs only in the reference."""
    measures: tuple[MeasureAgreement, ...]
    """One per measure both tables hold."""
    missing_measures: tuple[str, ...]
    """Measures of one table that the other lacks (not compared)."""

    def get(self, measure: str) -> MeasureAgreement:
        """The agreement of one measure."""
        for m in self.measures:
            if m.measure == measure:
                return m
        raise KeyError(measure)


def _best(values: dict[Design, float]) -> tuple[Design, float] | None:
    finite = [(v, d) for d, v in values.items() if math.isfinite(v)]
    if not finite:
        return None
    v, d = max(finite, key=lambda x: x[0])  # ties: the first design in file order
    return d, v


def _rank(values: dict[Design, float], design: Design) -> tuple[int, int] | None:
    v = values.get(design, math.nan)
    finite = [x for x in values.values() if math.isfinite(x)]
    if not math.isfinite(v):
        return None
    return 1 + sum(x > v for x in finite), len(finite)


def _stat(fn, a: np.ndarray, b: np.ndarray) -> float:  # noqa: ANN001
    if len(a) < 3 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return math.nan
    return float(fn(a, b)[0])


def agreement(ours: ScoreTable, ref: ScoreTable) -> Agreement:
    """Compare two tables (see the module docstring)."""
    common = tuple(d for d in ours.designs if d in ref.designs)
    if not common:
        raise TableError(
            f"{ours.path} and {ref.path} have no design in common "
            f"(ours: {_fmt_designs(ours.designs)}; reference: {_fmt_designs(ref.designs)})"
        )
    mine, theirs = ours.measures(), ref.measures()
    both = [m for m in mine if m in theirs]
    out = []
    baseline = (round(BASELINE_DEG[0], _ROUND), round(BASELINE_DEG[1], _ROUND))
    for m in both:
        a = np.array([ours.values[m][d] for d in common])
        b = np.array([ref.values[m][d] for d in common])
        ok = np.isfinite(a) & np.isfinite(b)
        a, b = a[ok], b[ok]
        out.append(
            MeasureAgreement(
                m,
                int(ok.sum()),
                _stat(spearmanr, a, b),
                _stat(kendalltau, a, b),
                float(np.mean(np.abs(a - b))) if len(a) else math.nan,
                _best(ours.values[m]),
                _best(ref.values[m]),
                _rank(ours.values[m], baseline),
                _rank(ref.values[m], baseline),
            )
        )
    missing = tuple(m for m in mine if m not in theirs) + tuple(m for m in theirs if m not in mine)
    return Agreement(
        ours,
        ref,
        common,
        tuple(d for d in ours.designs if d not in ref.designs),
        tuple(d for d in ref.designs if d not in ours.designs),
        tuple(out),
        missing,
    )


def _fmt_designs(ds: Sequence[Design], limit: int = 12) -> str:
    txt = ", ".join(f"{c:g}/{m:g}" for c, m in ds[:limit])
    return txt + (f", … ({len(ds)} in all)" if len(ds) > limit else "")


def _num(x: float, digits: int = 2) -> str:
    return "–" if not math.isfinite(x) else f"{x:.{digits}f}"


def _design(best: tuple[Design, float] | None) -> str:
    return "–" if best is None else f"{best[0][0]:g}/{best[0][1]:g} ({best[1]:.1f})"


def _rank_txt(r: tuple[int, int] | None) -> str:
    return "–" if r is None else f"{r[0]} of {r[1]}"


def agreement_markdown(ag: Agreement) -> str:
    """The agreement as a Markdown report (what ``handbench validate`` prints)."""
    lines = [
        f"ours: `{ag.ours.path}` ({len(ag.ours.designs)} designs); "
        f"reference: `{ag.ref.path}` ({len(ag.ref.designs)} designs); "
        f"compared on {len(ag.common)} designs in both.",
        "",
        "| measure | n | Spearman ρ | Kendall τ | mean abs diff (pts) | best ours (CMC/MCP, %) "
        "| best reference | baseline rank ours | baseline rank reference |",
        "|---|---:|---:|---:|---:|---|---|---|---|",
    ]
    for m in ag.measures:
        lines.append(
            f"| {m.measure} | {m.n} | {_num(m.spearman)} | {_num(m.kendall)} | {_num(m.mad, 1)} "
            f"| {_design(m.best_ours)} | {_design(m.best_ref)} "
            f"| {_rank_txt(m.baseline_rank_ours)} | {_rank_txt(m.baseline_rank_ref)} |"
        )
    per_object = [m.spearman for m in ag.measures if m.measure not in SUMMARY]
    finite = [x for x in per_object if math.isfinite(x)]
    lines += [
        "",
        f"median per-object Spearman ρ: {_num(float(np.median(finite))) if finite else '–'} "
        f"(over {len(finite)} objects)",
    ]
    if ag.only_ours:
        lines.append(f"designs only in ours ({len(ag.only_ours)}): {_fmt_designs(ag.only_ours)}")
    if ag.only_ref:
        lines.append(
            f"designs only in the reference ({len(ag.only_ref)}): {_fmt_designs(ag.only_ref)}"
        )
    if ag.missing_measures:
        lines.append(f"measures in one table only (not compared): {', '.join(ag.missing_measures)}")
    return "\n".join(lines)


def write_agreement_csv(ag: Agreement, path: str | Path) -> Path:
    """One row per measure: the figures of ``MeasureAgreement``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["measure", "n", "spearman", "kendall", "mad_pts", "best_ours_cmc",
                    "best_ours_mcp", "best_ref_cmc", "best_ref_mcp", "baseline_rank_ours",
                    "baseline_rank_ref", "n_ours", "n_ref"])  # fmt: skip
        for m in ag.measures:
            bo, br = m.best_ours, m.best_ref
            ro, rr = m.baseline_rank_ours, m.baseline_rank_ref
            w.writerow([
                m.measure, m.n, _num(m.spearman, 4), _num(m.kendall, 4), _num(m.mad, 3),
                bo[0][0] if bo else "", bo[0][1] if bo else "",
                br[0][0] if br else "", br[0][1] if br else "",
                ro[0] if ro else "", rr[0] if rr else "",
                ro[1] if ro else "", rr[1] if rr else "",
            ])  # fmt: skip
    return path
