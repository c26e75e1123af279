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

import dataclasses
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
from mpl_toolkits.mplot3d import Axes3D, proj3d  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402
from scipy.spatial import KDTree  # noqa: E402

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
#: Camera of the design grid: from the palmar, radial and distal side, so the thumb's
#: opposition shows.
GRID_VIEW = (30.0, -38.0)
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
GRID_FINGER_DEG = (10.0, 10.0, 5.0)
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
#: Longest edge (mm) of the triangles where one link enters another (a finger into the palm).
JUNCTION_EDGE_MM = 1.5
#: Object triangles are refined to edges of at most max(MAX_EDGE_MM, size / this).
OBJECT_EDGE_DIVISIONS = 20.0
#: Mesh detail of the design grid's small pictures (edges 1/GRID_DETAIL times longer).
GRID_DETAIL = 0.5
#: Sampling spacing (mm) of the link surfaces when the hand is moved to first contact.
CLEARANCE_SPACING_MM = 2.5
#: First-contact search: distance counted as contact, and the smallest sphere-tracing step.
CONTACT_TOL_MM = 0.2
MIN_STEP_MM = 1.5


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


_REFINED: dict[tuple[int, float], tuple[trimesh.Trimesh, np.ndarray, np.ndarray]] = {}


def _render_tris(
    mesh: trimesh.Trimesh, max_edge: float = MAX_EDGE_MM
) -> tuple[np.ndarray, np.ndarray]:
    """Refined triangles and their unit normals of a mesh in its own frame (cached)."""
    hit = _REFINED.get((id(mesh), max_edge))
    if hit is not None and hit[0] is mesh:
        return hit[1], hit[2]
    tris = _refine(np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)], max_edge)
    area2 = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    tris = tris[area2 > 1e-12]  # drop degenerate triangles
    n = _face_normals(tris)
    if len(_REFINED) > 64:
        _REFINED.clear()
    _REFINED[(id(mesh), max_edge)] = (mesh, tris, n)
    return tris, n


def _part(
    mesh: trimesh.Trimesh,
    T_display_mesh: np.ndarray,
    rgb: np.ndarray,
    max_edge: float = MAX_EDGE_MM,
) -> _Part:
    tris, n = _render_tris(mesh, max_edge)
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


def _hand_parts(
    hand: Hand, q: np.ndarray, T_display_palm: np.ndarray, detail: float = 1.0
) -> list[_Part]:
    """Posed, refined link meshes without the triangles buried inside another link (the
    capsule ends overlap at the joints and inside the palm; drawing them would confuse the
    painter's algorithm)."""
    meshes = hand.visual_meshes()
    poses = hand.link_poses(q)
    inv = np.linalg.inv(poses)
    parts = []
    for i, lk in enumerate(hand.links):
        tris, n = _render_tris(meshes[lk.name], MAX_EDGE_MM / detail)
        others = [j for j in range(len(hand.links)) if j != i]

        def corners_inside(t: np.ndarray, i: int = i, others: list[int] = others) -> np.ndarray:
            v_palm = _transform(poses[i], t.reshape(-1, 3))
            inside = np.zeros(len(v_palm), bool)
            for j in others:
                inside |= _inside_shape(hand.links[j].shape, _transform(inv[j], v_palm), 0.0)
            return inside.reshape(-1, 3)

        inside = corners_inside(tris)
        straddle = inside.any(axis=1) & ~inside.all(axis=1)
        if straddle.any():  # refine where a link enters another, then drop the buried bits
            fine = _refine(tris[straddle], JUNCTION_EDGE_MM / detail)
            fine_n = _face_normals(fine)
            keep = ~inside.any(axis=1)
            fine_keep = ~corners_inside(fine).all(axis=1)
            tris = np.concatenate([tris[keep], fine[fine_keep]])
            n = np.concatenate([n[keep], fine_n[fine_keep]])
        else:
            keep = ~inside.all(axis=1)
            tris, n = tris[keep], n[keep]
        T = T_display_palm @ poses[i]
        R, t = T[:3, :3], T[:3, 3]
        parts.append(_Part(tris @ R.T + t, n @ R.T, _link_rgb(lk.name)))
    return parts


def _face_normals(tris: np.ndarray) -> np.ndarray:
    """Unit normals (F, 3) of triangles (F, 3, 3) (right-hand rule)."""
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(norm > 1e-12, norm, 1.0)


def _camera(view: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (toward the eye, screen right, screen up) of matplotlib's camera."""
    el, az = np.deg2rad(view[0]), np.deg2rad(view[1])
    eye = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], eye)
    if np.linalg.norm(right) < 1e-9:  # looking straight down or up
        right = np.array([-np.sin(az), np.cos(az), 0.0])
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
    ax.patch.set_alpha(0.0)  # axes squares may overlap their neighbours' cells
    return ax


