"""Off-screen pictures of the hand and the objects (matplotlib, Agg: no display, no browser).

Everything is drawn as shaded triangles in one ``Poly3DCollection`` per picture, so the
painter's algorithm sorts the hand and the object polygons together and occlusion between
them is right. The projection is orthographic: the view direction is the same for every
polygon, which makes back-face culling exact (half the polygons are dropped before matplotlib
sees them) and the Lambert shading consistent.

Frames: with an object, the picture is drawn in the object frame (+z up, mm); the hand only,
in the palm frame, shown upright (palm +y, the fingers, pointing up; palm +z, the palmar
side, toward the default camera). Only this module imports matplotlib; the core never does.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from mpl_toolkits.mplot3d import Axes3D  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

from app.contact_set import ContactSet, finger_of  # noqa: E402
from app.hand.geometry import VISUAL_INSET, BoxShape, CapsuleShape  # noqa: E402
from app.hand.model import Hand, build_hand  # noqa: E402
from app.hypotheses import palm_orientation  # noqa: E402

if TYPE_CHECKING:
    from app.objects import GraspObject

# ------------------------------------------------------------------------- appearance
#: Base colours (RGB in [0, 1]) before shading.
PALM_RGB = np.array([0.93, 0.76, 0.63])
FINGER_RGB = {  # proximal, middle, distal: a slight gradient so the joints read
    "proximal": np.array([0.90, 0.72, 0.59]),
    "middle": np.array([0.92, 0.75, 0.62]),
    "distal": np.array([0.94, 0.78, 0.66]),
}
THUMB_RGB = {
    "thumb_metacarpal": np.array([0.86, 0.58, 0.48]),
    "thumb_proximal": np.array([0.89, 0.62, 0.51]),
    "thumb_distal": np.array([0.92, 0.66, 0.55]),
}
OBJECT_RGB = np.array([0.60, 0.67, 0.78])
RAY_RGB = np.array([0.55, 0.25, 0.70])
#: Contact colours: palmar contact on a finger, non-palmar contact, contact on the palm.
CONTACT_RGB = {"palmar": "#1a9e3a", "non-palmar": "#f28c1c", "palm": "#1f5fd6"}
#: Thumb joint axis colours.
THUMB_AXIS_RGB = {"CMC": "#d62728", "MCP": "#2ca02c", "IP": "#1f77b4"}

AMBIENT = 0.38
DIFFUSE = 0.62
SPECULAR = 0.12
SHININESS = 24.0

#: Camera (elevation, azimuth) in degrees for the hand alone (upright palm-frame display).
HAND_VIEW = (18.0, -62.0)
#: Default cameras for the shipped objects with the hand at roll 0 (object frame, +z up).
OBJECT_VIEWS: dict[str, tuple[float, float]] = {
    "small_marker": (18.0, -75.0),
    "plastic_pear": (14.0, -115.0),
    "washer": (25.0, -70.0),
    "chips_can": (16.0, -68.0),
    "coffee_can": (18.0, -68.0),
    "power_drill": (12.0, -122.0),
}
#: The thumb posture of the design grid: CMC, MCP, IP (degrees), long fingers slightly bent.
GRID_THUMB_DEG = (60.0, 40.0, 30.0)
GRID_FINGER_DEG = (15.0, 15.0, 10.0)
DEFAULT_DESIGNS: tuple[tuple[float, float], ...] = (
    (0, 0),
    (0, 45),
    (0, 90),
    (45, 0),
    (45, 45),
    (45, 90),
)

#: Upright display of the palm frame: display (x, y, z) = palm (x, -z, y).
R_DISPLAY_PALM = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

#: Longest triangle edge (mm) drawn: long slivers (a capsule's side, a can's wall) are split
#: so that depth sorting across meshes stays right.
MAX_EDGE_MM = 7.0
#: Sampling spacing (mm) of the link surfaces when the hand is moved to first contact.
CLEARANCE_SPACING_MM = 2.5


@dataclass(frozen=True)
class RenderInfo:
    """What a render call produced (handy for tests and logs)."""

    path: Path
    """The PNG written."""
    size: tuple[int, int]
    """(width, height) in pixels."""
    seconds: float
    """Wall time of the call."""
    n_polygons: int
    """Triangles drawn (after back-face culling), all subplots together."""
    legend_labels: tuple[str, ...] = ()
    """Labels of the legend entries (contacts), empty when there is no legend."""


@dataclass
class _Part:
    """Triangles of one mesh in display coordinates with one base colour."""

    tris: np.ndarray  # (F, 3, 3)
    normals: np.ndarray  # (F, 3) unit
    rgb: np.ndarray  # (3,)


# ------------------------------------------------------------------------------ helpers
def _link_rgb(name: str) -> np.ndarray:
    if name == "palm":
        return PALM_RGB
    if name in THUMB_RGB:
        return THUMB_RGB[name]
    return FINGER_RGB[name.split("_", 1)[1]]


def _transform(T: np.ndarray, p: np.ndarray) -> np.ndarray:
    return p @ T[:3, :3].T + T[:3, 3]


def _refine(tris: np.ndarray, max_edge: float) -> np.ndarray:
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


_REFINED: dict[int, tuple[trimesh.Trimesh, np.ndarray, np.ndarray]] = {}


def _render_tris(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Refined triangles and their unit normals of a mesh in its own frame (cached)."""
    hit = _REFINED.get(id(mesh))
    if hit is not None and hit[0] is mesh:
        return hit[1], hit[2]
    tris = _refine(np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)], MAX_EDGE_MM)
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    norm = np.linalg.norm(n, axis=1)
    keep = norm > 1e-12
    tris, n = tris[keep], n[keep] / norm[keep, None]
    if len(_REFINED) > 64:
        _REFINED.clear()
    _REFINED[id(mesh)] = (mesh, tris, n)
    return tris, n


