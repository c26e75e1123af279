"""Grasp-type correctness (app.quality.grasp_type) on hand-built contact sets."""

from __future__ import annotations

import numpy as np
import pytest

from app.errors import SettingsError
from app.model.contact_set import ContactSet
from app.quality.grasp_type import (
    GraspTypeSettings,
    Verdict,
    check_cg,
    check_grasp_type,
    check_pp,
    is_palmar,
    line_angle_deg,
)

Z = np.array([0.0, 0.0, 1.0])  # grip axis of a standing cylinder
X = np.array([1.0, 0.0, 0.0])


def _cs(*items: tuple[str, bool]) -> ContactSet:
    """ContactSet with one point per (link, palmar) item (geometry irrelevant here)."""
    k = len(items)
    rng = np.random.default_rng(k)
    n = rng.normal(size=(k, 3))
    return ContactSet(
        rng.normal(size=(k, 3)),
        n / np.linalg.norm(n, axis=1, keepdims=True),
        np.array([a for a, _ in items], dtype=object).reshape(k),
        np.array([b for _, b in items], dtype=bool).reshape(k),
    )


# ---------------------------------------------------------------- palmar


def test_is_palmar_threshold_and_batching():
    npal = np.array([0.0, 0.0, 1.0])
    ang = np.radians([0.0, 30.0, 74.9, 75.1, 90.0, 180.0])
    nc = np.c_[np.sin(ang), np.zeros_like(ang), np.cos(ang)] * 3.0  # not unit on purpose
    got = is_palmar(nc, np.broadcast_to(npal, nc.shape), 75.0)
    assert got.tolist() == [True, True, True, False, False, False]
    # leading batch axes
    assert is_palmar(nc.reshape(2, 3, 3), np.broadcast_to(npal, (2, 3, 3)), 75.0).shape == (2, 3)


def test_line_angle_ignores_sign():
    assert float(line_angle_deg(Z, -Z)) == pytest.approx(0.0)
    assert float(line_angle_deg(X, Z)) == pytest.approx(90.0)
    assert float(line_angle_deg([1.0, 0, 1.0], -Z)) == pytest.approx(45.0)
    with pytest.raises(ValueError):
        line_angle_deg(np.zeros(3), Z)


# ---------------------------------------------------------------- PP


def test_pp_correct():
    v = check_pp(_cs(("thumb_distal", True), ("index_distal", True), ("index_middle", False)))
    assert v == Verdict(True, ())


def test_pp_with_palm_contact():
    # a non-palmar palm contact also fails
    v = check_pp(_cs(("thumb_distal", True), ("index_distal", True), ("palm", False)))
    assert not v.correct and v.reasons == ("contact with the palm",)


def test_pp_with_two_distal_fingers():
    v = check_pp(_cs(("thumb_distal", True), ("index_distal", True), ("middle_distal", True)))
    assert not v.correct
    assert v.reasons == (
        "palmar contacts on the distal phalanges of 2 long fingers (index, middle); "
        "pulp pinch needs exactly one",
    )


def test_pp_with_non_palmar_thumb_contact():
    v = check_pp(_cs(("thumb_distal", False), ("thumb_proximal", True), ("index_distal", True)))
    assert not v.correct
    assert v.reasons == ("no palmar contact on the thumb distal phalanx",)


def test_pp_lists_every_failure():
    v = check_pp(_cs(("index_middle", True), ("palm", True)))
    assert not v.correct and len(v.reasons) == 3
    assert "thumb distal" in v.reasons[0]
    assert "any long finger" in v.reasons[1]
    assert v.reasons[2] == "contact with the palm"


# ---------------------------------------------------------------- CG

CG_OK = (
    ("thumb_proximal", True),
    ("index_proximal", True),
    ("index_middle", True),
    ("middle_proximal", True),
    ("middle_distal", True),
    ("ring_middle", True),
    ("ring_distal", True),
    ("little_distal", False),
    ("palm", True),
)


def test_cg_correct():
    assert check_cg(_cs(*CG_OK), X, Z) == Verdict(True, ())
    # the thumb axis's and grip axis's signs do not matter
    assert check_cg(_cs(*CG_OK), -X, -Z).correct