def _set_limits(ax: Axes3D, pts: np.ndarray) -> tuple[float, float, float]:
    """Equal-aspect data box around ``pts`` (a cube-free box: set_box_aspect from ranges)."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 1e-3)
    pad = 0.02 * span.max()
    lo, hi = lo - pad, hi + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    box = (float(hi[0] - lo[0]), float(hi[1] - lo[1]), float(hi[2] - lo[2]))
    ax.set_box_aspect(box, zoom=1)
    return box


def _fit(ax: Axes3D, pts: np.ndarray, target: tuple[float, float, float, float]) -> None:
    """Zoom and move the 3-D axes so that the projection of ``pts`` fills ``target``
    (x0, y0, x1, y1, figure pixels) and is centred in it. The orthographic projection is
    linear about the axes centre, so one measurement is enough."""
    fig = ax.get_figure(root=True)
    assert fig is not None
    W, H = fig.get_size_inches() * fig.dpi
    x0, y0, x1, y1 = target
    side = max(x1 - x0, y1 - y0)  # a square axes (Axes3D is always square) over the target
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    ax.set_position((float((cx - side / 2) / W), float((cy - side / 2) / H), side / W, side / H))
    ax.apply_aspect()
    box = _set_limits(ax, pts)
    xs, ys, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.get_proj())
    d = ax.transData.transform(np.column_stack([xs, ys]))
    centre = ax.transAxes.transform((0.5, 0.5))
    lo, hi = d.min(axis=0), d.max(axis=0)
    f = min((x1 - x0) / max(hi[0] - lo[0], 1e-6), (y1 - y0) / max(hi[1] - lo[1], 1e-6))
    ax.set_box_aspect(box, zoom=f)  # pyright: ignore[reportArgumentType]  (stub says int)
    now = centre + f * (0.5 * (lo + hi) - centre)  # content centre after the zoom
    shift = np.array([cx, cy]) - now
    pos = ax.get_position()
    ax.set_position((pos.x0 + shift[0] / W, pos.y0 + shift[1] / H, pos.width, pos.height))


def _draw_meshes(ax: Axes3D, parts: Sequence[_Part], view: tuple[float, float]) -> int:
    tris, rgba = _shaded_polys(parts, view)
    coll = Poly3DCollection(list(tris), facecolors=rgba, edgecolors=rgba, linewidths=0.6, zorder=1)
    coll.set_zsort("average")
    ax.add_collection3d(coll)
    ax.view_init(elev=view[0], azim=view[1])
    return len(tris)


def _arrow(ax: Axes3D, tail: np.ndarray, vec: np.ndarray, **kw: Any) -> None:
    x, y, z = (float(c) for c in tail)
    u, v, w = (float(c) for c in vec)
    ax.quiver(x, y, z, u, v, w, **kw)


def _text(ax: Axes3D, p: np.ndarray, s: str, **kw: Any) -> None:
    ax.text(float(p[0]), float(p[1]), float(p[2]), s, **kw)


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
            _arrow(
                ax, tail, vec, color=THUMB_AXIS_RGB[name], linewidth=2.6,
                arrow_length_ratio=0.22, zorder=10,
            )  # fmt: skip
            tip = tail + vec
            _text(
                ax, tip + 0.03 * scale * a[j], name, color=THUMB_AXIS_RGB[name],
                fontsize=11, fontweight="bold", zorder=11,
            )  # fmt: skip
            ends += [tail, tip, tip + 0.08 * scale * a[j]]
        else:
            length = 0.09 * scale
            tail = p[j] - 0.5 * length * a[j]
            _arrow(
                ax, tail, length * a[j], color="#444444", linewidth=0.9, alpha=0.6,
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
            p[sel, 0], p[sel, 1], p[sel, 2], s=36, c=col, depthshade=False,
            edgecolors="black", linewidths=0.3, zorder=12,
        )  # fmt: skip
        segs = np.stack([p[sel], p[sel] + nlen * n[sel]], axis=1)
        ax.add_collection3d(Line3DCollection(list(segs), colors=col, linewidths=1.6, zorder=12))
        handles.append(
            Line2D([], [], marker="o", linestyle="-", color=col, markeredgecolor="black",
                   markeredgewidth=0.3, label=labels[kind])
        )  # fmt: skip
    # a figure legend: the square 3-D axes may reach outside the figure, its corner too
    fig = ax.get_figure(root=True)
    assert fig is not None
    fig.legend(
        handles=handles,
        loc="upper right",
        bbox_to_anchor=(0.99, 0.93),
        fontsize=10,
        framealpha=0.9,
    )
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
        _arrow(ax, o, d, color=col, linewidth=1.4, arrow_length_ratio=0.25, zorder=8)
        _text(ax, o + 1.18 * d, lab, color=col, fontsize=9, zorder=8)
        ends.append(o + 1.2 * d)
    _text(ax, o - 0.35 * length * up, f"{name} frame", color="#555555", fontsize=8, zorder=8)
    return np.array(ends)


def _tube_parts(target: np.ndarray, end: np.ndarray, radius: float, rgb: np.ndarray) -> list[_Part]:
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
    tree = KDTree(v)
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
    target: tuple[float, float, float, float],
    detail: float = 1.0,
) -> tuple[int, tuple[str, ...]]:
    """Draw one scene on ``ax`` fitted into ``target`` (x0, y0, x1, y1, figure pixels);
    returns (polygons drawn, legend labels)."""
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
    obj_parts = []
    if obj is not None:
        extent = float(np.ptp(np.asarray(obj.mesh.vertices), axis=0).max())
        edge = max(MAX_EDGE_MM, extent / OBJECT_EDGE_DIVISIONS) / detail
        obj_parts = [_part(obj.mesh, T_display_frame, OBJECT_RGB, edge)]
    hand_parts: list[_Part] = []
    q_ = None
    if hand is not None:
        q_ = hand.q_open if q is None else np.asarray(q, float)
        hand_parts = _hand_parts(hand, q_, T_display_palm, detail)
    parts = obj_parts + hand_parts
    if not parts:
        raise ValueError("render_scene needs a hand, an object, or both")
    pts = [np.concatenate([p.tris.reshape(-1, 3) for p in parts])]
    scale = float(np.ptp(pts[0], axis=0).max())
    if approach_ray is not None:
        ray_o, ray_d = (np.asarray(v, float) for v in approach_ray)
        t = _transform(T_display_frame, ray_o[None])[0]
        d = T_display_frame[:3, :3] @ ray_d
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
    _fit(ax, np.concatenate(pts), target)
    for artist in [*ax.collections, *ax.lines, *ax.texts]:
        artist.set_clip_on(False)  # the content may overhang the (square) 3-D axes
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
    m = 0.04 * min(size)
    target = (m, m, size[0] - m, size[1] - m - (0.06 * size[1] if title else 0.0))
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
        target=target,
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
    for _ in range(500):  # sphere tracing: the SDF is 1-Lipschitz, a step of d is safe
        d = min_dist(s)
        if d < CONTACT_TOL_MM:
            break
        if d >= MIN_STEP_MM:
            s -= d
            continue
        # grazing: a fixed small step, then bisect back to the first contact
        lo, hi = s - MIN_STEP_MM, s
        if min_dist(lo) >= CONTACT_TOL_MM:
            s = lo
            continue
        while hi - lo > CONTACT_TOL_MM:
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if min_dist(mid) < CONTACT_TOL_MM else (mid, hi)
        s = hi
        break
    else:
        s = 0.0
    if s < -reach:  # the hand never meets the object along the ray
        s = 0.0
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

    t0 = time.perf_counter()
    obj = load_object(key)
    hand = build_hand(cmc_deg, mcp_deg, cmc_tilt=cmc_tilt) if with_hand else None
    T = roll0_pose(hand, obj, standoff_mm=standoff_mm) if hand is not None else None
    if title is None:
        title = f"{obj.spec.name} ({obj.spec.grasp_type})"
        if hand is not None:
            d = float(min(obj.spec.setup.standoffs_mm)) if standoff_mm is None else standoff_mm
            title += f": hand c = {cmc_deg:g}°, m = {mcp_deg:g}° at roll 0, axis ray, δ = {d:g} mm"
    info = render_scene(
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
    return dataclasses.replace(info, seconds=time.perf_counter() - t0)


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
    view = GRID_VIEW if view is None else view
    fig = plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    top = size[1] - (50.0 if title else 0.0)
    cell_w, cell_h = size[0] / ncols, top / nrows
    n_poly = 0
    for i, (c, m) in enumerate(designs):
        hand = build_hand(c, m)
        ax = _new_axes(fig, nrows, ncols, i + 1)
        r, c_ = divmod(i, ncols)
        x0, y1 = c_ * cell_w, top - r * cell_h
        pad = 0.05 * min(cell_w, cell_h)
        target = (x0 + pad, y1 - cell_h + pad, x0 + cell_w - pad, y1 - pad - 28.0)
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
            target=target,
            detail=GRID_DETAIL,
        )
        n_poly += k
        fig.text(
            (x0 + cell_w / 2) / size[0], (y1 - 8.0) / size[1], f"c = {c:g}°, m = {m:g}°",
            ha="center", va="top", fontsize=12,
        )  # fmt: skip
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
