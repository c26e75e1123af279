"""Force closure and ε (app.quality.force_closure) against physics and an independent LP/QP."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from app.errors import SettingsError
from app.model.contact_set import ContactSet
from app.quality.force_closure import (
    FCSettings,
    epsilon_quality,
    evaluate_fc,
    fc_and_epsilon,
    friction_cone_edges,
    is_force_closure,
    positively_spans,
    primitive_wrenches,
)
from app.quality.force_closure_lp import distance_to_hull, is_force_closure_lp, lp_margin, support

R_SPHERE = 20.0


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _sphere_patch(direction, radius_mm: float = 3.0, k: int = 4, R: float = R_SPHERE):
    """k points on a circle of ``radius_mm`` around the sphere point along ``direction``,
    projected on the sphere; normals into the object (toward the centre)."""
    d = _unit(np.asarray(direction, dtype=float))
    a = np.eye(3)[np.argmin(np.abs(d))]
    t1 = _unit(np.cross(a, d))
    t2 = np.cross(d, t1)
    ang = 2 * np.pi * np.arange(k) / k
    q = R * d + radius_mm * (np.cos(ang)[:, None] * t1 + np.sin(ang)[:, None] * t2)
    p = R * _unit(q)
    return p, -p / R


def _contacts(p: np.ndarray, n: np.ndarray) -> ContactSet:
    k = len(p)
    return ContactSet(
        np.asarray(p, float),
        np.asarray(n, float),
        np.array(["index_distal"] * k, dtype=object),
        np.ones(k, dtype=bool),
    )


def _fc(p, n, mu=0.4, n_edges=8, c=None, r=R_SPHERE):
    c = np.zeros(3) if c is None else c
    return fc_and_epsilon(primitive_wrenches(p, n, c, r, mu, n_edges))


# ---------------------------------------------------------------- cone edges and wrenches


def test_cone_edges_geometry():
    rng = np.random.default_rng(0)
    n = _unit(rng.normal(size=(50, 3)))
    mu = 0.4
    e = friction_cone_edges(n, mu, 8)
    assert e.shape == (50, 8, 3)
    # unit normal component, tangential part of length mu: every edge on the true cone
    np.testing.assert_allclose(np.einsum("kej,kj->ke", e, n), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(e, axis=2), np.sqrt(1 + mu**2), atol=1e-12)
    # evenly spread: the edges sum to 8 n (the tangential parts cancel)
    np.testing.assert_allclose(e.sum(axis=1), 8 * n, atol=1e-12)


def test_primitive_wrenches_layout():
    p = np.array([[10.0, 0, 0], [0, 5.0, 0]])
    n = np.array([[-1.0, 0, 0], [0, -1.0, 0]])
    c = np.array([1.0, 2.0, 3.0])
    W = primitive_wrenches(p, n, c, 4.0, 0.3, 6)
    assert W.shape == (12, 6)
    f = friction_cone_edges(n, 0.3, 6).reshape(-1, 3)
    np.testing.assert_allclose(W[:, :3], f)
    arm = np.repeat(p - c, 6, axis=0)
    np.testing.assert_allclose(W[:, 3:], np.cross(arm, f) / 4.0)


# ---------------------------------------------------------------- physics


def test_two_antipodal_points_not_fc():
    # Every force passes through the line joining the two points: no torque about it (rank 5).
    p = np.array([[R_SPHERE, 0, 0], [-R_SPHERE, 0, 0]])
    is_fc, eps = _fc(p, -p / R_SPHERE)
    assert not is_fc and eps == 0.0
    assert not is_force_closure_lp(primitive_wrenches(p, -p / R_SPHERE, np.zeros(3), R_SPHERE))


def test_two_antipodal_patches_fc():
    # Two 3 mm patches: friction at points off the axis resists the torque about it.
    p1, n1 = _sphere_patch([1, 0, 0])
    p2, n2 = _sphere_patch([-1, 0, 0])
    is_fc, eps = _fc(np.vstack([p1, p2]), np.vstack([n1, n2]))
    assert is_fc and eps > 0
    # ... and the torsional resistance vanishes with the patch radius: ε shrinks with it
    q1, m1 = _sphere_patch([1, 0, 0], radius_mm=0.3)
    q2, m2 = _sphere_patch([-1, 0, 0], radius_mm=0.3)
    is_fc_small, eps_small = _fc(np.vstack([q1, q2]), np.vstack([m1, m2]))
    assert is_fc_small and 0 < eps_small < eps


def test_three_contacts_on_equator_fc():
    # Physics: the three normals (120° apart) balance each other (an internal squeeze strictly
    # inside every cone), and the contact forces span all wrenches: in-plane tangential
    # friction gives torque about z (lever R), vertical friction gives force along z and
    # torque about the in-plane axes. So hard-finger point contacts with μ = 0.4 ARE FC;
    # torsional (soft-finger) resistance is only needed when all contacts are collinear.
    ang = np.radians([0.0, 120.0, 240.0])
    p = R_SPHERE * np.c_[np.cos(ang), np.sin(ang), np.zeros(3)]
    is_fc, eps = _fc(p, -p / R_SPHERE)
    assert is_fc and eps > 0
    # the same three contacts 60°/60°/240° apart: the normals cannot balance → not FC
    ang = np.radians([0.0, 60.0, 120.0])
    p = R_SPHERE * np.c_[np.cos(ang), np.sin(ang), np.zeros(3)]
    assert not _fc(p, -p / R_SPHERE)[0]


def test_cylinder_wrap_fc():
    R, H = 30.0, 120.0
    th, z = np.meshgrid(np.radians([0, 70, 150, 220, 290]), [20.0, 60.0, 100.0])
    th, z = th.ravel(), z.ravel()
    p = np.c_[R * np.cos(th), R * np.sin(th), z]
    n = -np.c_[np.cos(th), np.sin(th), np.zeros_like(th)]
    c = np.array([0, 0, H / 2])
    is_fc, eps = _fc(p, n, c=c, r=float(np.hypot(R, H / 2)))
    assert is_fc and eps > 0


def test_contacts_on_a_cap_not_fc():
    # All contacts within 60° of the north pole, normals toward the centre: every cone edge
    # has z component −cos θ + μ sin θ < 0 (tan 60° < 1/μ = 2.5), so no contact force can
    # push the object up: the wrench +z is unreachable.
    rng = np.random.default_rng(1)
    theta = np.radians(rng.uniform(5, 60, 12))
    phi = rng.uniform(0, 2 * np.pi, 12)
    d = np.c_[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]
    p = R_SPHERE * d
    W = primitive_wrenches(p, -d, np.zeros(3), R_SPHERE)
    assert np.all(W[:, 2] < 0)
    is_fc, eps = fc_and_epsilon(W)
    assert not is_fc and eps <= 0
    assert not is_force_closure_lp(W)


def test_frictionless_four_contacts_not_fc():
    # μ → 0: each cone collapses onto its normal, 4 wrenches span at most 4 of 6 dimensions
    # (frictionless form closure needs at least 7 contacts).
    rng = np.random.default_rng(2)
    p = rng.uniform(-20, 20, (4, 3))
    n = _unit(-p + rng.normal(0, 3, (4, 3)))
    for mu in (1e-12, 1e-14):
        W = primitive_wrenches(p, n, np.zeros(3), 30.0, mu, 8)
        assert not is_force_closure(W)
        assert not is_force_closure_lp(W)


def test_degenerate_inputs():
    assert not is_force_closure(np.zeros((0, 6)))
    assert not is_force_closure(np.eye(6))  # 6 points < 7
    assert not is_force_closure(np.zeros((20, 6)))
    assert not is_force_closure(np.full((20, 6), np.nan))
    # rank 5: a symmetric set in 5 dimensions (origin inside its 5-D hull, still not FC)
    W5 = np.vstack([np.eye(6)[:5], -np.eye(6)[:5]])
    assert not is_force_closure(W5) and epsilon_quality(W5) == 0.0
    # rank 6, origin strictly inside: the cross-polytope, ε = 1/sqrt(6)
    W6 = np.vstack([np.eye(6), -np.eye(6)])
    assert is_force_closure(W6)
    assert epsilon_quality(W6) == pytest.approx(1 / np.sqrt(6), rel=1e-12)
    # origin exactly on a facet (one side removed) → not strictly inside
    W_on = np.vstack([np.eye(6), -np.eye(6)[:5], np.zeros((1, 6))])
    assert not is_force_closure(W_on)
    assert evaluate_fc(_contacts(np.zeros((0, 3)), np.zeros((0, 3))), np.zeros(3), 1.0) == (
        False,
        0.0,
        0,
    )


# ---------------------------------------------------------------- random cross-check with LP


def _random_contact_set(rng: np.random.Generator, i: int):
    """Mixed random grasps, several near-degenerate, as (p, n, mu)."""
    kind = i % 5
    if kind == 0:  # points on a sphere, normals inward, random μ
        k = int(rng.integers(2, 7))
        p = R_SPHERE * _unit(rng.normal(size=(k, 3)))
        return p, -p / R_SPHERE, float(rng.uniform(0.1, 0.8))
    if kind == 1:  # box-ish object, normals roughly inward with noise
        k = int(rng.integers(3, 8))
        p = rng.uniform(-20, 20, (k, 3))
        n = _unit(-_unit(p) + rng.uniform(0, 1.5) * rng.normal(size=(k, 3)))
        return p, n, float(rng.uniform(0.05, 0.8))
    if kind == 2:  # near-degenerate: two antipodal patches of tiny radius, slightly tilted
        rad = float(10.0 ** rng.uniform(-3, 0))
        d = _unit(rng.normal(size=3))
        p1, n1 = _sphere_patch(d, rad, 3)
        p2, n2 = _sphere_patch(-d + rng.normal(0, 0.05, 3), rad, 3)
        return np.vstack([p1, p2]), np.vstack([n1, n2]), float(rng.uniform(0.1, 0.6))
    if kind == 3:  # near-degenerate: nearly coplanar contacts with in-plane normals
        k = int(rng.integers(3, 7))
        ang = rng.uniform(0, 2 * np.pi, k)
        p = np.c_[R_SPHERE * np.cos(ang), R_SPHERE * np.sin(ang), rng.normal(0, 1e-4, k)]
        return p, -_unit(p * [1, 1, 0]), float(rng.uniform(0.05, 0.6))
    # kind 4: contacts on a spherical cap of random extent (FC only for wide caps)
    k = int(rng.integers(3, 8))
    top = rng.uniform(40, 120)
    theta = np.radians(rng.uniform(0, top, k))
    phi = rng.uniform(0, 2 * np.pi, k)
    d = np.c_[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]
    return R_SPHERE * d, -d, float(rng.uniform(0.1, 0.8))


def test_qhull_lp_and_positive_span_agree_on_random_sets():
    rng = np.random.default_rng(12345)
    disagree, n_fc, n_not = [], 0, 0
    for i in range(250):
        p, n, mu = _random_contact_set(rng, i)
        W = primitive_wrenches(p, n, np.zeros(3), R_SPHERE, mu, 8)
        a, b, c = is_force_closure(W), is_force_closure_lp(W), positively_spans(W)
        if not a == b == c:
            disagree.append((i, a, b, c))
        n_fc += a
        n_not += not a
    assert disagree == []
    assert n_fc >= 20 and n_not >= 20, (n_fc, n_not)


# ---------------------------------------------------------------- invariances


def _fc_grasp() -> tuple[ContactSet, np.ndarray, float]:
    """A FC grasp on a sphere offset from the origin: two patches and a third contact."""
    c = np.array([5.0, -3.0, 40.0])
    p1, n1 = _sphere_patch([1, 0.2, 0])
    p2, n2 = _sphere_patch([-1, 0, 0.3])
    p3, n3 = _sphere_patch([0, 1, -0.4], 1.0, 3)
    return _contacts(np.vstack([p1, p2, p3]) + c, np.vstack([n1, n2, n3])), c, R_SPHERE


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Uniform random rotation (QR of a Gaussian matrix, signs fixed, det +1)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _pose(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def test_invariant_under_translation_and_axis_rotations():
    # Exact invariance: translations, and the 24 rotations permuting the axes (the cone
    # edges then map onto themselves; see friction_cone_edges).
    cs, c, r = _fc_grasp()
    ref = evaluate_fc(cs, c, r, with_epsilon=True)
    assert ref.is_fc
    rng = np.random.default_rng(3)
    rots = [
        np.eye(3)[list(perm)] * np.array(signs)[:, None]
        for perm in itertools.permutations(range(3))
        for signs in itertools.product((1, -1), repeat=3)
    ]
    rots = [R for R in rots if np.linalg.det(R) > 0]
    assert len(rots) == 24
    for R in rots:
        T = _pose(R, rng.uniform(-100, 100, 3))
        got = evaluate_fc(cs.transformed(T), T[:3, :3] @ c + T[:3, 3], r, with_epsilon=True)
        assert got.is_fc
        assert got.epsilon == pytest.approx(ref.epsilon, rel=1e-9)


def test_invariant_under_random_rigid_motion_within_linearisation_bounds():
    # A general rotation turns each 8-edge polygon about its normal, so ε moves, but only
    # inside the bounds given by replacing each polygon by discs: the 8-gon contains the disc
    # of radius μ cos(π/8) and lies inside the disc of radius μ. Bounds computed with 16-gons
    # inscribed in the inner disc (a subset) and circumscribed about the outer one (a
    # superset); ε is monotone under inclusion of the wrench hull.
    cs, c, r = _fc_grasp()
    mu = 0.4
    W_lo = primitive_wrenches(cs.p_object, cs.n_object, c, r, mu * np.cos(np.pi / 8), 16)
    W_hi = primitive_wrenches(cs.p_object, cs.n_object, c, r, mu / np.cos(np.pi / 16), 16)
    eps_lo, eps_hi = epsilon_quality(W_lo), epsilon_quality(W_hi)
    assert 0 < eps_lo < eps_hi
    rng = np.random.default_rng(4)
    for _ in range(10):
        R = _random_rotation(rng)
        T = _pose(R, rng.uniform(-200, 200, 3))
        got = evaluate_fc(cs.transformed(T), R @ c + T[:3, 3], r, with_epsilon=True)
        assert got.is_fc
        assert eps_lo * (1 - 1e-9) <= got.epsilon <= eps_hi * (1 + 1e-9)


def test_r_scaling_changes_eps_not_fc_and_uniform_scaling_changes_nothing():
    cs, c, r = _fc_grasp()
    ref = evaluate_fc(cs, c, r, with_epsilon=True)
    for k in (0.25, 0.5, 2.0, 10.0):
        got = evaluate_fc(cs, c, r * k, with_epsilon=True)
        assert got.is_fc == ref.is_fc
        assert got.epsilon != pytest.approx(ref.epsilon, rel=1e-3)
    # same geometry in other units (mm → m): W identical, so ε identical
    metres = ContactSet(cs.p_object * 1e-3, cs.n_object, cs.link, cs.palmar)
    got = evaluate_fc(metres, c * 1e-3, r * 1e-3, with_epsilon=True)
    assert got.epsilon == pytest.approx(ref.epsilon, rel=1e-9)


# ---------------------------------------------------------------- ε against the LP / QP


def test_epsilon_positive_iff_fc_and_matches_support_function():
    rng = np.random.default_rng(7)
    checked_fc = checked_not = 0
    for i in range(60):
        p, n, mu = _random_contact_set(rng, i)
        W = primitive_wrenches(p, n, np.zeros(3), R_SPHERE, mu, 8)
        is_fc, eps = fc_and_epsilon(W)
        assert (eps > 0) == is_fc or abs(eps) < 1e-12
        if is_fc:
            checked_fc += 1
            # every direction's support value bounds ε from above ...
            U = rng.normal(size=(5000, 6))
            assert support(W, U).min() >= eps - 1e-12
            # ... and the closest facet's normal attains it
            eq = ConvexHull(W).equations
            u_star = eq[np.argmin(-eq[:, -1]), :6]
            assert support(W, u_star[None])[0] == pytest.approx(eps, rel=1e-9)
            assert lp_margin(W) > 0
        elif np.linalg.matrix_rank(W) == 6:
            checked_not += 1
            # origin outside (or on) the hull: its distance bounds the worst violation −ε
            dist, _ = distance_to_hull(W)
            assert dist >= -eps - 1e-6
    assert checked_fc >= 5 and checked_not >= 5


def test_epsilon_is_inscribed_radius_by_qp():
    cs, c, r = _fc_grasp()
    W = primitive_wrenches(cs.p_object, cs.n_object, c, r)
    eps = epsilon_quality(W)
    rng = np.random.default_rng(8)
    # points at 0.98 ε in random directions are inside the hull ...
    for u in _unit(rng.normal(size=(10, 6))):
        assert distance_to_hull(W, 0.98 * eps * u)[0] < 1e-6
    # ... and beyond ε along the closest facet normal they are outside
    eq = ConvexHull(W).equations
    u_star = eq[np.argmin(-eq[:, -1]), :6]
    d_out, _ = distance_to_hull(W, 1.05 * eps * u_star)
    assert d_out == pytest.approx(0.05 * eps, rel=1e-3)
    # the origin of a non-FC set (cap grasp) is a positive distance away
    theta = np.radians([10.0, 30.0, 50.0, 40.0])
    phi = np.radians([0.0, 100.0, 200.0, 300.0])
    d = np.c_[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]
    W_cap = primitive_wrenches(R_SPHERE * d, -d, np.zeros(3), R_SPHERE)
    assert distance_to_hull(W_cap)[0] > 0.1


# ---------------------------------------------------------------- settings


def test_fc_settings_validation():
    assert FCSettings().mu == 0.4 and FCSettings().n_edges == 8
    for bad in ({"mu": 0.0}, {"mu": -1.0}, {"mu": float("nan")}, {"n_edges": 2}):
        with pytest.raises(SettingsError, match=r"> 0|>= 3"):
            FCSettings(**bad)  # type: ignore[arg-type]
    with pytest.raises(SettingsError):
        FCSettings(n_edges=8.5)  # type: ignore[arg-type]


def test_evaluate_fc_uses_settings():
    cs, c, r = _fc_grasp()
    res = evaluate_fc(cs, c, r, FCSettings(mu=0.4, n_edges=6), with_epsilon=True)
    assert res.n_points == len(cs) * 6 and res.is_fc
    # less friction, less ε
    assert (
        evaluate_fc(cs, c, r, FCSettings(mu=0.2), with_epsilon=True).epsilon
        < evaluate_fc(cs, c, r, with_epsilon=True).epsilon
    )


def test_fast_decision_matches_qhull_on_the_analytic_cases():
    """evaluate_fc's default (positive span) and qhull agree on every case of this file."""
    for p_dir in ([1, 0, 0], [0, 1, 0.2]):
        p1, n1 = _sphere_patch(p_dir)
        p2, n2 = _sphere_patch(-np.asarray(p_dir, float))
        cs = _contacts(np.vstack([p1, p2]), np.vstack([n1, n2]))
        fast = evaluate_fc(cs, np.zeros(3), R_SPHERE)
        full = evaluate_fc(cs, np.zeros(3), R_SPHERE, with_epsilon=True)
        assert fast.is_fc == full.is_fc and np.isnan(fast.epsilon)