def _part(mesh: trimesh.Trimesh, T_display_mesh: np.ndarray, rgb: np.ndarray) -> _Part:
    tris, n = _render_tris(mesh)
    R, t = T_display_mesh[:3, :3], T_display_mesh[:3, 3]
    return _Part(tris @ R.T + t, n @ R.T, rgb)


def _inside_shape(shape: CapsuleShape | BoxShape, p: np.ndarray, margin: float) -> np.ndarray:
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


def _hand_parts(hand: Hand, q: np.ndarray, T_display_palm: np.ndarray) -> list[_Part]:
    """Posed, refined link meshes without the triangles buried inside another link (the
    capsule ends overlap at the joints and inside the palm; drawing them would confuse the
    painter's algorithm)."""
    meshes = hand.visual_meshes()
    poses = hand.link_poses(q)
    inv = np.linalg.inv(poses)
    parts = []
    for i, lk in enumerate(hand.links):
        tris, n = _render_tris(meshes[lk.name])
        c_palm = _transform(poses[i], tris.mean(axis=1))
        buried = np.zeros(len(tris), bool)
        for j, other in enumerate(hand.links):
            if j != i:
                buried |= _inside_shape(other.shape, _transform(inv[j], c_palm), 0.05)
        T = T_display_palm @ poses[i]
        R, t = T[:3, :3], T[:3, 3]
        parts.append(_Part(tris[~buried] @ R.T + t, n[~buried] @ R.T, _link_rgb(lk.name)))
    return parts


def _camera(view: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (toward the eye, screen right, screen up) of matplotlib's camera."""
    el, az = np.deg2rad(view[0]), np.deg2rad(view[1])
    eye = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], eye)
    right /= np.linalg.norm(right)
    up = np.cross(eye, right)
    return eye, right, up


