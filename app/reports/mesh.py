"""Triangles for off-screen pictures: colours, refinement, the hand's and the object's meshes
in display coordinates (numpy and trimesh; matplotlib is imported by ``scene`` only).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from app.model.hand.geometry import VISUAL_INSET, BoxShape, CapsuleShape
from app.model.hand.model import Hand

if TYPE_CHECKING:
    pass


#: Base colours (RGB in [0, 1]) before shading.
PALM_RGB = np.array([0.93, 0.76, 0.63])


FINGER_RGB = {  # proximal, middle, distal: a slight gradient so the joints read
    "proximal": np.array([0.88, 0.70, 0.57]),
    "middle": np.array([0.92, 0.75, 0.62]),
    "distal": np.array([0.96, 0.80, 0.68]),
}


THUMB_RGB = {
    "thumb_metacarpal": np.array([0.86, 0.58, 0.48]),
    "thumb_proximal": np.array([0.89, 0.62, 0.51]),
    "thumb_distal": np.array([0.92, 0.66, 0.55]),
}


OBJECT_RGB = np.array([0.60, 0.67, 0.78])


RAY_RGB = np.array([0.55, 0.25, 0.70])


#: Upright display of the palm frame: display (x, y, z) = palm (x, -z, y).
R_DISPLAY_PALM = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


#: Longest triangle edge (mm) drawn: long slivers (a capsule's side, a can's wall) are split
#: so that depth sorting across meshes stays right.
MAX_EDGE_MM = 7.0


#: Longest edge (mm) of the triangles where one link enters another (a finger into the palm).
JUNCTION_EDGE_MM = 1.5


#: Object triangles are refined to edges of at most max(MAX_EDGE_MM, size / this).
OBJECT_EDGE_DIVISIONS = 20.0


#: Mesh detail of the design grid's small pictures (edges 1/GRID_DETAIL times longer).
GRID_DETAIL = 0.5


@dataclass
class Part:
    """Triangles of one mesh in display coordinates with one base colour."""

    tris: np.ndarray  # (F, 3, 3)
    normals: np.ndarray  # (F, 3) unit
    rgb: np.ndarray  # (3,)


def link_rgb(name: str) -> np.ndarray:
    if name == "palm":
        return PALM_RGB
    if name in THUMB_RGB:
        return THUMB_RGB[name]
    return FINGER_RGB[name.split("_", 1)[1]]


def transform(T: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p @ T[:3, :3].T + T[:3, 3]


def refine(tris: np.ndarray, max_edge: float) -> np.ndarray:
    """Split triangles (F, 3, 3) at the midpoint of their longest edge until every edge is
    at most ``max_edge``: long slivers (a capsule's side, a can's wall) then sort right in
    the painter's algorithm. Orientation is kept; T-junctions do not matter for drawing."""
    done = []
    t = np.asarray(tris, float)
    while len(t):
        e = np.stack(
            [
                np.linalg.norm(t[:, 1] - t[:, 0], axis=1),
                np.linalg.norm(t[:, 2] - t[:, 1], axis=1),
                np.linalg.norm(t[:, 0] - t[:, 2], axis=1),
            ],
            axis=1,
        )
        ok = e.max(axis=1) <= max_edge
        done.append(t[ok])
        t, k = t[~ok], e[~ok].argmax(axis=1)
        # rotate the vertices so that the longest edge is v0-v1 (cyclic: orientation kept)
        idx = (np.arange(3)[None, :] + k[:, None]) % 3
        t = np.take_along_axis(t, idx[:, :, None], axis=1)
        mid = 0.5 * (t[:, 0] + t[:, 1])
        t = np.concatenate(
            [np.stack([t[:, 0], mid, t[:, 2]], 1), np.stack([mid, t[:, 1], t[:, 2]], 1)]
        )
    return np.concatenate(done) if done else np.zeros((0, 3, 3))


REFINED: dict[tuple[int, float], tuple[trimesh.Trimesh, np.ndarray, np.ndarray]] = {}


def render_tris(
    mesh: trimesh.Trimesh, max_edge: float = MAX_EDGE_MM
) -> tuple[np.ndarray, np.ndarray]:
    """Refined triangles and their unit normals of a mesh in its own frame (cached)."""
    hit = REFINED.get((id(mesh), max_edge))
    if hit is not None and hit[0] is mesh:
        return hit[1], hit[2]
    tris = refine(np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)], max_edge)
    area2 = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    tris = tris[area2 > 1e-12]  # drop degenerate triangles
    n = face_normals(tris)
    if len(REFINED) > 64:
        REFINED.clear()
    REFINED[(id(mesh), max_edge)] = (mesh, tris, n)
    return tris, n


