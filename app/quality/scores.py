"""The grasp-success score S_GAS per object, grasp type and design (METHOD §5).

Per object i, over its N_GH_i grasp hypotheses: FC_i force-closure grasps, of which C_i are
of the correct grasp type and NC_i = FC_i − C_i are not:

    S_GAS_i = (C_i + 0.5 · NC_i) / N_GH_i                                (reported in %)

FC % = 100 · FC_i / N_GH_i and C % = 100 · C_i / N_GH_i (both over all hypotheses).
Per grasp type: the mean of S_GAS_i over the objects of that type present; total: the mean
over all objects present. An object with N_GH_i = 0 has undefined (NaN, JSON null)
percentages and is left out of the means.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from app.errors import SettingsError
from app.quality.grasp_type import GRASP_TYPES


def _pct(num: float, den: int) -> float:
    return 100.0 * num / den if den > 0 else math.nan


class ObjectScore(NamedTuple):
    """Counts of one object's grasps under one design."""

    n_gh: int
    """Grasp hypotheses simulated, N_GH."""
    n_fc: int
    """Force-closure grasps, FC = C + NC."""
    n_correct: int
    """FC grasps of the correct grasp type, C."""

    @property
    def fc_pct(self) -> float:
        """100 · FC / N_GH (NaN when N_GH = 0)."""
        return _pct(self.n_fc, self.n_gh)

    @property
    def c_pct(self) -> float:
        """100 · C / N_GH (NaN when N_GH = 0)."""
        return _pct(self.n_correct, self.n_gh)

    @property
    def sgas_pct(self) -> float:
        """100 · (C + 0.5 · (FC − C)) / N_GH (NaN when N_GH = 0)."""
        return _pct(self.n_correct + 0.5 * (self.n_fc - self.n_correct), self.n_gh)


def score_object(fc: np.ndarray, correct: np.ndarray) -> ObjectScore:
    """Score one object from per-grasp verdicts.

    Args:
        fc: (N,) bool, grasp is force closure.
        correct: (N,) bool, grasp is FC and of the correct type (correct ⊆ fc).

    Raises:
        AssertionError: shapes differ, or a grasp is correct without being FC.
    """
    fc = np.asarray(fc, dtype=bool).reshape(-1)
    correct = np.asarray(correct, dtype=bool).reshape(-1)
    if fc.shape != correct.shape:
        raise AssertionError(f"fc {fc.shape} and correct {correct.shape} differ in shape")
    if np.any(correct & ~fc):
        bad = np.flatnonzero(correct & ~fc)
        raise AssertionError(f"grasps {bad.tolist()} are counted correct but are not FC")
    return ObjectScore(int(fc.size), int(fc.sum()), int(correct.sum()))


def _mean(values: list[float]) -> float | None:
    vals = [v for v in values if not math.isnan(v)]
    return float(np.mean(vals)) if vals else None


def _json_num(x: float) -> float | None:
    return None if math.isnan(x) else float(x)


@dataclass(frozen=True)
class DesignScore:
    """Scores of one design (thumb DA) over the objects simulated."""

    objects: dict[str, ObjectScore]
    """Object key → its score, in report order."""
    grasp_types: Mapping[str, str] = field(default_factory=dict)
    """Object key → "PP" or "CG"; must cover every key of ``objects``."""

    def __post_init__(self) -> None:
        for key in self.objects:
            g = self.grasp_types.get(key)
            if g not in GRASP_TYPES:
                raise SettingsError(
                    f"object {key!r} has grasp type {g!r}; choose one of {GRASP_TYPES}"
                )

    @classmethod
    def from_verdicts(
        cls,
        fc: Mapping[str, np.ndarray],
        correct: Mapping[str, np.ndarray],
        grasp_types: Mapping[str, str],
    ) -> DesignScore:
        """Build from per-object (N,) bool arrays ``fc[key]`` and ``correct[key]``."""
        return cls({k: score_object(fc[k], correct[k]) for k in fc}, dict(grasp_types))

    def _type_mean(self, grasp_type: str | None) -> float | None:
        return _mean(
            [
                s.sgas_pct
                for k, s in self.objects.items()
                if grasp_type is None or self.grasp_types[k] == grasp_type
            ]
        )

    @property
    def pp_sgas_pct(self) -> float | None:
        """Mean S_GAS % over the PP objects present (None when there are none)."""
        return self._type_mean("PP")

    @property
    def cg_sgas_pct(self) -> float | None:
        """Mean S_GAS % over the CG objects present (None when there are none)."""
        return self._type_mean("CG")

    @property
    def total_sgas_pct(self) -> float | None:
        """Mean S_GAS % over all objects present (None when there are none)."""
        return self._type_mean(None)

    def to_json_dict(
        self, cmc_deg: float, mcp_deg: float, settings: Mapping[str, Any]
    ) -> dict[str, Any]:
        """``{"design": {"cmc_deg", "mcp_deg"}, "objects": {key: {"n_gh", "fc_pct", "c_pct",
        "sgas_pct"}}, "pp_sgas_pct", "cg_sgas_pct", "total_sgas_pct", "settings"}``;
        undefined values are None (JSON null)."""
        return {
            "design": {"cmc_deg": float(cmc_deg), "mcp_deg": float(mcp_deg)},
            "objects": {
                k: {
                    "n_gh": s.n_gh,
                    "fc_pct": _json_num(s.fc_pct),
                    "c_pct": _json_num(s.c_pct),
                    "sgas_pct": _json_num(s.sgas_pct),
                }
                for k, s in self.objects.items()
            },
            "pp_sgas_pct": self.pp_sgas_pct,
            "cg_sgas_pct": self.cg_sgas_pct,
            "total_sgas_pct": self.total_sgas_pct,
            "settings": dict(settings),
        }

    def to_row(self, cmc_deg: float, mcp_deg: float) -> dict[str, float | None]:
        """Flat row: ``cmc_deg, mcp_deg, <key>_fc_pct, <key>_c_pct, <key>_sgas_pct`` per
        object (in ``objects`` order), ``pp_sgas_pct, cg_sgas_pct, total_sgas_pct``."""
        row: dict[str, float | None] = {"cmc_deg": float(cmc_deg), "mcp_deg": float(mcp_deg)}
        for k, s in self.objects.items():
            row[f"{k}_fc_pct"] = _json_num(s.fc_pct)
            row[f"{k}_c_pct"] = _json_num(s.c_pct)
            row[f"{k}_sgas_pct"] = _json_num(s.sgas_pct)
        row["pp_sgas_pct"] = self.pp_sgas_pct
        row["cg_sgas_pct"] = self.cg_sgas_pct
        row["total_sgas_pct"] = self.total_sgas_pct
        return row
