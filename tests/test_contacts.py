"""Contact extraction: the coarse screening of link samples is exact."""

from __future__ import annotations

import numpy as np
import pytest

from app.model.hand.model import build_hand
from app.model.objects import load_object
from app.sim.contacts import _samples, near_surface


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
            # a random rotation, shifted so that a random sample of the link lies within a
            # few mm of a random surface vertex
            R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            anchor = surface[rng.integers(len(surface))]
            k = rng.integers(len(p_link))
            T = np.eye(4)
            T[:3, :3] = R
            T[:3, 3] = anchor - R @ p_link[k] + rng.normal(scale=1.0, size=3)
            centre = p_link[rng.integers(len(p_link))]
            radius = float(rng.choice([10.0, 30.0, 200.0]))
            tol = float(rng.choice([0.5, 1.0, 3.0]))
            p_obj = p_link @ R.T + T[:3, 3]
            near = ((p_link - centre) ** 2).sum(1) < radius**2
            dense = np.flatnonzero(near & (obj.sdf(p_obj) <= tol))
            got = near_surface(obj, link.shape, T, centre, radius, tol, 1.0)
            assert np.array_equal(got, dense), (key, link.name)
            checked += len(dense) > 0
    assert checked > 20  # most placements actually touch