def _shaded_polys(
    parts: Sequence[_Part], view: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """Cull back faces, Lambert + a little Blinn-Phong; returns (tris (F,3,3), rgba (F,4))."""
    eye, right, up = _camera(view)
    light = eye + 0.7 * up - 0.45 * right  # key light above-left of the camera
    light /= np.linalg.norm(light)
    half = (light + eye) / np.linalg.norm(light + eye)
    tris, cols = [], []
    for p in parts:
        keep = p.normals @ eye > -0.02
        n = p.normals[keep]
        lam = np.clip(n @ light, 0.0, None)
        spec = np.clip(n @ half, 0.0, None) ** SHININESS
        rgb = p.rgb[None, :] * (AMBIENT + DIFFUSE * lam)[:, None] + SPECULAR * spec[:, None]
        tris.append(p.tris[keep])
        cols.append(np.clip(rgb, 0.0, 1.0))
    t = np.concatenate(tris) if tris else np.zeros((0, 3, 3))
    c = np.concatenate(cols) if cols else np.zeros((0, 3))
    rgba = np.concatenate([c, np.ones((len(c), 1))], axis=1)
    return t, rgba


def _new_axes(fig: Figure, *args: Any) -> Axes3D:
    ax = fig.add_subplot(*args, projection="3d")
    assert isinstance(ax, Axes3D)
    ax.set_proj_type("ortho")
    ax.computed_zorder = False  # overlays (axes, contacts) stay on top of the meshes
    ax.set_axis_off()
    return ax


def _frame_limits(ax: Axes3D, pts: np.ndarray, margin: float = 0.04, zoom: float = 1.0) -> None:
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-3)
    pad = margin * span.max()
    lo, hi = lo - pad, hi + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo), zoom=zoom)


def _draw_meshes(ax: Axes3D, parts: Sequence[_Part], view: tuple[float, float]) -> int:
    tris, rgba = _shaded_polys(parts, view)
    coll = Poly3DCollection(
        list(tris), facecolors=rgba, edgecolors=rgba, linewidths=0.6, zorder=1
    )
    coll.set_zsort("average")
    ax.add_collection3d(coll)
    ax.view_init(elev=view[0], azim=view[1])
    return len(tris)


def _draw_joint_axes(
    ax: Axes3D, hand: Hand, q: np.ndarray, T_display_palm: np.ndarray, scale: float
) -> list[np.ndarray]:
    """Short arrows along the joint axes; the thumb's three highlighted and labelled."""
    p_palm, a_palm = hand.joint_axes(q)
    p = _transform(T_display_palm, p_palm)
    a = a_palm @ T_display_palm[:3, :3].T
    ends: list[np.ndarray] = []
    for j in range(len(p)):
        if j < 3:
            name = ("CMC", "MCP", "IP")[j]
            length = 0.16 * scale
            tail = p[j] - 0.45 * length * a[j]
            vec = 1.45 * length * a[j]
            ax.quiver(
                *tail, *vec, color=THUMB_AXIS_RGB[name], linewidth=2.6,
                arrow_length_ratio=0.22, zorder=10,
            )  # fmt: skip
            tip = tail + vec
            ax.text(
                *(tip + 0.03 * scale * a[j]), name, color=THUMB_AXIS_RGB[name],
                fontsize=11, fontweight="bold", zorder=11,
            )  # fmt: skip
            ends += [tail, tip]
        else:
            length = 0.09 * scale
            tail = p[j] - 0.5 * length * a[j]
            ax.quiver(
                *tail, *(length * a[j]), color="#444444", linewidth=0.9, alpha=0.6,
                arrow_length_ratio=0.3, zorder=9,
            )  # fmt: skip
            ends += [tail, tail + length * a[j]]
    return ends


