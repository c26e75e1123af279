"""Contact extraction: the coarse screening of link samples is exact."""

from __future__ import annotations

import numpy as np
import pytest

from app.contacts import _samples, near_surface
from app.hand.model import build_hand
from app.objects import load_object


@pytest.mark.parametrize("key", ["power_drill", "plastic_pear", "washer", "chips_can"])
def test_screened_patch_points_equal_dense_evaluation(key: str) -> None:
    """Links placed with random poses touching or grazing the object: the screened selection
    equals evaluating the SDF on every candidate sample."""
    obj = load_object(key)
    hand = build_hand(0.0, 45.0)
    rng = np.random.default_rng(7)
    surface = obj.mesh.vertices
    checked = 0
    for link in hand.links:
        p_link, _ = _samples(link.shape, 1.0)
        for _ in range(6):
            # rotate randomly, then shift so the link's sample nearest the object lies
            # within a few mm of a random surface vertex
            q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            p = p_link @ q.T
            anchor = surface[rng.integers(len(surface))]
            p = p + (anchor - p[rng.integers(len(p))]) + rng.normal(scale=1.0, size=3)
            cand = rng.random(len(p)) < 0.9
            tol = float(rng.choice([0.5, 1.0, 3.0]))
            dense = np.flatnonzero(cand & (obj.sdf(p) <= tol))
            got = near_surface(obj, link.shape, p, cand, tol, 1.0)
            assert np.array_equal(got, dense), (key, link.name)
            checked += len(dense) > 0
    assert checked > 20  # most placements actually touch
