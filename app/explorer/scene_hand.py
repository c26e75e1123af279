"""The hand in the scene: one mesh node per link, added once, then moved by pose updates."""

from __future__ import annotations

import numpy as np
import viser

from app.explorer.units import MM, pose_to_scene, to_scene
from app.model.hand.model import Hand

HAND_COLOR = (214, 186, 160)
THUMB_COLOR = (196, 160, 130)
GHOST_COLOR = (90, 130, 220)
GHOST_OPACITY = 0.35
SEE_THROUGH_OPACITY = 0.5
"""Links that carry a contact are this opaque while contacts are shown: a contact sits
between the finger and the object, so an opaque finger hid it from half the views."""
#: Joint-axis colours: CMC red, MCP green, IP blue (thumb), long fingers grey.
AXIS_COLORS = ((220, 40, 40), (30, 160, 60), (40, 90, 220))
AXIS_HALF_LENGTH_MM = 22.0
PATH_COLOR = (220, 60, 200)
"""The thumb pad's flexion path (the design's opposition), magenta."""
PATH_STEPS = 24
THUMB_AXIS_HALF_LENGTH_MM = 32.0
"""The thumb's axes are the design: drawn longer than the long fingers'."""


class HandView:
    """Draws a ``Hand`` placed by ``T_object_palm`` at joint angles ``q``."""

    def __init__(
        self,
        scene: viser.SceneApi,
        hand: Hand,
        root: str = "/hand",
        *,
        prefix: str = "",
        ghost: bool = False,
    ) -> None:
        """``prefix``: draw only the links whose names start with it ('thumb' for the
        ghost); ``ghost``: one translucent blue colour, no shadows, hidden at first."""
        self.scene = scene
        self.root = root
        self.ghost = ghost
        self.nodes: dict[str, viser.MeshHandle] = {}
        self._corners: dict[str, np.ndarray] = {}
        for name, mesh in hand.visual_meshes().items():
            lo, hi = np.asarray(mesh.bounds, float)
            self._corners[name] = np.array(
                [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
            )
            if not name.startswith(prefix):
                continue
            color = THUMB_COLOR if name.startswith("thumb") else HAND_COLOR
            self.nodes[name] = scene.add_mesh_simple(
                f"{root}/{name}",
                vertices=to_scene(mesh.vertices),
                faces=np.asarray(mesh.faces, dtype=np.uint32),
                color=GHOST_COLOR if ghost else color,
                opacity=GHOST_OPACITY if ghost else None,
                flat_shading=False,
                cast_shadow=not ghost,
                visible=not ghost,
            )
        self.axes: viser.LineSegmentsHandle | None = None
        self.path: viser.LineSegmentsHandle | None = None
        self.show_axes = ghost
        self.thumb_axes_only = True
        """Only the thumb's axes (the design); the long fingers' are the same in every one."""
        self.see_through: set[str] = set()
        """Links drawn translucent now (``set_see_through``)."""
        self.hand = hand
        self.T_object_palm = np.eye(4)
        self.q = hand.q_open

    def set_pose(self, hand: Hand, T_object_palm: np.ndarray, q: np.ndarray) -> None:
        """Move every link node (one websocket batch); redraw the joint axes if shown."""
        self.hand, self.T_object_palm, self.q = hand, T_object_palm, np.asarray(q, float)
        T_object_link = T_object_palm[None] @ hand.link_poses(self.q)
        for lk, T in zip(hand.links, T_object_link, strict=True):
            node = self.nodes.get(lk.name)
            if node is None:
                continue
            wxyz, pos = pose_to_scene(T)
            node.wxyz = wxyz
            node.position = pos
        self._draw_axes()

    def set_see_through(self, links: set[str]) -> None:
        """Make ``links`` translucent (the ones carrying shown contacts), the others opaque."""
        if self.ghost:
            return
        for name, node in self.nodes.items():
            want = SEE_THROUGH_OPACITY if name in links else None
            if node.opacity != want:
                node.opacity = want
        self.see_through = set(links) & set(self.nodes)

    def set_visible(self, visible: bool) -> None:
        """Show or hide every link node."""
        for node in self.nodes.values():
            node.visible = visible
        for node in (self.axes, self.path):
            if node is not None:
                node.visible = visible and self.show_axes

    @property
    def visible(self) -> bool:
        """Whether the links are shown."""
        return any(n.visible for n in self.nodes.values())

    def points_mm(self, prefix: str = "") -> np.ndarray:
        """(8K, 3) box corners of the links named ``prefix``…, object frame, mm (framing)."""
        return self.points_mm_at(self.hand, self.T_object_palm, self.q, prefix)

    def points_mm_at(
        self, hand: Hand, T_object_palm: np.ndarray, q: np.ndarray, prefix: str = ""
    ) -> np.ndarray:
        """``points_mm`` of ``hand`` placed at ``T_object_palm`` with joints ``q``."""
        T = np.asarray(T_object_palm)[None] @ hand.link_poses(np.asarray(q, float))
        out = [
            self._corners[lk.name] @ T[k, :3, :3].T + T[k, :3, 3]
            for k, lk in enumerate(hand.links)
            if lk.name.startswith(prefix)
        ]
        return np.vstack(out)

    def link_position_mm(self, name: str) -> np.ndarray:
        """Where the node of link ``name`` is now, object frame, mm (read back from viser)."""
        return np.asarray(self.nodes[name].position, dtype=float) / MM

    def set_axes_visible(self, visible: bool) -> None:
        """Show or hide the joint axes (thumb CMC/MCP/IP coloured, long fingers grey)."""
        self.show_axes = visible
        self._draw_axes()

    def flex_path_mm(self) -> np.ndarray:
        """(PATH_STEPS, 3) the thumb pad (centre of the distal phalanx) as the thumb's
        three joints flex from the shown pose to their upper limits, object frame, mm.
        At zero flexion every design looks alike; this path is where the design shows."""
        h = self.hand
        k = h.link_index["thumb_distal"]
        centre = self._corners["thumb_distal"].mean(axis=0)
        q0 = np.asarray(self.q, float)
        out = []
        for t in np.linspace(0.0, 1.0, PATH_STEPS):
            q = q0.copy()
            q[:3] = q0[:3] + t * (h.q_upper[:3] - q0[:3])
            T = self.T_object_palm @ h.link_poses(q)[k]
            out.append(T[:3, :3] @ centre + T[:3, 3])
        return np.array(out)

    def _draw_axes(self) -> None:
        if not self.show_axes:
            if self.axes is not None:
                self.axes.visible = False
            if self.path is not None:
                self.path.visible = False
            return
        path = self.flex_path_mm()
        pc = np.array(PATH_COLOR, float)
        if self.ghost:
            pc = 0.45 * pc + 0.55 * 255
        self.path = self.scene.add_line_segments(
            f"{self.root}_path",
            points=to_scene(np.stack([path[:-1], path[1:]], axis=1)),
            colors=pc.astype(np.uint8),
            thickness=3.0 if self.ghost else 5.0,
            thickness_units="screen",
        )
        p, a = self.hand.joint_axes(self.q)
        R, t = self.T_object_palm[:3, :3], self.T_object_palm[:3, 3]
        p_obj = p @ R.T + t
        a_obj = a @ R.T
        n = 3 if self.thumb_axes_only else len(p)
        p_obj, a_obj = p_obj[:n], a_obj[:n]
        half = np.where(np.arange(n) < 3, THUMB_AXIS_HALF_LENGTH_MM, AXIS_HALF_LENGTH_MM)
        seg = np.stack([p_obj - half[:, None] * a_obj, p_obj + half[:, None] * a_obj], axis=1)
        colors = np.array([AXIS_COLORS[k] if k < 3 else (120, 120, 120) for k in range(n)], float)
        if self.ghost:  # faded: the previous design's axes
            colors = 0.45 * colors + 0.55 * 255
        colors = np.repeat(colors[:, None, :], 2, axis=1).astype(np.uint8)
        self.axes = self.scene.add_line_segments(
            f"{self.root}_axes",
            points=to_scene(seg),
            colors=colors,
            thickness=3.0 if self.ghost else 5.0,
            thickness_units="screen",
        )