def _draw_contacts(
    ax: Axes3D, contacts: ContactSet, T_display_frame: np.ndarray, scale: float
) -> tuple[str, ...]:
    if len(contacts) == 0:
        return ()
    p = _transform(T_display_frame, contacts.p_object)
    n = contacts.n_object @ T_display_frame[:3, :3].T
    on_palm = np.array([finger_of(str(s)) == "palm" for s in contacts.link])
    palmar = np.asarray(contacts.palmar, bool)
    kinds = {
        "palmar": ~on_palm & palmar,
        "non-palmar": ~on_palm & ~palmar,
        "palm": on_palm,
    }
    labels = {
        "palmar": "palmar contact (finger)",
        "non-palmar": "non-palmar contact",
        "palm": "palm contact",
    }
    handles = []
    nlen = 0.06 * scale
    for kind, sel in kinds.items():
        if not sel.any():
            continue
        col = CONTACT_RGB[kind]
        ax.scatter(
            p[sel, 0], p[sel, 1], p[sel, 2], s=14, c=col, depthshade=False,
            edgecolors="black", linewidths=0.3, zorder=12,
        )  # fmt: skip
        segs = np.stack([p[sel], p[sel] + nlen * n[sel]], axis=1)
        ax.add_collection3d(Line3DCollection(list(segs), colors=col, linewidths=1.0, zorder=12))
        handles.append(
            Line2D([], [], marker="o", linestyle="-", color=col, markeredgecolor="black",
                   markeredgewidth=0.3, label=labels[kind])
        )  # fmt: skip
    ax.legend(handles=handles, loc="upper right", fontsize=9, framealpha=0.85)
    return tuple(h.get_label() for h in handles)


def _draw_frame_triad(
    ax: Axes3D,
    R_display_frame: np.ndarray,
    pts: np.ndarray,
    view: tuple[float, float],
    length: float,
    name: str,
) -> np.ndarray:
    """A small x/y/z triad of the scene's frame at the bounding-box corner that appears
    lowest-left on screen (an orientation gizmo, out of the way of the meshes)."""
    _, right, up = _camera(view)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])  # fmt: skip
    o = corners[np.argmin(corners @ right + corners @ up)]
    ends = [o]
    for k, (lab, col) in enumerate(zip("xyz", ("#c0392b", "#27ae60", "#2e6fd8"), strict=True)):
        d = R_display_frame[:, k] * length
        ax.quiver(*o, *d, color=col, linewidth=1.4, arrow_length_ratio=0.25, zorder=8)
        ax.text(*(o + 1.18 * d), lab, color=col, fontsize=9, zorder=8)
        ends.append(o + 1.2 * d)
    ax.text(*(o - 0.35 * length * up), f"{name} frame", color="#555555", fontsize=8, zorder=8)
    return np.array(ends)


def _tube_parts(
    target: np.ndarray, end: np.ndarray, radius: float, rgb: np.ndarray
) -> list[_Part]:
    """The approach ray as a thin tube with a ball at the target: part of the depth-sorted
    meshes, so the hand and the object hide it where they are in front of it."""
    meshes = [trimesh.creation.icosphere(subdivisions=2, radius=2.4 * radius)]
    meshes[0].apply_translation(target)
    if np.linalg.norm(end - target) > 1e-6:
        meshes.append(
            trimesh.creation.cylinder(radius=radius, segment=np.stack([target, end]), sections=10)
        )
    return [_part(m, np.eye(4), rgb) for m in meshes]


def _save(fig: Figure, path: str | Path, dpi: int) -> Path:
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi, facecolor="white")
    plt.close(fig)
    return out


def _ray_length(t: np.ndarray, d: np.ndarray, hand_parts: Sequence[_Part], scale: float) -> float:
    """Length of the approach ray from the target to where it reaches the hand surface
    (within a few mm of a hand vertex), or ``0.6 * scale`` when it misses the hand."""
    if not hand_parts:
        return 0.6 * scale
    v = np.concatenate([p.tris.reshape(-1, 3) for p in hand_parts])
    tree = cKDTree(v)
    s = np.arange(0.0, 1.5 * scale, 1.0)
    dist, _ = tree.query(t + s[:, None] * d)
    hit = np.nonzero(dist < 0.6 * MAX_EDGE_MM)[0]
    return float(s[hit[0]]) if len(hit) else 0.6 * scale


