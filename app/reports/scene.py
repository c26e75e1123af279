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
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from mpl_toolkits.mplot3d import Axes3D, proj3d  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection  # noqa: E402
from scipy.spatial import KDTree  # noqa: E402

from app.model.contact_set import ContactSet, finger_of  # noqa: E402
from app.model.hand.model import Hand  # noqa: E402

if TYPE_CHECKING:
    from app.model.objects import GraspObject

from app.reports.mesh import (
    MAX_EDGE_MM,
    OBJECT_EDGE_DIVISIONS,
    OBJECT_RGB,
    R_DISPLAY_PALM,
    RAY_RGB,
    Part,
    hand_mesh_parts,
    part,
    transform,
    tube_parts,
)

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


#: Contact colours: palmar contact on a finger, non-palmar contact, contact on the palm.
CONTACT_RGB = {"palmar": "#1a9e3a", "non-palmar": "#f28c1c", "palm": "#1f5fd6"}


#: Thumb joint axis colours.
THUMB_AXIS_RGB = {"CMC": "#d62728", "MCP": "#2ca02c", "IP": "#1f77b4"}


AMBIENT = 0.38


DIFFUSE = 0.62


SPECULAR = 0.12


SHININESS = 24.0


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


def camera(view: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit vectors (toward the eye, screen right, screen up) of matplotlib's camera."""
    el, az = np.deg2rad(view[0]), np.deg2rad(view[1])
    eye = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross([0.0, 0.0, 1.0], eye)
    if np.linalg.norm(right) < 1e-9:  # looking straight down or up
        right = np.array([-np.sin(az), np.cos(az), 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(eye, right)
    return eye, right, up


def shaded_polys(parts: Sequence[Part], view: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Cull back faces, Lambert + a little Blinn-Phong; returns (tris (F,3,3), rgba (F,4))."""
    eye, right, up = camera(view)
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


def new_axes(fig: Figure, *args: Any) -> Axes3D:
    ax = fig.add_subplot(*args, projection="3d")
    assert isinstance(ax, Axes3D)
    ax.set_proj_type("ortho")
    ax.computed_zorder = False  # overlays (axes, contacts) stay on top of the meshes
    ax.set_axis_off()
    ax.patch.set_alpha(0.0)  # axes squares may overlap their neighbours' cells
    return ax


def set_limits(ax: Axes3D, pts: np.ndarray) -> tuple[float, float, float]:
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


def fit(ax: Axes3D, pts: np.ndarray, target: tuple[float, float, float, float]) -> None:
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
    box = set_limits(ax, pts)
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


def draw_meshes(ax: Axes3D, parts: Sequence[Part], view: tuple[float, float]) -> int:
    tris, rgba = shaded_polys(parts, view)
    coll = Poly3DCollection(list(tris), facecolors=rgba, edgecolors=rgba, linewidths=0.6, zorder=1)
    coll.set_zsort("average")
    ax.add_collection3d(coll)
    ax.view_init(elev=view[0], azim=view[1])
    return len(tris)


def arrow(ax: Axes3D, tail: np.ndarray, vec: np.ndarray, **kw: Any) -> None:
    x, y, z = (float(c) for c in tail)
    u, v, w = (float(c) for c in vec)
    ax.quiver(x, y, z, u, v, w, **kw)


def text(ax: Axes3D, p: np.ndarray, s: str, **kw: Any) -> None:
    ax.text(float(p[0]), float(p[1]), float(p[2]), s, **kw)


def draw_joint_axes(
    ax: Axes3D, hand: Hand, q: np.ndarray, T_display_palm: np.ndarray, scale: float
) -> list[np.ndarray]:
    """Short arrows along the joint axes; the thumb's three highlighted and labelled."""
    p_palm, a_palm = hand.joint_axes(q)
    p = transform(T_display_palm, p_palm)
    a = a_palm @ T_display_palm[:3, :3].T
    ends: list[np.ndarray] = []
    for j in range(len(p)):
        if j < 3:
            name = ("CMC", "MCP", "IP")[j]
            length = 0.16 * scale
            tail = p[j] - 0.45 * length * a[j]
            vec = 1.45 * length * a[j]
            arrow(
                ax, tail, vec, color=THUMB_AXIS_RGB[name], linewidth=2.6,
                arrow_length_ratio=0.22, zorder=10,
            )  # fmt: skip
            tip = tail + vec
            text(
                ax, tip + 0.03 * scale * a[j], name, color=THUMB_AXIS_RGB[name],
                fontsize=11, fontweight="bold", zorder=11,
            )  # fmt: skip
            ends += [tail, tip, tip + 0.08 * scale * a[j]]
        else:
            length = 0.09 * scale
            tail = p[j] - 0.5 * length * a[j]
            arrow(
                ax, tail, length * a[j], color="#444444", linewidth=0.9, alpha=0.6,
                arrow_length_ratio=0.3, zorder=9,
            )  # fmt: skip
            ends += [tail, tail + length * a[j]]
    return ends


def draw_contacts(
    ax: Axes3D, contacts: ContactSet, T_display_frame: np.ndarray, scale: float
) -> tuple[str, ...]:
    if len(contacts) == 0:
        return ()
    p = transform(T_display_frame, contacts.p_object)
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


def draw_frame_triad(
    ax: Axes3D,
    R_display_frame: np.ndarray,
    pts: np.ndarray,
    view: tuple[float, float],
    length: float,
    name: str,
) -> np.ndarray:
    """A small x/y/z triad of the scene's frame at the bounding-box corner that appears
    lowest-left on screen (an orientation gizmo, out of the way of the meshes)."""
    _, right, up = camera(view)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])  # fmt: skip
    o = corners[np.argmin(corners @ right + corners @ up)]
    ends = [o]
    for k, (lab, col) in enumerate(zip("xyz", ("#c0392b", "#27ae60", "#2e6fd8"), strict=True)):
        d = R_display_frame[:, k] * length
        arrow(ax, o, d, color=col, linewidth=1.4, arrow_length_ratio=0.25, zorder=8)
        text(ax, o + 1.18 * d, lab, color=col, fontsize=9, zorder=8)
        ends.append(o + 1.2 * d)
    text(ax, o - 0.35 * length * up, f"{name} frame", color="#555555", fontsize=8, zorder=8)
    return np.array(ends)


def save(fig: Figure, path: str | Path, dpi: int) -> Path:
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi, facecolor="white")
    plt.close(fig)
    return out


def ray_length(t: np.ndarray, d: np.ndarray, hand_parts: Sequence[Part], scale: float) -> float:
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


def draw_scene(
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
        obj_parts = [part(obj.mesh, T_display_frame, OBJECT_RGB, edge)]
    hand_parts: list[Part] = []
    q_ = None
    if hand is not None:
        q_ = hand.q_open if q is None else np.asarray(q, float)
        hand_parts = hand_mesh_parts(hand, q_, T_display_palm, detail)
    parts = obj_parts + hand_parts
    if not parts:
        raise ValueError("render_scene needs a hand, an object, or both")
    pts = [np.concatenate([p.tris.reshape(-1, 3) for p in parts])]
    scale = float(np.ptp(pts[0], axis=0).max())
    if approach_ray is not None:
        ray_o, ray_d = (np.asarray(v, float) for v in approach_ray)
        t = transform(T_display_frame, ray_o[None])[0]
        d = T_display_frame[:3, :3] @ ray_d
        d = d / np.linalg.norm(d)
        end = t + d * ray_length(t, d, hand_parts, scale)
        parts += tube_parts(t, end, 0.005 * scale, RAY_RGB)
        pts.append(np.stack([t, end]))
    n_poly = draw_meshes(ax, parts, view)
    if hand is not None and show_axes and q_ is not None:
        hand_pts = np.concatenate([p.tris.reshape(-1, 3) for p in hand_parts])
        hand_scale = float(np.ptp(hand_pts, axis=0).max())
        pts.append(np.array(draw_joint_axes(ax, hand, q_, T_display_palm, hand_scale)))
    if show_frame:
        pts.append(
            draw_frame_triad(
                ax, T_display_frame[:3, :3], np.concatenate(pts), view, 0.08 * scale, frame_name
            )
        )
    labels: tuple[str, ...] = ()
    if contacts is not None:
        labels = draw_contacts(ax, contacts, T_display_frame, scale)
    fit(ax, np.concatenate(pts), target)
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
    ax = new_axes(fig, 1, 1, 1)
    m = 0.04 * min(size)
    target = (m, m, size[0] - m, size[1] - m - (0.06 * size[1] if title else 0.0))
    n_poly, labels = draw_scene(
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
    out = save(fig, path, dpi)
    return RenderInfo(out, size, time.perf_counter() - t0, n_poly, labels)
