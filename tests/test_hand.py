"""Parametric hand: kinematics, design axes, palmar normals, shapes, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.errors import DesignError
from app.model.design import ThumbDesign, published_designs
from app.model.hand.chains import finger_chains
from app.model.hand.data import load_hand_dims
from app.model.hand.geometry import CapsuleShape
from app.model.hand.model import FINGER_JOINTS, FINGER_LINKS, build_hand

RNG = np.random.default_rng(7)


def line_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    c = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(1.0, c)))


def random_q(hand) -> np.ndarray:
    return RNG.uniform(hand.q_lower, hand.q_upper)


def test_segment_lengths_match_the_data_file() -> None:
    dims = load_hand_dims()
    hand = build_hand(15, 60)
    for _ in range(5):
        q = random_q(hand)
        p, _ = hand.joint_axes(q)
        for f in dims.fingers:
            j = FINGER_JOINTS[f.name]
            assert np.allclose(p[j[0]], f.mcp_palm)  # MCP does not move
            assert np.linalg.norm(p[j[1]] - p[j[0]]) == pytest.approx(f.lengths[0])
            assert np.linalg.norm(p[j[2]] - p[j[1]]) == pytest.approx(f.lengths[1])
            tip = hand.fingertip_palm(f.name, q)
            assert np.linalg.norm(tip - p[j[2]]) == pytest.approx(f.lengths[2])
        t = FINGER_JOINTS["thumb"]
        assert np.linalg.norm(p[t[1]] - p[t[0]]) == pytest.approx(dims.thumb.lengths[0])
        assert np.linalg.norm(p[t[2]] - p[t[1]]) == pytest.approx(dims.thumb.lengths[1])
        tip = hand.fingertip_palm("thumb", q)
        assert np.linalg.norm(tip - p[t[2]]) == pytest.approx(dims.thumb.lengths[2])


@pytest.mark.parametrize("design", published_designs()[::3] + [ThumbDesign(12.3, 71.9)])
def test_axis_angles_equal_the_design_angles(design: ThumbDesign) -> None:
    hand = build_hand(design.cmc_deg, design.mcp_deg)
    y = np.array([0.0, 1.0, 0.0])
    for q in (hand.q_open, random_q(hand), random_q(hand)):
        _, a = hand.joint_axes(q)
        cmc, mcp, ip = a[0], a[1], a[2]
        assert line_angle_deg(cmc, y) == pytest.approx(design.cmc_deg, abs=1e-9)
        assert abs(cmc[2]) < 1e-12  # the CMC axis lies in the palm plane
        assert line_angle_deg(mcp, cmc) == pytest.approx(design.mcp_deg, abs=1e-9)
        assert line_angle_deg(ip, mcp) == pytest.approx(0.0, abs=1e-6)  # IP parallel to MCP


def test_cmc_tilt_direction_and_open_metacarpal() -> None:
    c = 30.0
    ulnar = build_hand(c, 0)
    _, a = ulnar.joint_axes(ulnar.q_open)
    # METHOD §1: a = (-sin c, cos c, 0) up to sign: distal end leans ulnar (-x)
    assert np.allclose(np.abs(a[0]), [math.sin(math.radians(c)), math.cos(math.radians(c)), 0])
    assert np.sign(a[0][0]) != np.sign(a[0][1])
    T = ulnar.link_poses(ulnar.q_open)[ulnar.link_index["thumb_metacarpal"]]
    assert np.allclose(T[:3, 1], [math.cos(math.radians(c)), math.sin(math.radians(c)), 0])
    radial = build_hand(c, 0, cmc_tilt="radial")
    _, a2 = radial.joint_axes(radial.q_open)
    assert np.sign(a2[0][0]) == np.sign(a2[0][1])


def test_closing_the_cmc_swings_the_thumb_palmar() -> None:
    hand = build_hand(0, 45)
    q = hand.q_open.copy()
    tip0 = hand.fingertip_palm("thumb", q)
    q[0] = np.deg2rad(60)
    assert hand.fingertip_palm("thumb", q)[2] > tip0[2] + 40


@pytest.mark.parametrize("design", [(0, 0), (30, 75), (45, 90)])
def test_palmar_normals_point_the_way_the_joint_closes(design: tuple[float, float]) -> None:
    """Finite differences: closing joint k moves its link's surface along n_palmar."""
    hand = build_hand(*design)
    for _ in range(4):
        q = random_q(hand)
        q = np.clip(q, hand.q_lower, hand.q_upper - 1e-3)
        n = hand.n_palmar_palm(q)
        for lk in hand.links[1:]:
            T0 = hand.link_poses(q)[hand.link_index[lk.name]]
            dq = np.zeros_like(q)
            dq[lk.joint] = 1e-6
            T1 = hand.link_poses(q + dq)[hand.link_index[lk.name]]
            # a point on the link axis, away from the joint
            p_link = np.array([0.0, 10.0, 0.0])
            v = (T1[:3, :3] @ p_link + T1[:3, 3] - T0[:3, :3] @ p_link - T0[:3, 3]) / 1e-6
            assert v @ n[hand.link_index[lk.name]] == pytest.approx(np.linalg.norm(v), rel=1e-4)
    assert np.allclose(hand.n_palmar_palm(hand.q_open)[0], [0, 0, 1])