def part(
    mesh: trimesh.Trimesh,
    T_display_mesh: np.ndarray,
    rgb: np.ndarray,
    max_edge: float = MAX_EDGE_MM,
) -> Part:
    tris, n = render_tris(mesh, max_edge)
    R, t = T_display_mesh[:3, :3], T_display_mesh[:3, 3]
    return Part(tris @ R.T + t, n @ R.T, rgb)


def inside_shape(shape: CapsuleShape | BoxShape, p: np.ndarray, margin: float) -> np.ndarray:
    """(N,) True where link-frame points lie deeper than ``margin`` inside the visual solid."""
    if isinstance(shape, CapsuleShape):
        a, b = shape.p0_link, shape.p1_link
        ab = b - a
        t = np.clip((p - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        d = np.linalg.norm(p - (a + t[:, None] * ab), axis=1)
        return d < shape.radius * (1 - VISUAL_INSET) - margin
    r = shape.corner_radius
    c = 0.5 * (shape.lo_link + shape.hi_link)
    half = 0.5 * (shape.hi_link - shape.lo_link) - r * (1 + VISUAL_INSET)
    qd = np.abs(p - c) - half
    sd = np.linalg.norm(np.maximum(qd, 0.0), axis=1) + np.minimum(qd.max(axis=1), 0.0) - r
    return sd < -margin


def hand_mesh_parts(
    hand: Hand, q: np.ndarray, T_display_palm: np.ndarray, detail: float = 1.0
) -> list[Part]:
    """Posed, refined link meshes without the triangles buried inside another link (the
    capsule ends overlap at the joints and inside the palm; drawing them would confuse the
    painter's algorithm)."""
    meshes = hand.visual_meshes()
    poses = hand.link_poses(q)
    inv = np.linalg.inv(poses)
    parts = []
    for i, lk in enumerate(hand.links):
        tris, n = render_tris(meshes[lk.name], MAX_EDGE_MM / detail)
        others = [j for j in range(len(hand.links)) if j != i]

        def corners_inside(t: np.ndarray, i: int = i, others: list[int] = others) -> np.ndarray:
            v_palm = transform(poses[i], t.reshape(-1, 3))
            inside = np.zeros(len(v_palm), bool)
            for j in others:
                inside |= inside_shape(hand.links[j].shape, transform(inv[j], v_palm), 0.0)
            return inside.reshape(-1, 3)

        inside = corners_inside(tris)
        straddle = inside.any(axis=1) & ~inside.all(axis=1)
        if straddle.any():  # refine where a link enters another, then drop the buried bits
            fine = refine(tris[straddle], JUNCTION_EDGE_MM / detail)
            fine_n = face_normals(fine)
            keep = ~inside.any(axis=1)
            fine_keep = ~corners_inside(fine).all(axis=1)
            tris = np.concatenate([tris[keep], fine[fine_keep]])
            n = np.concatenate([n[keep], fine_n[fine_keep]])
        else:
            keep = ~inside.all(axis=1)
            tris, n = tris[keep], n[keep]
        T = T_display_palm @ poses[i]
        R, t = T[:3, :3], T[:3, 3]
        parts.append(Part(tris @ R.T + t, n @ R.T, link_rgb(lk.name)))
    return parts


def face_normals(tris: np.ndarray) -> np.ndarray:
    """Unit normals (F, 3) of triangles (F, 3, 3) (right-hand rule)."""
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(norm > 1e-12, norm, 1.0)


def tube_parts(target: np.ndarray, end: np.ndarray, radius: float, rgb: np.ndarray) -> list[Part]:
    """The approach ray as a thin tube with a ball at the target: part of the depth-sorted
    meshes, so the hand and the object hide it where they are in front of it."""
    meshes = [trimesh.creation.icosphere(subdivisions=2, radius=2.4 * radius)]
    meshes[0].apply_translation(target)
    if np.linalg.norm(end - target) > 1e-6:
        meshes.append(
            trimesh.creation.cylinder(radius=radius, segment=np.stack([target, end]), sections=10)
        )
    return [part(m, np.eye(4), rgb) for m in meshes]