def test_cg_thumb_axis_parallel_to_grip_axis():
    v = check_cg(_cs(*CG_OK), Z, Z)
    assert not v.correct
    assert v.reasons == ("thumb axis at 0° to the grip axis; needs > 60°",)
    tilt = np.array([np.sin(np.radians(42.0)), 0.0, np.cos(np.radians(42.0))])
    assert check_cg(_cs(*CG_OK), tilt, -Z).reasons == (
        "thumb axis at 42° to the grip axis; needs > 60°",
    )
    # 60° exactly is not enough ("greater than"), 61° is
    at = lambda a: np.array([np.sin(np.radians(a)), 0.0, np.cos(np.radians(a))])  # noqa: E731
    assert not check_cg(_cs(*CG_OK), at(60.0 - 1e-9), Z).correct
    assert check_cg(_cs(*CG_OK), at(61.0), Z).correct


def test_cg_with_only_two_fingers():
    items = tuple(x for x in CG_OK if not x[0].startswith("ring"))
    v = check_cg(_cs(*items), X, Z)
    assert not v.correct
    assert v.reasons == (
        "palmar contacts on two phalanges of only 2 long fingers (index, middle); needs 3",
    )
    # a finger with palmar contacts on one phalanx only (ring) does not count ...
    v = check_cg(_cs(*items, ("ring_distal", True), ("ring_distal", True)), X, Z)
    assert not v.correct
    # ... unless the protocol parameter says one phalanx is enough
    assert check_cg(
        _cs(*items, ("ring_distal", True)), X, Z, GraspTypeSettings(cg_min_phalanges_per_finger=1)
    ).correct
    # the strict protocol (three phalanges) fails the relaxed-correct grasp
    strict = GraspTypeSettings(cg_min_phalanges_per_finger=3)
    v = check_cg(_cs(*CG_OK), X, Z, strict)
    assert v.reasons == ("no long finger has palmar contacts on three phalanges; needs 3",)


def test_cg_without_palm():
    items = tuple(x for x in CG_OK if x[0] != "palm")
    v = check_cg(_cs(*items), X, Z)
    assert v == Verdict(False, ("no palmar contact on the palm",))
    # a non-palmar palm contact does not count
    v = check_cg(_cs(*items, ("palm", False)), X, Z)
    assert v.reasons == ("no palmar contact on the palm",)


def test_cg_without_palmar_thumb():
    items = tuple(x for x in CG_OK if not x[0].startswith("thumb")) + (("thumb_distal", False),)
    v = check_cg(_cs(*items), X, Z)
    assert v.reasons == ("no palmar contact on the thumb",)


def test_cg_lists_every_failure():
    v = check_cg(_cs(("index_distal", True)), Z, Z)
    assert not v.correct and len(v.reasons) == 4


# ---------------------------------------------------------------- dispatch and settings


def test_dispatch():
    pp = _cs(("thumb_distal", True), ("index_distal", True))
    assert check_grasp_type("PP", pp).correct
    assert check_grasp_type("CG", _cs(*CG_OK), X, Z).correct
    with pytest.raises(SettingsError, match=r"'PP', 'CG'"):
        check_grasp_type("power", pp)
    with pytest.raises(ValueError, match="grip_axis"):
        check_grasp_type("CG", pp)


@pytest.mark.parametrize(
    "bad",
    [
        {"palmar_angle_deg": 0.0},
        {"palmar_angle_deg": 180.0},
        {"palmar_angle_deg": float("nan")},
        {"cg_min_long_fingers": 0},
        {"cg_min_long_fingers": 5},
        {"cg_min_phalanges_per_finger": 4},
        {"cg_min_phalanges_per_finger": 2.0},
        {"cg_thumb_axis_min_angle_deg": 90.0},
        {"cg_thumb_axis_min_angle_deg": -1.0},
    ],
)
def test_settings_validation(bad):
    with pytest.raises(SettingsError, match="must be"):
        GraspTypeSettings(**bad)


def test_settings_defaults():
    s = GraspTypeSettings()
    assert s.as_dict() == {
        "palmar_angle_deg": 75.0,
        "cg_min_long_fingers": 3,
        "cg_min_phalanges_per_finger": 2,
        "cg_thumb_axis_min_angle_deg": 60.0,
    }
