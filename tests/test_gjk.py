"""Compiled GJK distances (``app.sim.gjk``) against closed forms and FCL, every piece type."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from app.model.objects.shapes import _convex_fcl
from app.sim import gjk
from app.sim.closing import pair_distance

NO_VERTS = np.zeros((0, 3))


def _pose(rng: np.random.Generator, spread: float) -> tuple[np.ndarray, np.ndarray]:
    R = Rotation.from_quat(rng.normal(size=4)).as_matrix()  # uniform: normalised Gaussian
    return R, rng.normal(size=3) * spread


def _segment_distance(p0, p1, q0, q1) -> float:
    """Segment-segment distance by a fine scan and golden-section refinement (reference)."""

    def point_seg(p):
        d = q1 - q0
        t = np.clip((p - q0) @ d / (d @ d), 0.0, 1.0)
        return float(np.linalg.norm(p - q0 - t * d))

    s = np.linspace(0.0, 1.0, 401)
    f = [point_seg(p0 + (p1 - p0) * x) for x in s]
    i = int(np.argmin(f))
    lo, hi = s[max(i - 1, 0)], s[min(i + 1, 400)]
    g = (np.sqrt(5) - 1) / 2
    for _ in range(80):  # the distance along one segment is convex in s
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        if point_seg(p0 + (p1 - p0) * a) < point_seg(p0 + (p1 - p0) * b):
            hi = b
        else:
            lo = a
    return min(min(f), point_seg(p0 + (p1 - p0) * 0.5 * (lo + hi)))


def test_capsule_capsule_is_exact() -> None:
    rng = np.random.default_rng(1)
    for _ in range(150):
        Ra, ta = _pose(rng, 40)
        Rb, tb = _pose(rng, 10)
        ra, la, rb, lb = rng.uniform(3, 10), rng.uniform(5, 50), rng.uniform(3, 10), 30.0
        ref = _segment_distance(
            ta - Ra[:, 2] * la / 2,
            ta + Ra[:, 2] * la / 2,
            tb - Rb[:, 2] * lb / 2,
            tb + Rb[:, 2] * lb / 2,
        )
        d = gjk.shape_distance(
            gjk.CAPSULE, np.array([ra, la / 2, 0]), Ra, ta,
            gjk.CAPSULE, np.array([rb, lb / 2, 0]), Rb, tb, NO_VERTS, 0, 0, 0, 0,
        )  # fmt: skip
        if ref > 1e-6:
            assert d == pytest.approx(ref - ra - rb, abs=1e-8)


def test_sphere_against_box_and_cylinder_is_exact() -> None:
    rng = np.random.default_rng(2)
    half = np.array([10.0, 15.0, 20.0])
    r_cyl, h_cyl = 12.0, 25.0
    for _ in range(300):
        Rb, tb = _pose(rng, 5)
        c = rng.normal(size=3) * 30
        local = Rb.T @ (c - tb)
        box_ref = np.linalg.norm(np.maximum(np.abs(local) - half, 0.0))
        dr = max(np.hypot(local[0], local[1]) - r_cyl, 0.0)
        dz = max(abs(local[2]) - h_cyl, 0.0)
        cyl_ref = np.hypot(dr, dz)
        sph = np.array([2.0, 0, 0])
        for typ, prm, ref in (
            (gjk.BOX, half, box_ref),
            (gjk.CYLINDER, np.array([r_cyl, h_cyl, 0.0]), cyl_ref),
        ):
            d = gjk.shape_distance(
                gjk.SPHERE, sph, np.eye(3), c, typ, prm, Rb, tb, NO_VERTS, 0, 0, 0, 0
            )
            if ref > 1e-6:
                assert d == pytest.approx(ref - 2.0, abs=1e-7)


def _hull_vertices(rng: np.random.Generator) -> np.ndarray:
    pts = rng.normal(size=(40, 3)) * [20, 20, 30]
    return np.ascontiguousarray(pts[ConvexHull(pts).vertices])


@pytest.mark.parametrize("kind", ["box", "cylinder", "capsule", "convex"])
def test_capsule_against_every_piece_type_matches_fcl(kind: str) -> None:
    """FCL's distances (libccd GJK, tolerance ~1e-6 relative) err by up to ~1e-3 mm on some
    poses (against closed forms, see above), so the bound here is FCL's, not ours; the median
    shows the two agree to ~1e-7 mm."""
    rng = np.random.default_rng(3)
    verts = _hull_vertices(rng)
    geom, typ, prm = {
        "box": (fcl.Box(20, 30, 40), gjk.BOX, np.array([10.0, 15.0, 20.0])),
        "cylinder": (fcl.Cylinder(30, 80), gjk.CYLINDER, np.array([30.0, 40.0, 0.0])),
        "capsule": (fcl.Capsule(8, 40), gjk.CAPSULE, np.array([8.0, 20.0, 0.0])),
        "convex": (_convex_fcl(verts)[0], gjk.POINTS, np.zeros(3)),
    }[kind]
    diffs = []
    for _ in range(400):
        Ra, ta = _pose(rng, 60)
        Rb, tb = _pose(rng, 10)
        r, length = rng.uniform(5, 12), rng.uniform(10, 50)
        a = fcl.CollisionObject(fcl.Capsule(r, length), fcl.Transform(Ra, ta))
        b = fcl.CollisionObject(geom, fcl.Transform(Rb, tb))
        ref = pair_distance(a, b)
        d = gjk.shape_distance(
            gjk.CAPSULE, np.array([r, length / 2, 0]), Ra, ta,
            typ, prm, Rb, tb, verts, 0, 0, 0, len(verts),
        )  # fmt: skip
        if ref > 1e-3:
            diffs.append(abs(d - ref))
        elif ref < -1e-3:
            assert d <= 1e-9  # intersecting: not a positive distance
    diffs_a = np.array(diffs)
    assert len(diffs_a) > 200
    assert diffs_a.max() < 2e-3
    assert np.median(diffs_a) < 1e-6


def test_box_against_convex_matches_fcl() -> None:
    """The approach moves the palm box too."""
    rng = np.random.default_rng(4)
    verts = _hull_vertices(rng)
    geom = _convex_fcl(verts)[0]
    diffs = []
    for _ in range(300):
        Ra, ta = _pose(rng, 60)
        Rb, tb = _pose(rng, 10)
        a = fcl.CollisionObject(fcl.Box(70, 90, 20), fcl.Transform(Ra, ta))
        b = fcl.CollisionObject(geom, fcl.Transform(Rb, tb))
        ref = pair_distance(a, b)
        d = gjk.shape_distance(
            gjk.BOX, np.array([35.0, 45.0, 10.0]), Ra, ta,
            gjk.POINTS, np.zeros(3), Rb, tb, verts, 0, 0, 0, len(verts),
        )  # fmt: skip
        if ref > 1e-3:
            diffs.append(abs(d - ref))
    assert len(diffs) > 50
    assert max(diffs) < 2e-3


def test_capsule_against_cylinder_direct_route_agrees_with_gjk_and_closed_forms() -> None:
    """A capsule against a cylinder takes ``_segment_cylinder``, not GJK: on random poses the
    two agree to 1e-6 mm (both exact; GJK converges only linearly on the curved side), in
    either argument order; a capsule lying along the wall, parallel to the axis, has the
    closed form ρ − R − r, and one crossing the cylinder touches (non-positive)."""
    rng = np.random.default_rng(7)
    R_cyl, h_cyl, r_cap, h_cap = 20.0, 40.0, 6.0, 15.0
    cyl, cap = np.array([R_cyl, h_cyl, 0.0]), np.array([r_cap, h_cap, 0.0])
    n_far = 0
    for _ in range(500):
        Ra, ta = _pose(rng, 60)
        Rb, tb = _pose(rng, 10)
        d1 = gjk.shape_distance(gjk.CAPSULE, cap, Ra, ta, gjk.CYLINDER, cyl, Rb, tb,
                                NO_VERTS, 0, 0, 0, 0)  # fmt: skip
        d2 = gjk.shape_distance(gjk.CYLINDER, cyl, Rb, tb, gjk.CAPSULE, cap, Ra, ta,
                                NO_VERTS, 0, 0, 0, 0)  # fmt: skip
        ref = gjk.core_distance(gjk.CAPSULE, cap, Ra, ta, gjk.CYLINDER, cyl, Rb, tb,
                                NO_VERTS, 0, 0, 0, 0) - r_cap  # fmt: skip
        assert d1 == d2
        if ref > 1e-6:
            n_far += 1
            assert d1 == pytest.approx(ref, abs=1e-6)
        else:
            assert d1 <= 1e-6  # touching or intersecting
    assert n_far > 200
    Rb, tb = _pose(rng, 10)
    for rho in (26.5, 30.0, 55.0):  # along the wall, parallel to the axis
        for z in (0.0, 20.0, h_cyl + h_cap - 1.0):
            theta = rng.uniform(0, 2 * np.pi)
            c_local = np.array([rho * np.cos(theta), rho * np.sin(theta), z])
            d = gjk.shape_distance(gjk.CAPSULE, cap, Rb, Rb @ c_local + tb, gjk.CYLINDER, cyl,
                                   Rb, tb, NO_VERTS, 0, 0, 0, 0)  # fmt: skip
            assert d == pytest.approx(rho - R_cyl - r_cap, abs=1e-9)
    R_x = np.eye(3)[[2, 0, 1]]  # the capsule's axis along x, crossing the wall at x = 20
    across = gjk.shape_distance(gjk.CAPSULE, cap, R_x, np.array([15.0, 0, 0]), gjk.CYLINDER,
                                cyl, np.eye(3), np.zeros(3), NO_VERTS, 0, 0, 0, 0)  # fmt: skip
    assert across <= 0.0


def test_climbing_the_hull_finds_the_scanned_support() -> None:
    """A ``POINTS`` shape with a neighbour table is searched by climbing its hull's edges:
    distances equal the full scan's (to rounding) on random poses, for a dense hull with
    points inside it and on a flat face (those get no neighbours); the table is symmetric."""
    rng = np.random.default_rng(11)
    sphere = rng.normal(size=(400, 3))
    sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    pts = np.concatenate([sphere * [30, 20, 40], rng.normal(size=(50, 3)) * 3])
    pts[:30, 2] = np.minimum(pts[:30, 2], -35.0)  # a flat cap: coplanar points
    verts = np.ascontiguousarray(pts)
    nbr_start, nbr = gjk.hull_neighbours(verts)
    assert len(nbr_start) == len(verts) + 1 and nbr_start[-1] > 0
    assert nbr_start[1] == nbr_start[0]  # point 0 lies inside the flat cap: no neighbours
    pairs = {(i, int(j)) for i in range(len(verts)) for j in nbr[nbr_start[i] : nbr_start[i + 1]]}
    assert all((j, i) in pairs for i, j in pairs)
    assert np.all(np.diff(nbr_start)[400:] == 0)  # the inner points have no neighbours
    cap = np.array([6.0, 15.0, 0.0])
    n_far = 0
    for _ in range(400):
        Ra, ta = _pose(rng, 70)
        Rb, tb = _pose(rng, 10)
        args = (gjk.CAPSULE, cap, Ra, ta, gjk.POINTS, np.zeros(3), Rb, tb, verts)
        climbed = gjk.shape_distance_nbr(*args, nbr_start, nbr, 0, 0, 0, len(verts))
        scanned = gjk.shape_distance(*args, 0, 0, 0, len(verts))
        if scanned > 1e-9:
            n_far += 1
            assert climbed == pytest.approx(scanned, abs=1e-9)
        else:
            assert climbed <= 1e-9
    assert n_far > 200


def test_capsules_closed_form_agrees_with_gjk_parallel_and_crossing() -> None:
    """Capsules and spheres against each other take the closed form (``_segment_segment``):
    equal to GJK's distance to 1e-9 mm on random, parallel and nearly parallel poses; two
    parallel side-by-side capsules are their axes' distance apart less the radii."""
    rng = np.random.default_rng(5)
    n_far = 0
    for k in range(600):
        Ra, ta = _pose(rng, 30)
        Rb, tb = _pose(rng, 30)
        if k % 3 == 0:
            Rb = Ra  # parallel axes
        pa = np.array([rng.uniform(2, 8), rng.uniform(0, 25) * (k % 5 != 0), 0.0])
        pb = np.array([rng.uniform(2, 8), rng.uniform(0, 25), 0.0])
        ta_ = gjk.CAPSULE if pa[1] > 0 else gjk.SPHERE
        d = gjk.shape_distance(ta_, pa, Ra, ta, gjk.CAPSULE, pb, Rb, tb, NO_VERTS, 0, 0, 0, 0)
        ref = gjk.core_distance(ta_, pa, Ra, ta, gjk.CAPSULE, pb, Rb, tb, NO_VERTS, 0, 0, 0, 0)
        ref -= pa[0] + pb[0]
        if ref > 1e-6:
            n_far += 1
            assert d == pytest.approx(ref, abs=1e-9)
        else:
            assert d <= 1e-6
    assert n_far > 300
    R = _pose(rng, 0)[0]
    cap = np.array([5.0, 20.0, 0.0])
    side = R @ np.array([17.0, 0.0, 3.0])  # axes 17 mm apart, overlapping along z
    d = gjk.shape_distance(gjk.CAPSULE, cap, R, side, gjk.CAPSULE, cap, R, np.zeros(3),
                           NO_VERTS, 0, 0, 0, 0)  # fmt: skip
    assert d == pytest.approx(17.0 - 10.0, abs=1e-12)
