"""Anthropomorphic grasp hypotheses (METHOD §3a): counts, cone, rolls, orientation, ids."""

from __future__ import annotations

import numpy as np
import pytest

from app.errors import UnknownHypothesisError
from app.model.objects import OBJECT_KEYS, load_object
from app.sim.hypotheses import cone_rays, make_hypotheses, palm_orientation
from app.sim.hypothesis_sets import cached_hypotheses

N_GH = {
    "small_marker": 1026,
    "plastic_pear": 648,
    "washer": 1026,
    "chips_can": 420,
    "coffee_can": 420,
    "power_drill": 720,
}


@pytest.mark.parametrize("key", OBJECT_KEYS)
def test_counts_ids_and_determinism(key: str) -> None:
    h = cached_hypotheses(key)
    assert len(h) == N_GH[key] == load_object(key).spec.setup.n_gh
    assert len(set(h.ids)) == len(h)
    again = make_hypotheses(
        key,
        h.target_object,
        load_object(key).spec.normal_object,
        load_object(key).spec.palm_y_hint_object,
        load_object(key).spec.setup.hand_vector_palm,
        load_object(key).spec.setup.cone_angle_rad,
        load_object(key).spec.setup.n_rays,
        load_object(key).spec.setup.standoffs_mm,
        load_object(key).spec.setup.roll_range_deg,
        load_object(key).spec.setup.n_rolls,
    )
    assert again.ids == h.ids and np.array_equal(again.R_object_palm, h.R_object_palm)


@pytest.mark.parametrize("key", OBJECT_KEYS)
def test_rays_fill_the_cone_and_pass_the_target(key: str) -> None:
    spec = load_object(key).spec
    h = cached_hypotheses(key)
    ang = np.arccos(np.clip(h.ray_object @ spec.normal_object, -1, 1))
    assert ang.max() == pytest.approx(spec.setup.cone_angle_rad / 2, abs=1e-9)  # rim reached
    assert ang.min() == pytest.approx(0.0, abs=1e-9)  # axis ray included
    # the hand vector n (palm frame) points along -ray: the line through P hits the target
    n_obj = np.einsum("nij,j->ni", h.R_object_palm, spec.setup.hand_vector_palm)
    assert np.allclose(n_obj, -h.ray_object, atol=1e-12)
    assert np.allclose(np.linalg.det(h.R_object_palm), 1.0)


def test_rolls_span_the_range_both_ends_included_in_order() -> None:
    h = cached_hypotheses("chips_can")
    rolls = np.unique(np.round(np.rad2deg(h.roll_rad), 9))
    assert rolls.min() == pytest.approx(-50) and rolls.max() == pytest.approx(-20)
    assert len(rolls) == 15
    assert np.rad2deg(h.roll_rad[h.roll_index == 0][0]) == pytest.approx(-20)  # theta_i first


def test_roll_turns_about_the_ray() -> None:
    n_p = np.array([0.41, 0, 0.91]) / np.linalg.norm([0.41, 0, 0.91])
    approach = np.array([0.0, 0.0, -1.0])
    R0 = palm_orientation(approach, n_p, np.array([1.0, 0, 0]), 0.0)
    R1 = palm_orientation(approach, n_p, np.array([1.0, 0, 0]), np.deg2rad(30))
    rel = R1 @ R0.T
    axis_angle = np.rad2deg(np.arccos((np.trace(rel) - 1) / 2))
    assert axis_angle == pytest.approx(30)
    assert np.allclose(rel @ approach, approach)
    # roll 0 puts palm +y as close as possible to the hint
    y = R0 @ np.array([0.0, 1.0, 0.0])
    assert y @ np.array([1.0, 0, 0]) > 0.99


def test_cone_rays_are_spread() -> None:
    d = cone_rays(np.array([0, 0, 1.0]), 0.8, 24)
    gram = d @ d.T - 2 * np.eye(24)
    min_sep = np.rad2deg(np.arccos(gram.max()))
    assert min_sep > 3.0  # quasi-uniform: no two rays nearly coincide


def test_unknown_hypothesis_errors() -> None:
    h = cached_hypotheses("washer")
    assert h.index_of(h.ids[17]) == 17 and h.index_of(17) == 17
    with pytest.raises(UnknownHypothesisError, match="0..1025"):
        h.index_of(5000)
    with pytest.raises(UnknownHypothesisError, match="washer/r00"):
        h.index_of("nonsense")
