"""Build the parametric hand for a thumb design: Pinocchio kinematics + FCL link shapes.

``build_hand(cmc_deg, mcp_deg)`` is cheap (about a millisecond, see
``benchmarks/bench_hand_rebuild.py``): link shapes and visual meshes are fixed in their link
frames; a design only changes the thumb's joint placements.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin
import trimesh

from app.model.contact_set import LINK_NAMES, LONG_FINGERS, PHALANGES, THUMB_LINKS
from app.model.design import ThumbDesign
from app.model.hand.data import HandDims, ThumbReading, load_hand_dims
from app.model.hand.geometry import BoxShape, CapsuleShape, Shape

JOINT_NAMES = ("thumb_cmc", "thumb_mcp", "thumb_ip") + tuple(
    f"{f}_{j}" for f in LONG_FINGERS for j in ("mcp", "pip", "dip")
)
#: Fingers and their joint indices in ``q`` (proximal to distal).
FINGER_JOINTS: dict[str, tuple[int, int, int]] = {
    "thumb": (0, 1, 2),
    **{f: (3 + 3 * i, 4 + 3 * i, 5 + 3 * i) for i, f in enumerate(LONG_FINGERS)},
}
#: Links of each finger (proximal to distal); link k of a finger is moved by joint k.
FINGER_LINKS: dict[str, tuple[str, str, str]] = {
    "thumb": THUMB_LINKS,  # type: ignore[dict-item]
    **{f: tuple(f"{f}_{p}" for p in PHALANGES) for f in LONG_FINGERS},  # type: ignore[misc]
}


@dataclass(frozen=True)
class Link:
    """One rigid link of the hand."""

    name: str
    """One of ``app.model.contact_set.LINK_NAMES``."""
    finger: str
    """'palm', 'thumb', 'index', 'middle', 'ring' or 'little'."""
    joint: int
    """Index in ``q`` of the joint that moves this link (-1 for the palm)."""
    pin_joint_id: int
    """Pinocchio joint id whose frame is this link's frame (0 = universe/palm)."""
    shape: Shape
    """Collision shape in the link frame."""


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _turn(v: np.ndarray, k: np.ndarray, cos: float, sin: float) -> np.ndarray:
    """v turned about the unit line k (right-hand rule) by the angle with this cos and sin.

    Split into the part along k (kept) and across k (turned) so that vectors along or across
    k stay exact: the first reading's matrices come out bit for bit as they always did.
    """
    along = k * (k @ v)
    across = v - along
    return along + across * cos + np.cross(k, v) * sin


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def thumb_cmc_rotation(
    cmc_deg: float, tilt: str = "ulnar", reading: ThumbReading | None = None
) -> np.ndarray:
    """R_palm_metacarpal at q_cmc = 0: columns (CMC axis u, metacarpal axis d, n_palmar z).

    For a reading whose links turn with their hinges (``bones_turn``): the hand file gives
    the open metacarpal d0 and the CMC axis a0 ⟂ d0 at c = 0, so the metacarpal closes
    toward z0 = a0 × d0; c turns d0 and z0 by +c about ``cmc_tilt_line`` (-c for
    ``tilt='radial'``), and u = d × z, so a positive CMC angle swings d toward z. The first reading
    (``hand_models/imma_right_v1.toml``): d0 = +x, z0 = +z, line +z, which gives
    a = (-sin c, cos c, 0) and d = (cos c, sin c, 0) (METHOD §1, docs/design.md).
    """
    r = reading if reading is not None else load_hand_dims().thumb.reading
    c = np.deg2rad(cmc_deg)
    sigma = 1.0 if tilt == "ulnar" else -1.0
    cos, sin = np.cos(c), sigma * np.sin(c)
    d = _turn(r.rest_direction, r.cmc_tilt_line, cos, sin)
    z0 = np.cross(r.cmc_axis, r.rest_direction) + 0.0  # (+0.0: no signed zeros)
    z = _turn(z0, r.cmc_tilt_line, cos, sin)
    u = np.cross(d, z)
    return np.stack([u, d, z], axis=1)