def test_thumb_n_main_is_the_distal_long_axis() -> None:
    hand = build_hand(15, 30)
    q = random_q(hand)
    p, _ = hand.joint_axes(q)
    tip = hand.fingertip_palm("thumb", q)
    d = tip - p[2]
    assert np.allclose(hand.thumb_n_main_palm(q), d / np.linalg.norm(d))


def test_collision_shapes_enclose_the_visual_links() -> None:
    hand = build_hand(0, 45)
    visual = hand.visual_meshes()
    for lk in hand.links:
        v = visual[lk.name].vertices
        s = lk.shape
        if isinstance(s, CapsuleShape):
            ab = s.p1_link - s.p0_link
            t = np.clip((v - s.p0_link) @ ab / (ab @ ab), 0, 1)
            d = np.linalg.norm(v - (s.p0_link + t[:, None] * ab), axis=1)
            assert d.max() <= s.radius + 1e-9, lk.name
            assert d.max() >= 0.9 * s.radius  # and fills it: not a toy shape
        else:
            assert (v >= s.lo_link - 1e-9).all() and (v <= s.hi_link + 1e-9).all()


def test_fast_chains_agree_with_pinocchio() -> None:
    hand = build_hand(33.3, 12.1)
    chains = finger_chains(hand)
    for _ in range(5):
        q = random_q(hand)
        T = hand.link_poses(q)
        for f, ch in chains.items():
            assert ch.link_indices == tuple(hand.link_index[n] for n in FINGER_LINKS[f])
            assert np.allclose(ch.link_poses(q[list(ch.joints)]), T[list(ch.link_indices)])


def test_approach_point_and_palm() -> None:
    hand = build_hand(0, 45)
    assert np.allclose(hand.approach_point_palm, [10, 70, 0])
    mcp = {f.name: f.mcp_palm for f in load_hand_dims().fingers}
    mid = (mcp["index"] + mcp["middle"]) / 2
    assert np.linalg.norm(mid - hand.approach_point_palm) < 3.0  # P between index and middle MCP


@pytest.mark.parametrize(
    "cmc, mcp",
    [(float("nan"), 45), (0, float("inf")), (-1, 45), (46, 45), (0, 90.5), (0, -0.1)],
)
def test_bad_designs_raise_design_error(cmc: float, mcp: float) -> None:
    with pytest.raises(DesignError, match=r"range|finite"):
        build_hand(cmc, mcp)


def test_bad_tilt_lists_choices() -> None:
    with pytest.raises(DesignError, match="ulnar"):
        ThumbDesign(0, 0, "sideways")  # type: ignore[arg-type]


def test_continuous_designs_are_accepted() -> None:
    a, b = build_hand(7.77, 33.3), build_hand(7.78, 33.3)
    assert not np.allclose(a.link_poses(a.q_open)[3], b.link_poses(b.q_open)[3])
