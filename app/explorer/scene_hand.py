"""The hand in the scene: one mesh node per link, added once, then moved by pose updates."""

from __future__ import annotations

import numpy as np
import viser

from app.explorer.units import MM, pose_to_scene, to_scene
from app.model.hand.model import Hand

HAND_COLOR = (214, 186, 160)
THUMB_COLOR = (196, 160, 130)
#: Joint-axis colours: CMC red, MCP green, IP blue (thumb), long fingers grey.
AXIS_COLORS = ((220, 40, 40), (30, 160, 60), (40, 90, 220))
AXIS_HALF_LENGTH_MM = 22.0


class HandView:
    """Draws a ``Hand`` placed by ``T_object_palm`` at joint angles ``q``."""

    def __init__(self, scene: viser.SceneApi, hand: Hand, root: str = "/hand") -> None:
        self.scene = scene
        self.root = root
        self.nodes: dict[str, viser.MeshHandle] = {}
        for name, mesh in hand.visual_meshes().items():
            color = THUMB_COLOR if name.startswith("thumb") else HAND_COLOR
            self.nodes[name] = scene.add_mesh_simple(
                f"{root}/{name}",
                vertices=to_scene(mesh.vertices),
                faces=np.asarray(mesh.faces, dtype=np.uint32),
                color=color,
                flat_shading=False,
            )
        self.axes: viser.LineSegmentsHandle | None = None
        self.show_axes = False
        self.hand = hand
        self.T_object_palm = np.eye(4)
        self.q = hand.q_open

    def set_pose(self, hand: Hand, T_object_palm: np.ndarray, q: np.ndarray) -> None:
        """Move every link node (one websocket batch); redraw the joint axes if shown."""
        self.hand, self.T_object_palm, self.q = hand, T_object_palm, np.asarray(q, float)
        T_object_link = T_object_palm[None] @ hand.link_poses(self.q)
        for lk, T in zip(hand.links, T_object_link, strict=True):
            wxyz, pos = pose_to_scene(T)
            node = self.nodes[lk.name]
            node.wxyz = wxyz
            node.position = pos
        self._draw_axes()

    def link_position_mm(self, name: str) -> np.ndarray:
        """Where the node of link ``name`` is now, object frame, mm (read back from viser)."""
        return np.asarray(self.nodes[name].position, dtype=float) / MM

    def set_axes_visible(self, visible: bool) -> None:
        """Show or hide the joint axes (thumb CMC/MCP/IP coloured, long fingers grey)."""
        self.show_axes = visible
        self._draw_axes()

    def _draw_axes(self) -> None:
        if not self.show_axes:
            if self.axes is not None:
                self.axes.visible = False
            return
        p, a = self.hand.joint_axes(self.q)
        R, t = self.T_object_palm[:3, :3], self.T_object_palm[:3, 3]
        p_obj = p @ R.T + t
        a_obj = a @ R.T
        seg = np.stack(
            [p_obj - AXIS_HALF_LENGTH_MM * a_obj, p_obj + AXIS_HALF_LENGTH_MM * a_obj], axis=1
        )
        colors = np.array([AXIS_COLORS[k] if k < 3 else (120, 120, 120) for k in range(len(p))])
        colors = np.repeat(colors[:, None, :], 2, axis=1).astype(np.uint8)
        self.axes = self.scene.add_line_segments(
            f"{self.root}_axes",
            points=to_scene(seg),
            colors=colors,
            thickness=4.0,
            thickness_units="screen",
        )