def thumb_mcp_rotation(mcp_deg: float, sense: float = 1.0) -> np.ndarray:
    """R_metacarpal_proximal at q = 0: the MCP axis is the CMC axis turned by m about the
    metacarpal's long axis (+y). sense +1: toward the metacarpal's palmar side (+z), axis
    (cos m, 0, sin m) (the first reading); sense -1: toward its dorsal side (cos m, 0, -sin m).
    m = 0: MCP flexion coplanar with the CMC sweep. The open thumb stays straight: the
    proximal phalanx continues the metacarpal whatever m is."""
    return _rot_y(-np.deg2rad(mcp_deg) if sense > 0 else np.deg2rad(mcp_deg))


@dataclass(frozen=True)
class ThumbFrames:
    """The thumb's joint placements at q = 0 for one design, and its links' long axes."""

    R_palm_metacarpal: np.ndarray
    """(3, 3) CMC joint frame (x = CMC axis, z = ``n_palmar``) in the palm frame."""
    R_metacarpal_proximal: np.ndarray
    """(3, 3) MCP joint frame in the metacarpal frame."""
    bones: np.ndarray
    """(3, 3) unit long axis of the metacarpal, proximal and distal link in its own link
    frame: +y when the link is built perpendicular to its hinge, else oblique (in the
    link's x-y plane, so +z stays the way the link's surface moves when its joint closes)."""


def _hinge_frame(axis: np.ndarray, bone: np.ndarray, palmar: np.ndarray) -> np.ndarray:
    """R_palm_link of a link along ``bone`` hinged on ``axis``: x = the axis, signed so that
    closing moves the link toward ``palmar``; z = x × bone (normalised), y = z × x."""
    z = np.cross(axis, bone)
    n = float(np.linalg.norm(z))
    if n < 1e-9:  # hinge along the link: it only spins the link; keep the palmar side
        z, n = palmar - bone * (bone @ palmar), 1.0
        n = float(np.linalg.norm(z))
    z = z / n
    if z @ palmar < 0.0:
        axis, z = -axis, -z
    return np.stack([axis, np.cross(z, axis), z], axis=1)


def thumb_frames(design: ThumbDesign, reading: ThumbReading) -> ThumbFrames:
    """The thumb's joint placements for design (c, m) under a hand file's reading."""
    y = np.array([0.0, 1.0, 0.0])
    if reading.bones_turn:
        R1 = thumb_cmc_rotation(design.cmc_deg, design.cmc_tilt, reading)
        if reading.mcp_turn_line == "metacarpal_normal":
            R2 = _rot_z(reading.mcp_sense * np.deg2rad(design.mcp_deg))
        else:
            R2 = thumb_mcp_rotation(design.mcp_deg, reading.mcp_sense)
        return ThumbFrames(R1, R2, np.stack([y, y, y]))
    sigma = 1.0 if design.cmc_tilt == "ulnar" else -1.0
    c, m = np.deg2rad(design.cmc_deg), np.deg2rad(design.mcp_deg)
    k, d = reading.cmc_tilt_line, reading.rest_direction
    a_c = _turn(reading.cmc_axis, k, np.cos(c), sigma * np.sin(c))
    # the CMC closes the way the hand file signs its axis (a_c × d); along d: palm +z
    ad = np.cross(a_c, d)
    R1 = _hinge_frame(a_c, d, ad if np.linalg.norm(ad) > 1e-9 else np.array([0.0, 0.0, 1.0]))
    if reading.mcp_turn_line == "cmc_tilt_line":
        phi = sigma * c + reading.mcp_sense * m
        a_m = _turn(reading.cmc_axis, k, np.cos(phi), np.sin(phi))
    else:  # about the metacarpal, toward its palmar side for sense +1
        a_m = _turn(a_c, d, np.cos(m), -reading.mcp_sense * np.sin(m))
    R2_palm = _hinge_frame(a_m, d, R1[:, 2])
    bones = np.stack([R1.T @ d, R2_palm.T @ d, R2_palm.T @ d])
    return ThumbFrames(R1, R1.T @ R2_palm, bones)


