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

from app.contact_set import LINK_NAMES, LONG_FINGERS, PHALANGES, THUMB_LINKS
from app.design import ThumbDesign
from app.hand.data import HandDims, ThumbReading, load_hand_dims
from app.hand.geometry import BoxShape, CapsuleShape, Shape

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
    """One of ``app.contact_set.LINK_NAMES``."""
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


def thumb_cmc_rotation(
    cmc_deg: float, tilt: str = "ulnar", reading: ThumbReading | None = None
) -> np.ndarray:
    """R_palm_metacarpal at q_cmc = 0: columns (CMC axis u, metacarpal axis d, n_palmar z).

    The hand file's reading (``ThumbReading``) gives the open metacarpal d0 and the way it
    closes z0 at c = 0; c turns both by +c about ``cmc_tilt_line`` (-c for ``tilt='radial'``),
    and u = d × z, so a positive CMC angle swings d toward z. The first reading
    (``hand_models/imma_right_v1.toml``): d0 = +x, z0 = +z, line +z, which gives
    a = (-sin c, cos c, 0) and d = (cos c, sin c, 0) (METHOD §1, docs/design.md).
    """
    r = reading if reading is not None else load_hand_dims().thumb.reading
    c = np.deg2rad(cmc_deg)
    sigma = 1.0 if tilt == "ulnar" else -1.0
    cos, sin = np.cos(c), sigma * np.sin(c)
    d = _turn(r.rest_direction, r.cmc_tilt_line, cos, sin)
    z = _turn(r.rest_closing_direction, r.cmc_tilt_line, cos, sin)
    u = np.cross(d, z)
    return np.stack([u, d, z], axis=1)


def thumb_mcp_rotation(mcp_deg: float, sense: float = 1.0) -> np.ndarray:
    """R_metacarpal_proximal at q = 0: the MCP axis is the CMC axis turned by m about the
    metacarpal's long axis (+y). sense +1: toward the metacarpal's palmar side (+z), axis
    (cos m, 0, sin m) (the first reading); sense -1: toward its dorsal side (cos m, 0, -sin m).
    m = 0: MCP flexion coplanar with the CMC sweep. The open thumb stays straight: the
    proximal phalanx continues the metacarpal whatever m is."""
    return _rot_y(-np.deg2rad(mcp_deg) if sense > 0 else np.deg2rad(mcp_deg))


class Hand:
    """A hand at one thumb design. Lengths mm, angles rad (q), frames per conventions.md."""

    def __init__(self, design: ThumbDesign, dims: HandDims) -> None:
        self.design = design
        self.dims = dims
        self.model = pin.Model()
        self.model.name = f"{dims.name}_{design.label}"
        shapes = _link_shapes(dims)
        links: dict[str, Link] = {
            "palm": Link("palm", "palm", -1, 0, shapes["palm"]),
        }
        q_lo, q_hi = [], []
        thumb = dims.thumb
        placements = [
            pin.SE3(
                thumb_cmc_rotation(design.cmc_deg, design.cmc_tilt, thumb.reading),
                thumb.cmc_palm,
            ),
            pin.SE3(
                thumb_mcp_rotation(design.mcp_deg, thumb.reading.mcp_sense),
                np.array([0.0, thumb.lengths[0], 0]),
            ),
            pin.SE3(np.eye(3), np.array([0.0, thumb.lengths[1], 0.0])),
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
        return self.link_poses(q)[self.link_index["thumb_distal"], :3, 1]

    def fingertip_palm(self, finger: str, q: np.ndarray) -> np.ndarray:
        """(3,) fingertip point (end of the distal link), palm frame."""
        name = FINGER_LINKS[finger][2]
        T = self.link_poses(q)[self.link_index[name]]
        shape = self.links[self.link_index[name]].shape
        assert isinstance(shape, CapsuleShape)
        tip = shape.p1_link + np.array([0.0, shape.radius, 0.0])
        return T[:3, :3] @ tip + T[:3, 3]

    @property
    def q_open(self) -> np.ndarray:
        """(15,) the open hand (all joints at their lower limit)."""
        return self.q_lower.copy()

    def visual_meshes(self) -> dict[str, trimesh.Trimesh]:
        """Visual mesh of every link in its own link frame (shared, do not modify)."""
        return _visual_meshes(self.dims.path)


def _link_shapes(dims: HandDims) -> dict[str, Shape]:
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
            shapes[name] = CapsuleShape(np.zeros(3), np.array([0.0, end, 0.0]), r)
    return shapes


@lru_cache(maxsize=4)
def _visual_meshes(path: Path) -> dict[str, trimesh.Trimesh]:
    shapes = _link_shapes(load_hand_dims(path))
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