# ------------------------------------------------------------------------------ scene
def _draw_scene(
    ax: Axes3D,
    *,
    hand: Hand | None,
    q: np.ndarray | None,
    T_object_palm: np.ndarray | None,
    obj: GraspObject | None,
    contacts: ContactSet | None,
    show_axes: bool,
    show_frame: bool,
    view: tuple[float, float],
    approach_ray: tuple[np.ndarray, np.ndarray] | None = None,
    zoom: float = 1.0,
) -> tuple[int, tuple[str, ...]]:
    """Draw one scene on ``ax``; returns (polygons drawn, legend labels)."""
    if obj is not None:
        T_display_frame = np.eye(4)  # the object frame, +z already up
        T_frame_palm = np.eye(4) if T_object_palm is None else np.asarray(T_object_palm, float)
        frame_name = "object"
    else:
        T_display_frame = np.eye(4)
        T_display_frame[:3, :3] = R_DISPLAY_PALM
        T_frame_palm = np.eye(4)
        frame_name = "palm"
    T_display_palm = T_display_frame @ T_frame_palm
    obj_parts = [] if obj is None else [_part(obj.mesh, T_display_frame, OBJECT_RGB)]
    hand_parts: list[_Part] = []
    q_ = None
    if hand is not None:
        q_ = hand.q_open if q is None else np.asarray(q, float)
        hand_parts = _hand_parts(hand, q_, T_display_palm)
    parts = obj_parts + hand_parts
    if not parts:
        raise ValueError("render_scene needs a hand, an object, or both")
    pts = [np.concatenate([p.tris.reshape(-1, 3) for p in parts])]
    scale = float(np.ptp(pts[0], axis=0).max())
    if approach_ray is not None:
        target, direction = (np.asarray(v, float) for v in approach_ray)
        t = _transform(T_display_frame, target[None])[0]
        d = T_display_frame[:3, :3] @ direction
        d = d / np.linalg.norm(d)
        end = t + d * _ray_length(t, d, hand_parts, scale)
        parts += _tube_parts(t, end, 0.005 * scale, RAY_RGB)
        pts.append(np.stack([t, end]))
    n_poly = _draw_meshes(ax, parts, view)
    if hand is not None and show_axes and q_ is not None:
        hand_pts = np.concatenate([p.tris.reshape(-1, 3) for p in hand_parts])
        hand_scale = float(np.ptp(hand_pts, axis=0).max())
        pts.append(np.array(_draw_joint_axes(ax, hand, q_, T_display_palm, hand_scale)))
    if show_frame:
        pts.append(
            _draw_frame_triad(
                ax, T_display_frame[:3, :3], np.concatenate(pts), view, 0.08 * scale, frame_name
            )
        )
    labels: tuple[str, ...] = ()
    if contacts is not None:
        labels = _draw_contacts(ax, contacts, T_display_frame, scale)
    _frame_limits(ax, np.concatenate(pts), zoom=zoom)
    return n_poly, labels


def render_scene(
    path: str | Path,
    *,
    hand: Hand | None = None,
    q: np.ndarray | None = None,
    T_object_palm: np.ndarray | None = None,
    obj: GraspObject | None = None,
    contacts: ContactSet | None = None,
    show_axes: bool = True,
    show_frame: bool = True,
    approach_ray: tuple[np.ndarray, np.ndarray] | None = None,
    title: str | None = None,
    size: tuple[int, int] = (1000, 800),
    view: tuple[float, float] | None = None,
    dpi: int = 100,
) -> RenderInfo:
    """Write a PNG of the hand (at ``q``, default open) and/or an object.

    With an object the scene is in the object frame and the hand is posed by
    ``T_object_palm`` (default identity); without one, in the palm frame shown upright.
    ``contacts`` (object frame) are drawn as points with short normals: green palmar on a
    finger, orange non-palmar, blue on the palm. ``view`` is matplotlib's (elevation,
    azimuth) in degrees of the displayed frame. ``size`` is (width, height) in pixels.
    """
    t0 = time.perf_counter()
    if view is None:
        view = OBJECT_VIEWS.get(obj.key, (20.0, -40.0)) if obj is not None else HAND_VIEW
    fig = plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    ax = _new_axes(fig, 1, 1, 1)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.94 if title else 1)
    n_poly, labels = _draw_scene(
        ax,
        hand=hand,
        q=q,
        T_object_palm=T_object_palm,
        obj=obj,
        contacts=contacts,
        show_axes=show_axes,
        show_frame=show_frame,
        view=view,
        approach_ray=approach_ray,
        zoom=1.3,
    )
    if title:
        fig.suptitle(title, fontsize=13)
    out = _save(fig, path, dpi)
    return RenderInfo(out, size, time.perf_counter() - t0, n_poly, labels)


