"""The ten GQMs: analytic cases, ε against a QP and the full hull (the grown-hull ε), the
hand Jacobian against finite differences."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from app.model.contact_set import ContactSet
from app.model.hand.model import Hand, build_hand
from app.quality.force_closure import fc_and_epsilon, primitive_wrenches
from app.quality.force_closure_lp import distance_to_hull
from app.quality.gqm import GQM_NAMES, GQM_VERSION, GQMSettings, compute_gqms
from app.quality.gqm.a1 import q_a1
from app.quality.gqm.a2 import q_a2
from app.quality.gqm.a3 import q_a3
from app.quality.gqm.b1 import q_b1
from app.quality.gqm.b2 import q_b2
from app.quality.gqm.b3 import q_b3
from app.quality.gqm.c1 import q_c1
from app.quality.gqm.c2 import q_c2
from app.quality.gqm.contacts import link_contacts
from app.quality.gqm.d1 import q_d1
from app.quality.gqm.d2 import hand_object_jacobian, q_d2
from app.quality.gqm.epsilon import TOL_REL, grown_epsilon
from app.quality.gqm.grasp_matrix import grasp_matrix, grasp_singular_values
from app.quality.gqm.hand_jacobian import hand_jacobian
from app.quality.gqm.wrench_space import grasp_wrench_space, wrench_hull
from app.sim.hypotheses import rotation_about
from tests.utils import Body

R_OBJ = 30.0


def ring(n: int, r: float = R_OBJ, z: float = 0.0) -> np.ndarray:
    """(n, 3) points evenly on a circle of radius r in the plane z."""
    a = 2 * np.pi * np.arange(n) / n
    return np.stack([r * np.cos(a), r * np.sin(a), np.full(n, z)], axis=1)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    return rotation_about(rng.normal(size=3), float(rng.uniform(0, np.pi)))


# ----------------------------------------------------------------------------- Q_A
def test_grasp_matrix_maps_forces_to_wrenches() -> None:
    rng = np.random.default_rng(0)
    p, f, c = rng.normal(size=(4, 3)) * 20, rng.normal(size=(4, 3)), rng.normal(size=3)
    G = grasp_matrix(p, c, 25.0)
    w = G @ f.ravel()
    assert np.allclose(w[:3], f.sum(0))
    assert np.allclose(w[3:], np.cross(p - c, f).sum(0) / 25.0)


def test_symmetric_three_contacts_singular_values() -> None:
    """3 contacts at 120° on a circle of radius r about c: G Gᵀ = diag(3, 3, 3, 1.5, 1.5, 3)."""
    sv = grasp_singular_values(ring(3), np.zeros(3), R_OBJ)
    assert np.allclose(np.sort(sv), np.sqrt([1.5, 1.5, 3, 3, 3, 3]))
    assert q_a1(sv) == pytest.approx(math.sqrt(1.5))
    assert q_a2(sv) == pytest.approx(13.5)  # √(3⁴ · 1.5²)
    assert q_a3(sv) == pytest.approx(1 / math.sqrt(2))


def test_two_contacts_are_singular() -> None:
    sv = grasp_singular_values(ring(2), np.zeros(3), R_OBJ)  # squeezing along the line is free
    assert q_a1(sv) == pytest.approx(0.0, abs=1e-12)
    assert q_a2(sv) == pytest.approx(0.0, abs=1e-12) and q_a3(sv) == pytest.approx(0, abs=1e-12)


# ----------------------------------------------------------------------------- Q_B
def test_q_b1_centroid() -> None:
    assert q_b1(ring(3), np.zeros(3), R_OBJ) == pytest.approx(1.0)
    assert q_b1(ring(4) + [0, 0, 15.0], np.zeros(3), R_OBJ) == pytest.approx(0.5)
    assert q_b1(ring(4) + [0, 0, 90.0], np.zeros(3), R_OBJ) == 0.0  # clipped


def test_q_b2_area_in_any_plane() -> None:
    tri = np.array([[0.0, 0, 0], [30, 0, 0], [0, 40, 0]])
    rng = np.random.default_rng(1)
    R = random_rotation(rng)
    assert q_b2(tri @ R.T + [5, 6, 7]) == pytest.approx(600.0)
    # a point inside the triangle does not change the convex polygon
    assert q_b2(np.vstack([tri, [[5.0, 5, 0]]])) == pytest.approx(600.0)
    # a regular hexagon of circumradius 30
    assert q_b2(ring(6)) == pytest.approx(1.5 * math.sqrt(3) * 30**2)
    assert q_b2(ring(2)) == 0.0 and q_b2(np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2]])) == 0.0


def test_q_b3_shape() -> None:
    for n in (3, 4, 5, 8):
        assert q_b3(ring(n)) == pytest.approx(1.0)  # regular polygons
    # right isosceles triangle: angles 90, 45, 45 against 60: Σ = 60°, θ_max = 120 + 120
    assert q_b3(np.array([[0.0, 0, 0], [10, 0, 0], [0, 10, 0]])) == pytest.approx(0.75)
    flat = np.array([[0.0, 0, 0], [100, 0, 0], [50, 0.5, 0]])
    assert 0.0 <= q_b3(flat) < 0.05
    assert q_b3(ring(2)) == 0.0


# ----------------------------------------------------------------------------- Q_C
def fc_sphere_contacts() -> tuple[np.ndarray, np.ndarray]:
    """Six contacts on a sphere of radius R_OBJ at ±axes, a little off, normals inward."""
    p = np.vstack([np.eye(3), -np.eye(3)]) * R_OBJ
    p = p + np.array([[0, 3, 0], [0, 0, 3], [3, 0, 0], [0, -3, 0], [0, 0, -3], [-3, 0, 0]])
    p = R_OBJ * p / np.linalg.norm(p, axis=1, keepdims=True)
    return p, -p / R_OBJ


def test_q_c1_matches_fc_and_epsilon_and_qp() -> None:
    p, n = fc_sphere_contacts()
    W = primitive_wrenches(p, n, np.zeros(3), R_OBJ)
    ws = wrench_hull(W)
    eps = q_c1(W)
    fc, eps_ref = fc_and_epsilon(W)
    assert fc and eps > 0 and eps == pytest.approx(eps_ref, rel=1e-9)
    assert ws.epsilon == pytest.approx(eps_ref, rel=1e-12)
    rng = np.random.default_rng(2)
    U = rng.normal(size=(12, 6))
    U /= np.linalg.norm(U, axis=1, keepdims=True)
    for u in U:  # points at 0.98 ε in random directions are inside the hull
        assert distance_to_hull(W, 0.98 * eps * u)[0] < 1e-6
    k = int(np.argmin(-ws.equations[:, -1]))
    u_star = ws.equations[k, :6]
    assert distance_to_hull(W, 1.05 * eps * u_star)[0] > 1e-4  # ... beyond the closest facet
    # not FC (all contacts on one hemisphere, pushing the same way): Q_C1 = 0
    W_half = primitive_wrenches(p[:3], n[:3], np.zeros(3), R_OBJ)
    assert q_c1(W_half) == 0.0 and wrench_hull(W_half).epsilon < 0


def test_q_c2_cross_polytope_volume() -> None:
    W = np.vstack([np.eye(6), -np.eye(6)])
    assert q_c2(wrench_hull(W)) == pytest.approx(2**6 / math.factorial(6))
    assert q_c2(wrench_hull(W[:6])) == 0.0  # 6 points: no 6-D volume


# ----------------------------------------------------------------------------- Q_D
def test_q_d1_posture() -> None:
    lo, hi = np.zeros(4), np.array([1.0, 2.0, 3.0, 4.0])
    assert q_d1(0.5 * (lo + hi), lo, hi, range(4)) == pytest.approx(1.0)
    assert q_d1(lo, lo, hi, range(4)) == pytest.approx(0.0)
    assert q_d1(hi, lo, hi, range(4)) == pytest.approx(0.0)
    assert q_d1(0.25 * hi, lo, hi, range(4)) == pytest.approx(0.5)
    assert q_d1(np.array([0.5, 0, 0, 0]), lo, hi, [0]) == pytest.approx(1.0)  # joint subset


def _grasp_on_hand(seed: int) -> tuple[Hand, SimpleNamespace, np.ndarray]:
    """A hand at a random mid posture, contacts on 5 links, posed by a random T."""
    hand = build_hand(15, 60)
    rng = np.random.default_rng(seed)
    q = hand.q_lower + rng.uniform(0.2, 0.8, 15) * (hand.q_upper - hand.q_lower)
    links = ["palm", "thumb_distal", "index_distal", "middle_middle", "ring_proximal"]
    poses = hand.link_poses(q)
    p_link = rng.uniform(-3, 3, size=(len(links), 3)) + [0, 12, 0]
    p_palm = np.array(
        [poses[hand.link_index[n]] @ np.append(pl, 1) for n, pl in zip(links, p_link, strict=True)]
    )[:, :3]
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng)
    T[:3, 3] = rng.normal(size=3) * 50
    p_obj = p_palm @ T[:3, :3].T + T[:3, 3]
    link = np.empty(len(links), dtype=object)
    link[:] = links
    n_obj = rng.normal(size=(len(links), 3))
    n_obj /= np.linalg.norm(n_obj, axis=1, keepdims=True)
    cs = ContactSet(p_obj, n_obj, link, np.ones(len(links), bool))
    return hand, SimpleNamespace(q=q, T_object_palm=T, contacts=cs), p_link


def test_hand_jacobian_finite_differences() -> None:
    hand, g, p_link = _grasp_on_hand(3)
    lc = link_contacts(g.contacts)
    J = hand_jacobian(hand, g.q, g.T_object_palm, lc.links, lc.p)
    order = {n: i for i, n in enumerate(["palm", "thumb_distal", "index_distal",
                                          "middle_middle", "ring_proximal"])}  # fmt: skip
    pl = np.array([p_link[order[n]] for n in lc.links])

    def points(q: np.ndarray) -> np.ndarray:
        poses = g.T_object_palm @ hand.link_poses(q)
        return np.concatenate(
            [(poses[hand.link_index[n]] @ np.append(x, 1))[:3] for n, x in zip(lc.links, pl,
                                                                                  strict=True)]
        )  # fmt: skip

    h = 1e-6
    J_fd = np.stack(
        [(points(g.q + h * e) - points(g.q - h * e)) / (2 * h) for e in np.eye(15)], axis=1
    )
    assert np.allclose(J, J_fd, atol=1e-5)
    assert np.allclose(J[:3], 0.0)  # the palm does not move


def test_q_d2_frame_invariant_and_bounded() -> None:
    hand, g, _ = _grasp_on_hand(4)
    lc = link_contacts(g.contacts)
    c = np.array([1.0, 2.0, 3.0])
    G = grasp_matrix(lc.p, c, R_OBJ)
    J = hand_jacobian(hand, g.q, g.T_object_palm, lc.links, lc.p)
    d2 = q_d2(G, J)
    assert 0.0 < d2 <= 1.0
    # the same grasp seen from another object frame
    T2 = np.eye(4)
    T2[:3, :3] = random_rotation(np.random.default_rng(9))
    T2[:3, 3] = [10.0, -20.0, 5.0]
    p2 = lc.p @ T2[:3, :3].T + T2[:3, 3]
    G2 = grasp_matrix(p2, T2[:3, :3] @ c + T2[:3, 3], R_OBJ)
    J2 = hand_jacobian(hand, g.q, T2 @ g.T_object_palm, lc.links, p2)
    assert q_d2(G2, J2) == pytest.approx(d2, rel=1e-9)
    # H q̇ is the least-squares object twist consistent with the contact velocities
    H = hand_object_jacobian(G, J)
    qd = np.random.default_rng(5).normal(size=15)
    nu = np.linalg.lstsq(G.T, J @ qd, rcond=None)[0]
    assert np.allclose(H @ qd, nu)


# ----------------------------------------------------------------------------- all ten
def test_compute_gqms_keys_and_link_model() -> None:
    hand, g, _ = _grasp_on_hand(6)
    obj = Body(centroid_object=np.mean(g.contacts.p_object, axis=0), max_radius=80.0)
    vals = compute_gqms(g, obj, hand)  # type: ignore[arg-type]
    assert tuple(vals) == GQM_NAMES and all(np.isfinite(v) for v in vals.values())
    for k in ("Q_A3", "Q_B1", "Q_B3", "Q_D1", "Q_D2"):
        assert 0.0 <= vals[k] <= 1.0
    assert vals["Q_D1"] == pytest.approx(q_d1(g.q, hand.q_lower, hand.q_upper, range(15)))
    # one contact per link: the 'patch' and 'link' wrench spaces coincide here
    link = compute_gqms(g, obj, hand, GQMSettings(wrench_contacts="link"))  # type: ignore[arg-type]
    assert link["Q_C2"] == pytest.approx(vals["Q_C2"]) and link["Q_C1"] == vals["Q_C1"]


def test_link_contacts_reduce_patches() -> None:
    p = np.array([[0.0, 0, 0], [2, 0, 0], [10, 0, 0], [5, 5, 5]])
    n = np.array([[0.0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0, -1]])
    link = np.array(["index_distal", "index_distal", "palm", "thumb_distal"], dtype=object)
    lc = link_contacts(ContactSet(p, n, link, np.ones(4, bool)))
    assert lc.links == ("palm", "thumb_distal", "index_distal")  # LINK_NAMES order
    assert np.allclose(lc.p[2], [1, 0, 0])
    assert np.allclose(lc.n[2], np.array([0, 1, 1]) / math.sqrt(2))
    ws = grasp_wrench_space(lc.p, lc.n, np.zeros(3), 10.0, 0.4, 8)
    assert ws.W.shape == (3 * 8, 6)


# ----------------------------------------------------------------------------- wrench hull
CAN_R, CAN_CENTROID, CAN_MAX_R = 37.5, np.array([0.0, 0.0, 125.0]), 130.5


def can_grip(rng: np.random.Generator, n_links: int) -> tuple[np.ndarray, np.ndarray]:
    """Real-looking cylindrical-grip contacts (the chips can, r 37.5 mm): ``n_links`` patches
    of 6 points within ±5° and ±4 mm on the can with inward radial normals, spread around it,
    and a flat palm patch of 6 points sharing one normal (the palm against the can's side)."""
    p, n = [], []
    slots = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(n_links + 1) / (n_links + 1)
    for k in range(n_links):  # the links wrap around the can, the palm takes the last slot
        phi = slots[k] + rng.uniform(-0.09, 0.09, 6)
        z = rng.uniform(80, 170) + rng.uniform(-4, 4, 6)
        radial = np.stack([np.cos(phi), np.sin(phi), np.zeros(6)], axis=1)
        p.append(CAN_R * radial + np.stack([0 * z, 0 * z, z], axis=1))
        n.append(-radial)
    phi0, z0 = slots[-1], rng.uniform(80, 170)
    radial = np.array([np.cos(phi0), np.sin(phi0), 0.0])
    tangent = np.array([-np.sin(phi0), np.cos(phi0), 0.0])
    uv = rng.uniform(-3, 3, size=(6, 2))
    p.append(CAN_R * radial + [0, 0, z0] + uv[:, :1] * tangent + uv[:, 1:] * [0, 0, 1.0])
    n.append(np.tile(-radial, (6, 1)))
    return np.concatenate(p), np.concatenate(n)


def plain_hull(W: np.ndarray) -> tuple[float, float] | None:
    """ε and volume of scipy's ConvexHull with default options (None if qhull fails)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        h = ConvexHull(W)
    except QhullError:
        return None
    return float(np.min(-h.equations[:, -1])), float(h.volume)


@pytest.mark.parametrize("case", ["random", "can"])
def test_wrench_hull_equals_plain_qhull(case: str) -> None:
    """Q_C1/Q_C2's hull gives scipy's plain ConvexHull ε and volume (1e-9 relative), and
    every primitive wrench lies inside every facet (a correct hull, not just a repeatable one)."""
    rng = np.random.default_rng(11)
    for _ in range(2):
        if case == "random":
            p = rng.normal(size=(12, 3))
            p = R_OBJ * p / np.linalg.norm(p, axis=1, keepdims=True)
            n = -p / R_OBJ + rng.normal(scale=0.3, size=(12, 3))
            n /= np.linalg.norm(n, axis=1, keepdims=True)
            W = primitive_wrenches(p, n, np.zeros(3), R_OBJ)
        else:
            p, n = can_grip(rng, 4)
            W = primitive_wrenches(p, n, CAN_CENTROID, CAN_MAX_R)
        ws = wrench_hull(W)
        ref = plain_hull(W)
        if ref is None:  # qhull's precision error: the hull is retried with QJ
            assert ws.volume > 0
            continue
        eps, vol = ref
        assert ws.epsilon == pytest.approx(eps, rel=1e-9) and eps > 0
        assert ws.volume == pytest.approx(vol, rel=1e-9) and vol > 0
        viol = W @ ws.equations[:, :6].T + ws.equations[:, 6]
        assert np.max(viol) < 1e-12 * np.max(np.abs(W))
        assert q_c1(W) == pytest.approx(ws.epsilon, rel=1e-9) and q_c2(ws) == ws.volume


def test_gqm_settings_key() -> None:
    a, b = GQMSettings(), GQMSettings(wrench_contacts="link")
    assert a.key() == GQMSettings().key() and a.key() != b.key()
    assert a.key() != GQMSettings(mu=0.5).key() and len(a.key()) == 16


# ----------------------------------------------------------------------------- grown ε
def cross_polytope(t: np.ndarray | None = None) -> np.ndarray:
    """±e_i (6-D), translated by t: facets s·x ≤ 1 (s ∈ {±1}⁶), ε = (1 − ‖t‖₁)/√6."""
    W = np.vstack([np.eye(6), -np.eye(6)])
    return W if t is None else W + t


def hypercube(rng: np.random.Generator, n_inner: int) -> np.ndarray:
    """{±1}⁶ and ``n_inner`` points strictly inside it: ε = 1, twelve facets tied."""
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * 6)).reshape(6, -1).T
    return np.vstack([corners, rng.uniform(-0.95, 0.95, size=(n_inner, 6))])


def test_grown_epsilon_analytic() -> None:
    g = grown_epsilon(cross_polytope())  # 64 facets tied at the minimum
    assert g.method == "grown" and g.epsilon == pytest.approx(1 / math.sqrt(6), rel=1e-12)
    t = np.array([0.1, 0.05, -0.02, 0.0, 0.03, -0.01])
    g = grown_epsilon(cross_polytope(t))
    assert g.method == "grown" and g.epsilon == pytest.approx(0.79 / math.sqrt(6), rel=1e-12)
    rng = np.random.default_rng(3)
    W = hypercube(rng, 300)
    g = grown_epsilon(W)
    assert g.method == "grown" and g.epsilon == pytest.approx(1.0, rel=1e-12)
    assert g.n_used < 64  # stopped before every corner was in the sub-hull
    # rotation invariant, scales with W
    R = np.linalg.qr(rng.normal(size=(6, 6)))[0]
    assert grown_epsilon(2.5 * W @ R.T).epsilon == pytest.approx(2.5, rel=1e-12)


def test_grown_epsilon_origin_outside_or_degenerate() -> None:
    """Where the sub-hull argument does not apply, ε is the full hull's value, identical."""
    for t in (np.array([0.6, 0.5, 0, 0, 0, 0]), np.array([0.5, 0.5, 0, 0, 0, 0])):
        W = cross_polytope(t)  # ‖t‖₁ > 1: origin outside; = 1: on the boundary
        g = grown_epsilon(W)
        assert g.method == "full hull" and g.epsilon == wrench_hull(W).epsilon
        assert g.epsilon <= 1e-12 and q_c1(W) == 0.0
    assert grown_epsilon(cross_polytope(np.array([0.6, 0.5, 0, 0, 0, 0]))).epsilon < 0
    W = hypercube(np.random.default_rng(4), 20)
    W[:, 5] = 0.0  # rank 5
    for V in (W, W[:5] + 1.0):  # rank 5; fewer than 7 wrenches
        g = grown_epsilon(V)
        assert g.method == "degenerate" and g.epsilon == 0.0 == wrench_hull(V).epsilon


def test_grown_epsilon_first_sub_hull_flat() -> None:
    """Two wrenches extreme along every ±e_i: the first sub-hull fails, more directions join."""
    rng = np.random.default_rng(6)
    W = np.vstack([np.full(6, 5.0), np.full(6, -5.0), rng.normal(size=(200, 6))])
    assert len(np.unique(np.argmax(W @ np.vstack([np.eye(6), -np.eye(6)]).T, axis=0))) == 2
    g = grown_epsilon(W)
    assert g.method == "grown" and g.epsilon == pytest.approx(wrench_hull(W).epsilon, rel=1e-9)


def wrench_sets(rng: np.random.Generator) -> list[np.ndarray]:
    """Random clouds around the origin, random-sphere contacts, cylindrical grips."""
    out = []
    for shift in (0.0, 0.8, 1.5):  # the origin deep inside, nearer the boundary, outside
        X = rng.normal(size=(300, 6))
        out.append(X + shift * X.std(0) * np.eye(6)[0])
    for k in (6, 12):
        p = rng.normal(size=(k, 3))
        p = R_OBJ * p / np.linalg.norm(p, axis=1, keepdims=True)
        n = -p / R_OBJ + rng.normal(scale=0.3, size=(k, 3))
        out.append(primitive_wrenches(p, n / np.linalg.norm(n, axis=1, keepdims=True),
                                      np.zeros(3), R_OBJ))  # fmt: skip
    for n_links in (2, 4):
        p, n = can_grip(rng, n_links)
        out.append(primitive_wrenches(p, n, CAN_CENTROID, CAN_MAX_R))
    return out


def test_grown_epsilon_equals_full_hull() -> None:
    """The grown ε is plain qhull's full-hull ε (1e-9 relative) on random and realistic sets,
    with sub-hulls smaller than the full hull's vertex set where the origin is inside."""
    from scipy.spatial import ConvexHull, QhullError

    rng = np.random.default_rng(12)
    grown = 0
    for W in wrench_sets(rng) + wrench_sets(rng):
        try:
            h = ConvexHull(W)
        except QhullError:
            continue
        eps = float(np.min(-h.equations[:, -1]))
        g = grown_epsilon(W)
        if eps > 1e-9:
            assert g.method == "grown"
            assert g.epsilon == pytest.approx(eps, rel=1e-9)
            assert g.n_used < len(h.vertices)
            grown += 1
        else:
            assert g.method == "full hull" and g.epsilon == wrench_hull(W).epsilon
    assert grown >= 8


def test_sub_hull_facets_nearer_than_epsilon_are_cut() -> None:
    """The exactness argument of ``app.quality.gqm.epsilon``: for a subset S ⊆ W, ε(S) ≤ ε(W), and
    every facet of conv(S) nearer than ε(W) has a wrench of W beyond it, so a nearest facet
    of conv(S) with none beyond is at ε(W) exactly."""
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(5)
    p, n = can_grip(rng, 4)
    W = primitive_wrenches(p, n, CAN_CENTROID, CAN_MAX_R)
    full = ConvexHull(W)
    eps = float(np.min(-full.equations[:, -1]))
    nearest = full.simplices[int(np.argmin(-full.equations[:, -1]))]
    tol = TOL_REL * float(np.max(np.abs(W)))
    cut = supported = 0
    for size in (30, 60, 120):
        for _ in range(3):
            S = np.union1d(nearest, rng.choice(len(W), size, replace=False))
            eq = ConvexHull(W[S]).equations
            d = -eq[:, -1]
            excess = np.max(W @ eq[:, :6].T, axis=0) - d
            assert np.min(d) <= eps * (1 + 1e-12)
            near = d < eps * (1 - 1e-9)
            assert np.all(excess[near] > tol)
            cut += int(np.sum(near))
            k = int(np.argmin(d))
            if excess[k] <= tol:
                assert d[k] == pytest.approx(eps, rel=1e-9)
                supported += 1
    assert cut > 0 and supported > 0  # both branches of the argument were exercised


def patch_grasp() -> tuple[Hand, SimpleNamespace, Body]:
    """A force-closure grasp of a sphere (r = R_OBJ) by five links, six points per patch."""
    hand, g, _ = _grasp_on_hand(7)
    links = ["palm", "thumb_distal", "index_distal", "middle_middle", "ring_proximal"]
    centres = np.array([[1, 0.1, 0], [-1, 0.1, 0.1], [0, 1, -0.1], [0.1, -1, 0], [0, 0.1, 1.0]])
    rng = np.random.default_rng(8)
    p, link = [], []
    for name, u in zip(links, centres, strict=True):
        q = u / np.linalg.norm(u) + rng.normal(scale=0.05, size=(6, 3))
        p.append(R_OBJ * q / np.linalg.norm(q, axis=1, keepdims=True))
        link += [name] * 6
    P = np.concatenate(p)
    cs = ContactSet(P, -P / R_OBJ, np.array(link, dtype=object), np.ones(len(P), bool))
    obj = Body(centroid_object=np.zeros(3), max_radius=R_OBJ)
    return hand, SimpleNamespace(q=g.q, T_object_palm=g.T_object_palm, contacts=cs), obj


def test_q_c1_on_patches_q_c2_per_link() -> None:
    """Q_C1: the full patch hull's ε; Q_C2: the per-link hull's volume; ``wrench_contacts``
    moves Q_C1 only."""
    hand, g, obj = patch_grasp()
    vals = compute_gqms(g, obj, hand)  # type: ignore[arg-type]
    cs, lc = g.contacts, link_contacts(g.contacts)
    W_patch = primitive_wrenches(cs.p_object, cs.n_object, np.zeros(3), R_OBJ)
    W_link = primitive_wrenches(lc.p, lc.n, np.zeros(3), R_OBJ)
    eps_patch, eps_link = wrench_hull(W_patch).epsilon, wrench_hull(W_link).epsilon
    assert eps_patch > 0 and eps_link > 0 and eps_link != pytest.approx(eps_patch, rel=1e-3)
    assert vals["Q_C1"] == pytest.approx(eps_patch, rel=1e-9)
    vol_link = wrench_hull(W_link).volume
    assert vals["Q_C2"] == vol_link and vol_link != pytest.approx(wrench_hull(W_patch).volume)
    link = compute_gqms(g, obj, hand, GQMSettings(wrench_contacts="link"))  # type: ignore[arg-type]
    assert link["Q_C1"] == pytest.approx(eps_link, rel=1e-9) and link["Q_C2"] == vals["Q_C2"]
    assert GQM_VERSION >= 2  # version 1 stored Q_C2 of the patch hull: never reuse it
