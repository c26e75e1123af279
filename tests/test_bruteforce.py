"""Brute-force grasp hypotheses (METHOD §3b): grid, ray casting, counts, ids, store keys."""

from __future__ import annotations

import re

import numpy as np
import pytest
import trimesh

from app.bruteforce import (
    BF_HAND_VECTOR_PALM,
    BruteForceSettings,
    brute_force_hypotheses,
    cast_box_rays,
    face_grid,
    first_hits,
)
from app.design import ThumbDesign
from app.hand.model import build_hand
from app.objects import OBJECT_KEYS, load_object
from app.settings import SimSettings
from app.sweep import Task, hypotheses_of, object_key, run_task, set_object_key

ID_RE = re.compile(r"^[a-z_]+/bf/f[0-5]/i\d{2}j\d{2}/d[01]/t[0-4]$")


def test_face_grid_spacing_and_centre() -> None:
    lo, hi = np.array([-47.5, -10.0, 0.0]), np.array([47.5, 10.0, 270.0])
    for face in range(6):
        pts, ij = face_grid(lo, hi, face, 20.0)
        axis = face // 2
        assert np.allclose(pts[:, axis], hi[axis] if face % 2 == 0 else lo[axis])
        centre = 0.5 * (lo + hi)
        for a in (a for a in range(3) if a != axis):
            ticks = np.unique(pts[:, a])
            assert np.allclose(np.diff(ticks), 20.0)  # spacing d
            assert np.any(np.isclose(ticks, centre[a]))  # symmetric, holds the centre
            assert ticks.min() >= lo[a] - 1e-9 and ticks.max() <= hi[a] + 1e-9
            assert ticks.min() - 20.0 < lo[a]  # as many as fit
        assert len(np.unique(ij, axis=0)) == len(pts)


def test_first_hits_single_triangle() -> None:
    tri = np.array([[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]]])
    o = np.array([[1.0, 1.0, 5.0], [20.0, 20.0, 5.0], [1.0, -5.0, 0.0]])
    d = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    k, t = first_hits(o, d, tri, min_cos=0.1)
    assert k.tolist() == [0, -1, -1]  # hit, miss, grazing (in the triangle's plane)
    assert t[0] == pytest.approx(5.0)


def test_sphere_hits_and_misses() -> None:
    """A sphere r = 30: the grown box is ±40, grid {0, ±20, ±40}²; a ray hits iff a² + b² < r²."""
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=30.0)
    rays = cast_box_rays(mesh)
    assert rays.n_cast == 6 * 25
    assert len(rays.hit_object) == 6 * 9  # (0,0), (±20,0), (0,±20), (±20,±20)
    assert np.allclose(np.linalg.norm(rays.hit_object, axis=1), 30.0, atol=0.1)
    radial = rays.hit_object / np.linalg.norm(rays.hit_object, axis=1, keepdims=True)
    assert np.all(np.sum(radial * rays.normal_object, axis=1) > 0.99)  # outward


@pytest.mark.parametrize("key", OBJECT_KEYS)
def test_hypotheses_of_shipped_objects(key: str) -> None:
    obj = load_object(key)
    h = brute_force_hypotheses(obj)
    n_hits = len(h.hit_object)
    assert 0 < n_hits <= h.n_cast
    assert len(h) == n_hits * 2 * 5  # standoffs {0, 25} × rolls {0, π/2, π, 3π/2, 2π}
    assert len(set(h.ids)) == len(h) and all(ID_RE.match(i) for i in h.ids)
    # every hit on the surface
    assert np.max(np.abs(obj.sdf(h.hit_object))) < 0.5
    # approach = −normal: the palm normal (hand vector) points along −ray
    n_palm = np.einsum("nij,j->ni", h.R_object_palm, BF_HAND_VECTOR_PALM)
    assert np.allclose(n_palm, -h.ray_object, atol=1e-9)
    assert np.allclose(np.linalg.norm(h.ray_object, axis=1), 1.0)
    # the normal is outward: agrees with the SDF gradient away from edges
    cos = np.sum(obj.normal(h.hit_object) * h.ray_object[:: 2 * 5], axis=1)
    assert np.median(cos) > 0.99 and np.all(cos > 0.0)
    assert set(np.round(h.standoff_mm, 9)) == {0.0, 25.0}
    assert np.allclose(np.unique(h.roll_rad), [0, np.pi / 2, np.pi, 3 * np.pi / 2, 2 * np.pi])
    # the approach line of GH i goes through its own hit
    i = len(h) - 1
    line = h.approach_line(i)
    assert np.allclose(line.target_object, h.hit_object[h.ray_index[i]])


def test_rolls_turn_about_the_approach_and_duplicate_flag() -> None:
    obj = load_object("chips_can")
    h = brute_force_hypotheses(obj)
    R0, R4 = h.R_object_palm[0], h.R_object_palm[4]  # roll 0 and 2π of ray 0
    assert np.allclose(R0, R4, atol=1e-9)
    nodup = brute_force_hypotheses(obj, BruteForceSettings(drop_duplicate_roll=True))
    assert len(nodup) == len(nodup.hit_object) * 2 * 4
    assert set(nodup.ids) < set(h.ids)  # same ids minus t4: the store rows are shared


def test_store_keys_distinct() -> None:
    okey = object_key("washer")
    assert set_object_key("washer") == okey
    assert set_object_key("washer", "brute_force") == okey + ":bf"
    assert set_object_key("washer", "brute_force_nodup") == okey + ":bf"
    assert len(hypotheses_of("washer", "brute_force")) == len(
        brute_force_hypotheses(load_object("washer"))
    )


def test_run_task_closes_all_fingers_and_keeps_pose() -> None:
    h = hypotheses_of("small_marker", "brute_force")
    gh = (0, 11)
    design = ThumbDesign(0, 45)
    res = run_task(Task("small_marker", gh, (design,), SimSettings(), "brute_force"))
    assert [r[1] for r in res] == [h.ids[i] for i in gh]
    q_open = build_hand(0, 45).q_open
    for (_, _, o), i in zip(res, gh, strict=True):
        T = np.asarray(o.extra["T_object_palm"])
        assert np.allclose(T[:3, :3], h.R_object_palm[i]) and np.allclose(T[3], [0, 0, 0, 1])
        # P lies on the approach line hit + s·ray
        P = T[:3, :3] @ np.array([10.0, 70.0, 0.0]) + T[:3, 3]
        off = P - h.hit_object[h.ray_index[i]]
        assert np.linalg.norm(np.cross(off, h.ray_object[i])) < 1e-6
        # a PP object, yet middle, ring and little closed too (all fingers close)
        assert np.all((o.q_final_rad[6:] - q_open[6:]).reshape(3, 3).max(axis=1) > 0.1)
