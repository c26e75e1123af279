"""Parametric hand: kinematics, design axes, palmar normals, shapes, errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.errors import DesignError
from app.model.design import ThumbDesign, published_designs
from app.model.hand.chains import finger_chains
from app.model.hand.data import HAND_ENV, data_root, load_hand_dims
from app.model.hand.geometry import CapsuleShape
from app.model.hand.model import FINGER_JOINTS, FINGER_LINKS, build_hand

RNG = np.random.default_rng(7)
#: The first reading of the design angles, kept as a named variant (docs/validation.md).
V1 = data_root() / "hand_models" / "imma_right_v1.toml"
#: A screened reading whose thumb links are oblique to their hinges (bones_turn = false).
OBLIQUE = data_root() / "hand_models" / "study" / "C_pins_b45.toml"


def line_angle_deg(a: np.typing.ArrayLike, b: np.typing.ArrayLike) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    c = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(1.0, c)))


def random_q(hand) -> np.ndarray:
    return RNG.uniform(hand.q_lower, hand.q_upper)


@pytest.mark.parametrize("path", [None, V1, OBLIQUE])
def test_segment_lengths_match_the_data_file(path) -> None:
    dims = load_hand_dims(path)
    hand = build_hand(15, 60, model_path=path)
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


@pytest.mark.parametrize("path", [None, V1])
@pytest.mark.parametrize("design", published_designs()[::3] + [ThumbDesign(12.3, 71.9)])
def test_axis_angles_equal_the_design_angles(design: ThumbDesign, path) -> None:
    """Both readings: c = angle(CMC axis, palm +y), the CMC axis in the palm plane,
    m = angle(MCP axis, CMC axis), IP parallel to MCP, at any joint configuration."""
    hand = build_hand(design.cmc_deg, design.mcp_deg, model_path=path)
    y = np.array([0.0, 1.0, 0.0])
    for q in (hand.q_open, random_q(hand), random_q(hand)):
        _, a = hand.joint_axes(q)
        cmc, mcp, ip = a[0], a[1], a[2]
        assert line_angle_deg(cmc, y) == pytest.approx(design.cmc_deg, abs=1e-9)
        assert abs(cmc[2]) < 1e-12  # the CMC axis lies in the palm plane
        assert line_angle_deg(mcp, cmc) == pytest.approx(design.mcp_deg, abs=1e-9)
        assert line_angle_deg(ip, mcp) == pytest.approx(0.0, abs=1e-6)  # IP parallel to MCP


def test_default_reading_cmc_leans_radially_and_open_thumb() -> None:
    """The default reading: the CMC axis's distal end leans radially (+x) by c; the open
    metacarpal lies across it in the palm plane, along (cos c, -sin c, 0)."""
    for c in (15.0, 30.0, 45.0):
        hand = build_hand(c, 0)
        _, a = hand.joint_axes(hand.q_open)
        assert np.sign(a[0][0]) == np.sign(a[0][1])  # line (sin c, cos c, 0)
        T = hand.link_poses(hand.q_open)[hand.link_index["thumb_metacarpal"]]
        cr, sr = math.cos(math.radians(c)), math.sin(math.radians(c))
        assert np.allclose(T[:3, 1], [cr, -sr, 0])


def test_default_reading_mcp_axis_depends_on_c_plus_m_when_abducted() -> None:
    """The published clue: the MCP axis's orientation in the palm behaves like c + m. With
    the CMC closed 90 deg the metacarpal lies along the palm normal, the line c turns
    about, so designs with the same c + m have the same MCP axis there."""
    for total in (45.0, 75.0, 90.0, 105.0):
        axes = []
        for c in (c for c in (0.0, 15.0, 30.0, 45.0) if 0 <= total - c <= 90):
            hand = build_hand(c, total - c)
            q = hand.q_open.copy()
            q[0] = np.deg2rad(90.0)
            p, a = hand.joint_axes(q)
            assert np.allclose(p[1] - p[0], [0, 0, hand.dims.thumb.lengths[0]])
            axes.append(a[1])
            # in the palm plane, at c + m from the proximal-distal axis
            assert line_angle_deg(a[1], [0, 1, 0]) == pytest.approx(min(total, 180 - total))
        assert np.allclose(axes, axes[0], atol=1e-12)
    # the first reading turns them the opposite ways: c - m
    h1, h2 = build_hand(0, 60, model_path=V1), build_hand(30, 30, model_path=V1)
    q = h1.q_open.copy()
    q[0] = np.deg2rad(90.0)
    assert not np.allclose(h1.joint_axes(q)[1][1], h2.joint_axes(q)[1][1])


def test_cmc_tilt_direction_and_open_metacarpal_v1() -> None:
    c = 30.0
    ulnar = build_hand(c, 0, model_path=V1)
    _, a = ulnar.joint_axes(ulnar.q_open)
    # METHOD §1: a = (-sin c, cos c, 0) up to sign: distal end leans ulnar (-x)
    assert np.allclose(np.abs(a[0]), [math.sin(math.radians(c)), math.cos(math.radians(c)), 0])
    assert np.sign(a[0][0]) != np.sign(a[0][1])
    T = ulnar.link_poses(ulnar.q_open)[ulnar.link_index["thumb_metacarpal"]]
    assert np.allclose(T[:3, 1], [math.cos(math.radians(c)), math.sin(math.radians(c)), 0])
    radial = build_hand(c, 0, cmc_tilt="radial", model_path=V1)
    _, a2 = radial.joint_axes(radial.q_open)
    assert np.sign(a2[0][0]) == np.sign(a2[0][1])


def test_cmc_tilt_radial_mirrors_c() -> None:
    """``cmc_tilt='radial'`` turns the CMC axis the other way about the same line."""
    for path in (None, V1):
        a = build_hand(30, 45, model_path=path)
        b = build_hand(30, 45, cmc_tilt="radial", model_path=path)
        ya, yb = (h.joint_axes(h.q_open)[1][0] for h in (a, b))
        line = a.dims.thumb.reading.cmc_tilt_line
        assert line_angle_deg(ya, [0, 1, 0]) == pytest.approx(30, abs=1e-9)
        assert line_angle_deg(yb, [0, 1, 0]) == pytest.approx(30, abs=1e-9)
        assert not np.allclose(ya, yb) and not np.allclose(ya, -yb)
        assert ya @ line == pytest.approx(yb @ line, abs=1e-12)


def test_hand_file_is_selected_by_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(HAND_ENV, "imma_right_v1")
    assert load_hand_dims().path == V1
    assert load_hand_dims().name == "imma_right_v1"
    monkeypatch.setenv(HAND_ENV, str(V1))
    assert load_hand_dims().path == V1
    monkeypatch.delenv(HAND_ENV)
    assert load_hand_dims().path.name == "imma_right.toml"


def test_v1_file_is_the_first_reading() -> None:
    """The variant file reproduces the first reading's placements (docs/validation.md)."""
    for c, m in ((0, 0), (15, 60), (45, 90)):
        hand = build_hand(c, m, model_path=V1)
        cr, sr = math.cos(math.radians(c)), math.sin(math.radians(c))
        R1 = hand.model.jointPlacements[1].rotation
        assert np.array_equal(R1[:, 1], [cr, sr, 0.0])  # metacarpal (cos c, sin c, 0)
        cm, sm = math.cos(math.radians(m)), math.sin(math.radians(m))
        R2 = hand.model.jointPlacements[2].rotation
        assert np.allclose(R2[:, 0], [cm, 0, sm])  # MCP axis toward the metacarpal's +z


@pytest.mark.parametrize("path", [None, V1])
def test_closing_the_cmc_swings_the_thumb_palmar(path) -> None:
    hand = build_hand(0, 45, model_path=path)
    q = hand.q_open.copy()
    tip0 = hand.fingertip_palm("thumb", q)
    q[0] = hand.q_upper[0]
    assert hand.fingertip_palm("thumb", q)[2] > tip0[2] + 20


@pytest.mark.parametrize("path", [None, OBLIQUE])
@pytest.mark.parametrize("design", [(0, 0), (30, 75), (45, 90)])
def test_palmar_normals_point_the_way_the_joint_closes(design: tuple[float, float], path) -> None:
    """Finite differences: closing joint k moves its link's surface along n_palmar."""
    hand = build_hand(*design, model_path=path)
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


@pytest.mark.parametrize("path", [None, OBLIQUE])
def test_thumb_n_main_is_the_distal_long_axis(path) -> None:
    hand = build_hand(15, 30, model_path=path)
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


@pytest.mark.parametrize("path", [None, OBLIQUE])
def test_fast_chains_agree_with_pinocchio(path) -> None:
    hand = build_hand(33.3, 12.1, model_path=path)
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
