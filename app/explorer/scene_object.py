"""The object side of the scene: the object mesh, the approach cone, P and n, contacts."""

from __future__ import annotations

import numpy as np
import viser

from app.explorer.units import to_scene
from app.model.contact_set import ContactSet
from app.sim.hypotheses import Hypotheses

OBJECT_COLOR = (150, 170, 190)
RAY_COLOR = (150, 150, 150)
SELECTED_RAY_COLOR = (230, 120, 20)
P_COLOR = (200, 30, 160)
N_COLOR = (200, 30, 160)
#: Contact colours (the legend in the replay panel uses the same names).
CONTACT_COLORS = {
    "palmar": (30, 170, 60),
    "non_palmar": (245, 140, 20),
    "palm": (40, 100, 230),
}
RAY_LENGTH_MM = 120.0
NORMAL_LENGTH_MM = 20.0
N_LENGTH_MM = 60.0


def contact_colors(contacts: ContactSet) -> np.ndarray:
    """(K, 3) uint8: palm blue, palmar finger contact green, non-palmar orange."""
    out = np.empty((len(contacts), 3), dtype=np.uint8)
    for k, (link, palmar) in enumerate(zip(contacts.link, contacts.palmar, strict=True)):
        if str(link) == "palm":
            out[k] = CONTACT_COLORS["palm"]
        else:
            out[k] = CONTACT_COLORS["palmar" if palmar else "non_palmar"]
    return out


class ObjectView:
    """Draws one object with its hypotheses' cone, the palm point P, n and contacts."""

    def __init__(self, scene: viser.SceneApi, root: str = "/object") -> None:
        self.scene = scene
        self.root = root
        self.contacts_node: viser.PointCloudHandle | None = None
        self.n_contacts = 0

    def set_object(self, mesh_vertices_mm: np.ndarray, faces: np.ndarray) -> None:
        """(Re)draw the object mesh (object frame)."""
        self.scene.add_mesh_simple(
            f"{self.root}/mesh",
            vertices=to_scene(mesh_vertices_mm),
            faces=np.asarray(faces, dtype=np.uint32),
            color=OBJECT_COLOR,
            flat_shading=False,
        )

    def set_cone(self, hyps: Hypotheses, selected: int) -> None:
        """One segment per approach ray, from the target outward; the selected GH's ray
        highlighted."""
        rays_idx, first = np.unique(hyps.ray_index, return_index=True)
        rays = hyps.ray_object[first]
        t = hyps.target_object
        seg = np.stack([np.broadcast_to(t, rays.shape), t + RAY_LENGTH_MM * rays], axis=1)
        colors = np.tile(np.array(RAY_COLOR, dtype=np.uint8), (len(rays), 2, 1))
        sel = int(np.searchsorted(rays_idx, hyps.ray_index[selected]))
        colors[sel] = SELECTED_RAY_COLOR
        self.scene.add_line_segments(
            f"{self.root}/cone",
            points=to_scene(seg),
            colors=colors,
            thickness=1.5,
            thickness_units="screen",
        )

    def set_palm_point(self, T_object_palm: np.ndarray, p_palm: np.ndarray, n_palm: np.ndarray):
        """The approach point P (sphere) and the hand vector n (segment toward the object)."""
        R, t = T_object_palm[:3, :3], T_object_palm[:3, 3]
        p = R @ p_palm + t
        n = R @ n_palm
        self.scene.add_icosphere(
            f"{self.root}/P", radius=0.004, color=P_COLOR, position=tuple(to_scene(p))
        )
        self.scene.add_line_segments(
            f"{self.root}/n",
            points=to_scene(np.stack([p, p - N_LENGTH_MM * n])[None]),
            colors=N_COLOR,
            thickness=4.0,
            thickness_units="screen",
        )

    def set_contacts(self, contacts: ContactSet | None) -> None:
        """Contact points (point cloud) and their normals (segments), or remove them."""
        if contacts is None or len(contacts) == 0:
            for name in ("contacts", "normals"):
                self.scene.add_point_cloud(
                    f"{self.root}/{name}",
                    points=np.zeros((0, 3), np.float32),
                    colors=(0, 0, 0),
                    visible=False,
                )
            self.n_contacts = 0
            return
        colors = contact_colors(contacts)
        self.contacts_node = self.scene.add_point_cloud(
            f"{self.root}/contacts",
            points=to_scene(contacts.p_object),
            colors=colors,
            point_size=0.006,
            point_shape="circle",
            precision="float32",
        )
        seg = np.stack(
            [contacts.p_object, contacts.p_object - NORMAL_LENGTH_MM * contacts.n_object], axis=1
        )
        self.scene.add_line_segments(
            f"{self.root}/normals",
            points=to_scene(seg),
            colors=np.repeat(colors[:, None, :], 2, axis=1),
            thickness=2.0,
            thickness_units="screen",
        )
        self.n_contacts = len(contacts)
