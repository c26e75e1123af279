"""S_GAS scores (app.quality.scores) on small hand-computed examples."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.errors import SettingsError
from app.quality.scores import DesignScore, ObjectScore, score_object

TYPES = {"small_marker": "PP", "washer": "PP", "chips_can": "CG", "coffee_can": "CG"}


def test_score_object_counts_and_formula():
    fc = np.array([1, 1, 1, 0, 1, 0, 0, 0, 0, 0], dtype=bool)
    correct = np.array([1, 0, 1, 0, 0, 0, 0, 0, 0, 0], dtype=bool)
    s = score_object(fc, correct)
    assert s == ObjectScore(n_gh=10, n_fc=4, n_correct=2)
    # S_GAS = (C + 0.5 NC) / N_GH = (2 + 0.5 * 2) / 10 = 30 %
    assert s.sgas_pct == pytest.approx(30.0)
    assert s.fc_pct == pytest.approx(40.0)
    assert s.c_pct == pytest.approx(20.0)


def test_sgas_extremes():
    assert ObjectScore(8, 8, 8).sgas_pct == 100.0  # all FC and correct
    assert ObjectScore(8, 8, 0).sgas_pct == 50.0  # all FC, none correct
    assert ObjectScore(8, 0, 0).sgas_pct == 0.0
    assert math.isnan(ObjectScore(0, 0, 0).sgas_pct)


def test_correct_must_be_subset_of_fc():
    with pytest.raises(AssertionError, match=r"\[2\]"):
        score_object(np.array([True, False, False]), np.array([True, False, True]))
    with pytest.raises(AssertionError):
        score_object(np.array([True, False]), np.array([True, False, False]))


def _design() -> DesignScore:
    return DesignScore(
        {
            "small_marker": ObjectScore(10, 4, 2),  # 30 %
            "washer": ObjectScore(20, 10, 10),  # 50 %
            "chips_can": ObjectScore(4, 4, 1),  # (1 + 1.5) / 4 = 62.5 %
            "coffee_can": ObjectScore(5, 0, 0),  # 0 %
        },
        TYPES,
    )


def test_type_and_total_means():
    d = _design()
    assert d.pp_sgas_pct == pytest.approx(40.0)
    assert d.cg_sgas_pct == pytest.approx(31.25)
    # the mean over objects, not over grasps
    assert d.total_sgas_pct == pytest.approx((30 + 50 + 62.5 + 0) / 4)


def test_missing_type_gives_none_and_empty_objects_are_skipped():
    d = DesignScore({"chips_can": ObjectScore(4, 4, 1), "washer": ObjectScore(0, 0, 0)}, TYPES)
    assert d.pp_sgas_pct is None
    assert d.cg_sgas_pct == pytest.approx(62.5)
    assert d.total_sgas_pct == pytest.approx(62.5)
    js = d.to_json_dict(10.0, 20.0, {})
    assert js["pp_sgas_pct"] is None and js["objects"]["washer"]["sgas_pct"] is None
    json.dumps(js, allow_nan=False)


def test_grasp_type_required_and_validated():
    with pytest.raises(SettingsError, match="'PP', 'CG'"):
        DesignScore({"pear": ObjectScore(1, 1, 1)}, TYPES)
    with pytest.raises(SettingsError):
        DesignScore({"pear": ObjectScore(1, 1, 1)}, {"pear": "power"})


def test_from_verdicts():
    d = DesignScore.from_verdicts(
        {"washer": np.array([True, True, False]), "chips_can": np.array([True])},
        {"washer": np.array([True, False, False]), "chips_can": np.array([False])},
        TYPES,
    )
    assert d.objects == {"washer": ObjectScore(3, 2, 1), "chips_can": ObjectScore(1, 1, 0)}


def test_json_dict_exact_keys():
    settings = {"fc": {"mu": 0.4, "n_edges": 8}}
    js = _design().to_json_dict(15.0, -30.0, settings)
    assert list(js) == [
        "design",
        "objects",
        "pp_sgas_pct",
        "cg_sgas_pct",
        "total_sgas_pct",
        "settings",
    ]
    assert js["design"] == {"cmc_deg": 15.0, "mcp_deg": -30.0}
    assert list(js["objects"]) == ["small_marker", "washer", "chips_can", "coffee_can"]
    assert js["objects"]["small_marker"] == {
        "n_gh": 10,
        "fc_pct": 40.0,
        "c_pct": 20.0,
        "sgas_pct": 30.0,
    }
    assert js["settings"] == settings
    assert js["pp_sgas_pct"] == pytest.approx(40.0)
    json.dumps(js, allow_nan=False)


def test_row_columns():
    row = _design().to_row(15.0, -30.0)
    keys = ["small_marker", "washer", "chips_can", "coffee_can"]
    assert list(row) == (
        ["cmc_deg", "mcp_deg"]
        + [f"{k}_{m}" for k in keys for m in ("fc_pct", "c_pct", "sgas_pct")]
        + ["pp_sgas_pct", "cg_sgas_pct", "total_sgas_pct"]
    )
    assert row["chips_can_sgas_pct"] == pytest.approx(62.5)
    assert row["cg_sgas_pct"] == pytest.approx(31.25)