# ------------------------------------------------------------------------- hand, object
def render_hand(
    path: str | Path,
    cmc_deg: float,
    mcp_deg: float,
    q: np.ndarray | None = None,
    *,
    cmc_tilt: str = "ulnar",
    show_axes: bool = True,
    title: str | None = None,
    size: tuple[int, int] = (1000, 800),
    view: tuple[float, float] | None = None,
) -> RenderInfo:
    """The hand of design (c, m) alone, palm frame shown upright, at ``q`` (default open)."""
    hand = build_hand(cmc_deg, mcp_deg, cmc_tilt=cmc_tilt)
    if title is None:
        pose = "open hand" if q is None else "posed"
        title = f"Hand, thumb design c = {cmc_deg:g}°, m = {mcp_deg:g}° ({pose}, palm frame)"
    return render_scene(
        path, hand=hand, q=q, show_axes=show_axes, title=title, size=size, view=view
    )


def roll0_pose(
    hand: Hand,
    obj: GraspObject,
    *,
    standoff_mm: float | None = None,
    q: np.ndarray | None = None,
) -> np.ndarray:
    """T_object_palm of the hand on the object's axis ray at roll 0.

    Orientation: ``palm_orientation(-normal, hand_vector, palm_y_hint, 0)``. Position: P on
    the line target + s·normal, s where the hand (at ``q``, default open) first touches the
    object (sphere tracing on the object's SDF), plus ``standoff_mm`` (default: the object's
    smallest standoff δ, i.e. the pose the hand closes from).
    """
    spec = obj.spec
    n = np.asarray(spec.normal_object, float)
    n = n / np.linalg.norm(n)
    R = palm_orientation(-n, spec.setup.hand_vector_palm, spec.palm_y_hint_object, 0.0)
    q_ = hand.q_open if q is None else np.asarray(q, float)
    poses = hand.link_poses(q_)
    pts = []
    for i, lk in enumerate(hand.links):
        p_link, _ = lk.shape.surface_points(CLEARANCE_SPACING_MM)
        pts.append(_transform(poses[i], p_link))
    p_palm = np.concatenate(pts)
    base = p_palm @ R.T - R @ hand.approach_point_palm + spec.target_object  # s = 0

    def min_dist(s: float) -> float:
        x = base + s * n
        if hasattr(obj, "sdf"):
            return float(np.min(obj.sdf(x)))
        return float(np.min(np.abs(trimesh.proximity.signed_distance(obj.mesh, x))))

    reach = float(np.ptp(p_palm, axis=0).max()) + 2.0 * obj.max_radius
    s = reach
    for _ in range(300):  # sphere tracing: the SDF is 1-Lipschitz, each step is safe
        d = min_dist(s)
        if d < 0.2:
            break
        s -= d
        if s < -reach:  # the hand never meets the object along the ray
            s = 0.0
            break
    if standoff_mm is None:
        standoff_mm = float(min(spec.setup.standoffs_mm))
    s += standoff_mm
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = spec.target_object + s * n - R @ hand.approach_point_palm
    return T