class Hand:
    """A hand at one thumb design. Lengths mm, angles rad (q), frames per conventions.md."""

    def __init__(self, design: ThumbDesign, dims: HandDims) -> None:
        self.design = design
        self.dims = dims
        self.model = pin.Model()
        self.model.name = f"{dims.name}_{design.label}"
        thumb = dims.thumb
        frames = thumb_frames(design, thumb.reading)
        self.thumb_bones = frames.bones
        """(3, 3) long axis of each thumb link in its link frame (+y unless oblique)."""
        shapes = _link_shapes(dims, _bones_key(frames.bones))
        links: dict[str, Link] = {
            "palm": Link("palm", "palm", -1, 0, shapes["palm"]),
        }
        q_lo, q_hi = [], []
        if thumb.reading.bones_turn:  # the first reading's placements, bit for bit
            t_mcp = np.array([0.0, thumb.lengths[0], 0])
            t_ip = np.array([0.0, thumb.lengths[1], 0.0])
        else:
            t_mcp, t_ip = thumb.lengths[0] * frames.bones[0], thumb.lengths[1] * frames.bones[1]
        placements = [
            pin.SE3(frames.R_palm_metacarpal, thumb.cmc_palm),
            pin.SE3(frames.R_metacarpal_proximal, t_mcp),
            pin.SE3(np.eye(3), t_ip),
        ]
        chains: list[tuple[str, list[pin.SE3], tuple[tuple[float, float], ...]]] = [
            ("thumb", placements, thumb.limits_deg)
        ]
        for f in dims.fingers:
            chains.append(
                (
                    f.name,
                    [
                        pin.SE3(np.eye(3), f.mcp_palm),
                        pin.SE3(np.eye(3), np.array([0.0, f.lengths[0], 0.0])),
                        pin.SE3(np.eye(3), np.array([0.0, f.lengths[1], 0.0])),
                    ],
                    f.limits_deg,
                )
            )
        qi = 0
        for finger, placements_, limits in chains:
            parent = 0
            for k, (M, (lo, hi)) in enumerate(zip(placements_, limits, strict=True)):
                jname = JOINT_NAMES[qi]
                assert jname.startswith(finger)
                parent = self.model.addJoint(
                    parent,
                    pin.JointModelRX(),
                    M,
                    jname,
                    np.full(1, 1e9),
                    np.full(1, 1e9),
                    np.array([np.deg2rad(lo)]),
                    np.array([np.deg2rad(hi)]),
                )
                lname = FINGER_LINKS[finger][k]
                links[lname] = Link(lname, finger, qi, parent, shapes[lname])
                q_lo.append(np.deg2rad(lo))
                q_hi.append(np.deg2rad(hi))
                qi += 1
        assert qi == len(JOINT_NAMES) == self.model.nq
        self.data = self.model.createData()
        self.links: tuple[Link, ...] = tuple(links[n] for n in LINK_NAMES)
        self.link_index = {lk.name: i for i, lk in enumerate(self.links)}
        self.q_lower = np.array(q_lo)
        """(15,) lower joint limits, rad."""
        self.q_upper = np.array(q_hi)
        """(15,) upper joint limits, rad."""
        self.approach_point_palm = dims.approach_point_palm.copy()
        """(3,) the approach reference point P, palm frame, mm."""

    # ---------------------------------------------------------------- kinematics
    def link_poses(self, q: np.ndarray) -> np.ndarray:
        """(16, 4, 4) T_palm_link for every link (``LINK_NAMES`` order) at joint angles q (15,)."""
        q = np.asarray(q, float)
        assert q.shape == (self.model.nq,), q.shape
        pin.forwardKinematics(self.model, self.data, q)
        out = np.empty((len(self.links), 4, 4))
        for i, lk in enumerate(self.links):
            out[i] = self.data.oMi[lk.pin_joint_id].homogeneous
        return out

    def joint_axes(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Joint centres and unit axes in the palm frame: ``(p_palm (15, 3), a_palm (15, 3))``."""
        pin.forwardKinematics(self.model, self.data, np.asarray(q, float))
        p = np.array([self.data.oMi[j].translation for j in range(1, self.model.njoints)])
        a = np.array([self.data.oMi[j].rotation[:, 0] for j in range(1, self.model.njoints)])
        return p, a

    def n_palmar_palm(self, q: np.ndarray) -> np.ndarray:
        """(16, 3) each link's palmar normal (link +z) in the palm frame."""
        return self.link_poses(q)[:, :3, 2]

    def thumb_n_main_palm(self, q: np.ndarray) -> np.ndarray:
        """(3,) the thumb distal phalanx's long axis (IP joint toward the tip), palm frame."""
        R = self.link_poses(q)[self.link_index["thumb_distal"], :3, :3]
        b = self.thumb_bones[2]
        return R[:, 1] if b[1] == 1.0 else R @ b

    def fingertip_palm(self, finger: str, q: np.ndarray) -> np.ndarray:
        """(3,) fingertip point (end of the distal link), palm frame."""
        name = FINGER_LINKS[finger][2]
        T = self.link_poses(q)[self.link_index[name]]
        shape = self.links[self.link_index[name]].shape
        assert isinstance(shape, CapsuleShape)
        ab = shape.p1_link - shape.p0_link
        tip = shape.p1_link + shape.radius * ab / np.linalg.norm(ab)
        return T[:3, :3] @ tip + T[:3, 3]

    @property
    def q_open(self) -> np.ndarray:
        """(15,) the open hand (all joints at their lower limit)."""
        return self.q_lower.copy()

    def visual_meshes(self) -> dict[str, trimesh.Trimesh]:
        """Visual mesh of every link in its own link frame (shared, do not modify)."""
        return _visual_meshes(self.dims.path, _bones_key(self.thumb_bones))


def _bones_key(bones: np.ndarray) -> tuple[tuple[float, ...], ...] | None:
    """Hashable thumb link axes (None: all along +y, the common case)."""
    if (bones == np.array([0.0, 1.0, 0.0])).all():
        return None
    return tuple(tuple(float(v) for v in b) for b in bones)


def _link_shapes(
    dims: HandDims, thumb_bones: tuple[tuple[float, ...], ...] | None = None
) -> dict[str, Shape]:
    p = dims.palm
    shapes: dict[str, Shape] = {
        "palm": BoxShape(
            np.array([p.x_min, p.y_min, -p.thickness / 2]),
            np.array([p.x_max, p.y_max, p.thickness / 2]),
            p.corner_radius,
        )
    }
    t = dims.thumb
    fingers = [(FINGER_LINKS["thumb"], t.lengths, t.radii)] + [
        (FINGER_LINKS[f.name], f.lengths, (f.radius,) * 3) for f in dims.fingers
    ]
    for names, lengths, radii in fingers:
        for k, (name, length, r) in enumerate(zip(names, lengths, radii, strict=True)):
            # the distal link's rounded cap ends at the fingertip
            end = length - r if k == 2 else length
            if thumb_bones is not None and names is fingers[0][0]:
                p1 = end * np.asarray(thumb_bones[k])
            else:
                p1 = np.array([0.0, end, 0.0])
            shapes[name] = CapsuleShape(np.zeros(3), p1, r)
    return shapes


@lru_cache(maxsize=16)
def _visual_meshes(
    path: Path, thumb_bones: tuple[tuple[float, ...], ...] | None = None
) -> dict[str, trimesh.Trimesh]:
    shapes = _link_shapes(load_hand_dims(path), thumb_bones)
    return {name: s.visual_mesh() for name, s in shapes.items()}


def build_hand(
    cmc_deg: float,
    mcp_deg: float,
    *,
    cmc_tilt: str = "ulnar",
    model_path: str | Path | None = None,
) -> Hand:
    """The hand at thumb design (c, m) in degrees; raises DesignError outside the range."""
    design = ThumbDesign(cmc_deg, mcp_deg, cmc_tilt)  # type: ignore[arg-type]
    return Hand(design, load_hand_dims(model_path))
