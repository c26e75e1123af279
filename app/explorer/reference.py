"""The shipped reference sweep (``docs/results/table.csv`` + ``meta.json``) as a fallback
layer of the design map and the Live S_GAS panel.

On a fresh machine the results store is empty; the shipped table fills in the designs the
store lacks. It is used only when its ``meta.json`` says it was made with the session's
settings key (which includes the engine version) and the same hand model file, and with the
same number of hypotheses per object. Counts are rebuilt from the percentages (2 decimals
over N_GH <= ~1000 hypotheses round back exactly), so scores of any object subset follow.
The shipped sweep covers the ulnar CMC tilt only (unless ``meta.json`` names another).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from app.model.hand.data import load_hand_dims
from app.model.objects import load_object
from app.quality.scores import DesignScore, ObjectScore
from app.quality.settings import SimSettings
from app.sim.hypothesis_sets import cached_hypotheses

DEFAULT_REFERENCE_DIR = Path(__file__).resolve().parents[2] / "docs" / "results"
"""``docs/results`` of the repository."""

SOURCE_LABEL = "shipped reference (docs/results)"
REFERENCE_NOTE = (
    "from the shipped reference sweep; not in your store — grasp replays and outcome "
    "filters need it computed"
)
REFERENCE_DIFF_NOTE = (
    "A fresh computation can differ from the shipped sweep by a hypothesis or two (cause "
    "not found yet; not the executor): see docs/explorer.md, 'Shipped reference and your "
    "store'."
)


@dataclass(frozen=True)
class ReferenceTable:
    """A validated shipped table: per design (cmc, mcp) the per-object counts."""

    settings_key: str
    hand_hash: str
    cmc_tilt: str
    n_gh: dict[str, int]
    rows: dict[tuple[float, float], dict[str, ObjectScore]]


def _counts(pct: str, n: int) -> int:
    v = float(pct) if pct.strip() else math.nan
    return 0 if not math.isfinite(v) else round(v * n / 100.0)


@lru_cache(maxsize=8)
def _load(table: Path, meta: Path, _mtimes: tuple[int, int]) -> ReferenceTable | None:
    try:
        m = json.loads(meta.read_text())
        n_gh = {str(k): int(v) for k, v in m["n_gh"].items()}
        rows: dict[tuple[float, float], dict[str, ObjectScore]] = {}
        with table.open(newline="") as f:
            for r in csv.DictReader(f):
                scores = {}
                for k, n in n_gh.items():
                    fc = _counts(r[f"{k}_fc_pct"], n)
                    c = _counts(r[f"{k}_c_pct"], n)
                    scores[k] = ObjectScore(n, fc, c)
                rows[(float(r["cmc_deg"]), float(r["mcp_deg"]))] = scores
        return ReferenceTable(
            str(m["settings_key"]), str(m["hand_hash"]), str(m.get("cmc_tilt", "ulnar")),
            n_gh, rows,
        )  # fmt: skip
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None  # a missing or malformed shipped table is simply not used


def load_reference(ref_dir: Path | None = None) -> ReferenceTable | None:
    """The shipped table of ``ref_dir`` (default ``docs/results``), cached per file mtime;
    None when absent or malformed."""
    d = Path(ref_dir) if ref_dir is not None else DEFAULT_REFERENCE_DIR
    table, meta = d / "table.csv", d / "meta.json"
    try:
        mt = (table.stat().st_mtime_ns, meta.stat().st_mtime_ns)
    except OSError:
        return None
    return _load(table, meta, mt)


def reference_scores(
    objects: Sequence[str],
    settings: SimSettings,
    tilt: str = "ulnar",
    ref_dir: Path | None = None,
) -> dict[tuple[float, float], DesignScore]:
    """(cmc, mcp) -> score over ``objects`` of the shipped designs, or {} when the shipped
    table does not apply (other settings key, hand model, tilt, hypotheses or objects)."""
    ref = load_reference(ref_dir)
    if (
        ref is None
        or ref.settings_key != settings.key()
        or ref.hand_hash != load_hand_dims().content_hash
        or ref.cmc_tilt != tilt
        or any(ref.n_gh.get(k) != len(cached_hypotheses(k)) for k in objects)
    ):
        return {}
    types = {k: load_object(k).spec.grasp_type for k in objects}
    return {cm: DesignScore({k: s[k] for k in objects}, types) for cm, s in ref.rows.items()}


def reference_score(
    cmc_deg: float,
    mcp_deg: float,
    objects: Sequence[str],
    settings: SimSettings,
    tilt: str = "ulnar",
    ref_dir: Path | None = None,
) -> DesignScore | None:
    """The shipped score of one design, or None."""
    return reference_scores(objects, settings, tilt, ref_dir).get((float(cmc_deg), float(mcp_deg)))
