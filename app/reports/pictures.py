"""The shipped pictures: the hand alone, an object with the hand at roll 0, the design grid,
and ``make_static_pictures`` (the README's ``static/`` folder).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402

from app.model.contact_set import ContactSet  # noqa: E402
from app.model.hand.model import Hand, build_hand  # noqa: E402
from app.sim.hypotheses import palm_orientation  # noqa: E402

if TYPE_CHECKING:
    from app.model.objects import GraspObject

from app.reports.mesh import GRID_DETAIL, transform
from app.reports.scene import (
    CLEARANCE_SPACING_MM,
    CONTACT_TOL_MM,
    MIN_STEP_MM,
    OBJECT_VIEWS,
    RenderInfo,
    draw_scene,
    new_axes,
    render_scene,
    save,
)

#: Camera of the design grid: from the palmar, radial and distal side, so the thumb's
#: opposition shows.
GRID_VIEW = (30.0, -38.0)


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
        pts.append(transform(poses[i], p_link))
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
    from app.model.objects import load_object

    t0 = time.perf_counter()
    obj = load_object(key)
    hand = build_hand(cmc_deg, mcp_deg, cmc_tilt=cmc_tilt) if with_hand else None
    T = roll0_pose(hand, obj, standoff_mm=standoff_mm) if hand is not None else None
    if title is None:
        title = f"{obj.spec.name} ({obj.spec.grasp_type})"
        if hand is not None:
            d = float(min(obj.spec.setup.standoffs_mm)) if standoff_mm is None else standoff_mm
            title += f": hand c = {cmc_deg:g}°, m = {mcp_deg:g}° at roll 0, axis ray, δ = {d:g} mm"
    if view is None and T is not None and key not in OBJECT_VIEWS:
        # an imported object: the camera of the object it was imported like (its frame was
        # turned to match, --up/--rotate), else one on the hand's radial (thumb) side, a
        # little distal and dorsal, where the grip is visible whatever the mesh
        from app.reports.grasp_view import grasp_view_angles

        like = str(obj.spec.shape.get("like", ""))
        view = OBJECT_VIEWS.get(like) or grasp_view_angles(T)
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
        ax = new_axes(fig, nrows, ncols, i + 1)
        r, c_ = divmod(i, ncols)
        x0, y1 = c_ * cell_w, top - r * cell_h
        pad = 0.05 * min(cell_w, cell_h)
        target = (x0 + pad, y1 - cell_h + pad, x0 + cell_w - pad, y1 - pad - 28.0)
        qi = grid_pose(hand) if q is None else np.asarray(q, float)
        k, _ = draw_scene(
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
    out = save(fig, path, dpi)
    return RenderInfo(out, size, time.perf_counter() - t0, n_poly)


def make_static_pictures(folder: str | Path = "static") -> list[RenderInfo]:
    """The README pictures: baseline hand, design grid, each shipped object at roll 0."""
    from app.model.objects import OBJECT_KEYS

    d = Path(folder)
    out = [
        render_hand(d / "hand_baseline.png", 0.0, 45.0),
        render_design_grid(d / "hand_designs.png"),
    ]
    out += [render_object(d / f"object_{k}.png", k) for k in OBJECT_KEYS]
    return out
