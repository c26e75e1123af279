"""Stored scores of every design with complete results (the design map's data)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from app.explorer.reference import reference_scores
from app.model.objects import load_object
from app.quality.scores import DesignScore, ObjectScore
from app.quality.settings import SimSettings
from app.runs.keys import object_key
from app.runs.store import ResultStore
from app.sim.hypothesis_sets import cached_hypotheses

TOTAL = "total S_GAS"
PP = "PP S_GAS"
CG = "CG S_GAS"


@dataclass(frozen=True)
class MapPoint:
    """One computed design and its score."""

    cmc_deg: float
    mcp_deg: float
    score: DesignScore
    source: str = "store"
    """'store' (the user's results) or 'shipped' (the reference sweep in docs/results)."""

    @property
    def label(self) -> str:
        """'CMC 15°, MCP 60°' (+ ' (shipped)'): the design picker's option."""
        tag = " (shipped)" if self.source == "shipped" else ""
        return f"CMC {self.cmc_deg:g}°, MCP {self.mcp_deg:g}°{tag}"


def metric_choices(objects: Sequence[str]) -> tuple[str, ...]:
    """What the map can show: total, per grasp type, per object."""
    return (TOTAL, PP, CG, *objects)


def metric_value(score: DesignScore, metric: str) -> float:
    """The chosen metric (%, NaN when undefined)."""
    v = {
        TOTAL: score.total_sgas_pct,
        PP: score.pp_sgas_pct,
        CG: score.cg_sgas_pct,
    }.get(metric, math.nan)
    if metric in score.objects:
        v = score.objects[metric].sgas_pct
    return math.nan if v is None else float(v)


def complete_designs(
    store: ResultStore, objects: Sequence[str], settings: SimSettings, tilt: str = "ulnar"
) -> list[MapPoint]:
    """Designs whose every object has all its hypotheses stored under ``settings``."""
    skey = settings.key()
    okeys = {k: object_key(k) for k in objects}
    n_gh = {k: len(cached_hypotheses(k)) for k in objects}
    types = {k: load_object(k).spec.grasp_type for k in objects}
    out: list[MapPoint] = []
    for dkey, meta in store.designs():
        if meta.get("cmc_tilt", "ulnar") != tilt:
            continue
        summ = store.summary(dkey, skey)
        counts = {k: summ.get(okeys[k], (0, 0, 0)) for k in objects}
        if any(counts[k][0] < n_gh[k] for k in objects):
            continue
        score = DesignScore({k: ObjectScore(*counts[k]) for k in objects}, types)
        out.append(MapPoint(float(meta["cmc_deg"]), float(meta["mcp_deg"]), score))
    out.sort(key=lambda p: (p.cmc_deg, p.mcp_deg))
    return out


def map_points(
    store: ResultStore,
    objects: Sequence[str],
    settings: SimSettings,
    tilt: str = "ulnar",
    ref_dir: Path | None = None,
) -> list[MapPoint]:
    """The store's complete designs, plus the shipped reference designs the store lacks
    (when the shipped table applies to ``settings``, ``tilt`` and ``objects``)."""
    pts = complete_designs(store, objects, settings, tilt)
    have = {(p.cmc_deg, p.mcp_deg) for p in pts}
    ref = reference_scores(objects, settings, tilt, ref_dir)
    pts += [MapPoint(c, m, sc, "shipped") for (c, m), sc in ref.items() if (c, m) not in have]
    pts.sort(key=lambda p: (p.cmc_deg, p.mcp_deg))
    return pts