def render_object(
    path: str | Path,
    key: str,
    with_hand: bool = True,
    *,
    cmc_deg: float = 0.0,
    mcp_deg: float = 45.0,
    cmc_tilt: str = "ulnar",
    standoff_mm: float | None = None,
    contacts: ContactSet | None = None,
    title: str | None = None,
    size: tuple[int, int] = (1000, 800),
    view: tuple[float, float] | None = None,
) -> RenderInfo:
    """An object (by key) with, by default, the open hand at roll 0 on its axis ray.

    The hand is placed by :func:`roll0_pose` (first contact along the ray, backed off by
    the object's smallest standoff); the dashed line is the approach ray through the target.
    """
    from app.objects import load_object

    obj = load_object(key)
    hand = build_hand(cmc_deg, mcp_deg, cmc_tilt=cmc_tilt) if with_hand else None
    T = roll0_pose(hand, obj, standoff_mm=standoff_mm) if hand is not None else None
    if title is None:
        title = f"{obj.spec.name} ({obj.spec.grasp_type})"
        if hand is not None:
            d = float(min(obj.spec.setup.standoffs_mm)) if standoff_mm is None else standoff_mm
            title += f": hand c = {cmc_deg:g}°, m = {mcp_deg:g}° at roll 0, axis ray, δ = {d:g} mm"
    return render_scene(
        path,
        hand=hand,
        T_object_palm=T,
        obj=obj,
        contacts=contacts,
        show_axes=False,
        approach_ray=(obj.spec.target_object, obj.spec.normal_object),
        title=title,
        size=size,
        view=view,
    )


def grid_pose(hand: Hand) -> np.ndarray:
    """The design-grid posture: thumb partly closed, long fingers slightly bent."""
    q = np.zeros(len(hand.q_lower))
    q[:3] = np.deg2rad(GRID_THUMB_DEG)
    for f in range(4):
        q[3 + 3 * f : 6 + 3 * f] = np.deg2rad(GRID_FINGER_DEG)
    return np.clip(q, hand.q_lower, hand.q_upper)


def render_design_grid(
    path: str | Path,
    designs: Sequence[tuple[float, float]] = DEFAULT_DESIGNS,
    q: np.ndarray | None = None,
    *,
    ncols: int = 3,
    show_axes: bool = True,
    size: tuple[int, int] | None = None,
    view: tuple[float, float] | None = None,
    title: str | None = "Thumb design alternatives (c = CMC axis tilt, m = MCP axis turn)",
) -> RenderInfo:
    """One figure, one subplot per design (c, m) in degrees, the same posture ``q``
    (default: thumb CMC 60°, MCP 40°, IP 30°, fingers slightly bent) so the designs differ."""
    t0 = time.perf_counter()
    n = len(designs)
    ncols = min(ncols, n)
    nrows = int(np.ceil(n / ncols))
    if size is None:
        size = (400 * ncols, 420 * nrows)
    dpi = 100
    view = HAND_VIEW if view is None else view
    fig = plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.92 if title else 0.97, wspace=0, hspace=0.05)
    n_poly = 0
    for i, (c, m) in enumerate(designs):
        hand = build_hand(c, m)
        ax = _new_axes(fig, nrows, ncols, i + 1)
        qi = grid_pose(hand) if q is None else np.asarray(q, float)
        k, _ = _draw_scene(
            ax,
            hand=hand,
            q=qi,
            T_object_palm=None,
            obj=None,
            contacts=None,
            show_axes=show_axes,
            show_frame=False,
            view=view,
            zoom=1.2,
        )
        n_poly += k
        ax.set_title(f"c = {c:g}°, m = {m:g}°", fontsize=12, y=0.98)
    if title:
        fig.suptitle(title, fontsize=13)
    out = _save(fig, path, dpi)
    return RenderInfo(out, size, time.perf_counter() - t0, n_poly)


def make_static_pictures(folder: str | Path = "static") -> list[RenderInfo]:
    """The README pictures: baseline hand, design grid, each shipped object at roll 0."""
    from app.objects import OBJECT_KEYS

    d = Path(folder)
    out = [
        render_hand(d / "hand_baseline.png", 0.0, 45.0),
        render_design_grid(d / "hand_designs.png"),
    ]
    out += [render_object(d / f"object_{k}.png", k) for k in OBJECT_KEYS]
    return out


if __name__ == "__main__":
    for info in make_static_pictures():
        print(f"{info.path}: {info.seconds:.2f} s, {info.n_polygons} polygons")
