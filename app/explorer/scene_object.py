"""The object side of the scene: the object mesh, the approach cone, P and n, contacts."""

from __future__ import annotations

import numpy as np
import trimesh
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
CONTACT_RADIUS_MM = 4.0
"""Contact markers: spheres this big (a fingertip pad is ~10 mm wide) ..."""
OUTLINE_SCALE = 1.45
"""... with a dark outline (the back faces of a sphere this much larger)."""
CONTACT_SPHERE_SUBDIVISIONS = 1
"""A contact marker is an 80-triangle icosphere (and its outline another): a grasp has up to
~100 contacts, and at 320 triangles the markers took a quarter of a software-WebGL frame."""
OUTLINE_COLOR = (25, 25, 25)
OBJECT_OPACITY_WITH_CONTACTS = 0.5
"""The object turns translucent while contacts are shown, so none hides behind it."""
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
        self.contacts_node: viser.BatchedMeshHandle | None = None
        self.n_contacts = 0
        self.classes: set[str] = set()
        """Contact classes ('palmar', 'non_palmar', 'palm') shown now."""
        self._mesh: tuple[np.ndarray, np.ndarray] | None = None
        self._translucent = False
        sphere = trimesh.creation.icosphere(
            subdivisions=CONTACT_SPHERE_SUBDIVISIONS, radius=CONTACT_RADIUS_MM
        )
        self._sphere = (to_scene(sphere.vertices), np.asarray(sphere.faces, np.uint32))

    def set_object(self, mesh_vertices_mm: np.ndarray, faces: np.ndarray) -> None:
        """(Re)draw the object mesh (object frame)."""
        self._mesh = (to_scene(mesh_vertices_mm), np.asarray(faces, dtype=np.uint32))
        self._draw_mesh()

    def _draw_mesh(self) -> None:
        if self._mesh is None:
            return
        self.scene.add_mesh_simple(
            f"{self.root}/mesh",
            vertices=self._mesh[0],
            faces=self._mesh[1],
            color=OBJECT_COLOR,
            opacity=OBJECT_OPACITY_WITH_CONTACTS if self._translucent else None,
            flat_shading=False,
        )

    def _set_translucent(self, on: bool) -> None:
        if on != self._translucent:
            self._translucent = on
            self._draw_mesh()

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
        """Contact spheres (outlined, coloured by class) and their normals, or remove them.
        The object is translucent while contacts are shown."""
        empty = contacts is None or len(contacts) == 0
        self._set_translucent(not empty)
        if contacts is None or empty:
            for name in ("contacts", "contacts_outline", "normals"):
                self.scene.add_point_cloud(
                    f"{self.root}/{name}",
                    points=np.zeros((0, 3), np.float32),
                    colors=(0, 0, 0),
                    visible=False,
                )
            self.contacts_node = None
            self.n_contacts = 0
            self.classes = set()
            return
        colors = contact_colors(contacts)
        pos = to_scene(contacts.p_object)
        wxyz = np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (len(pos), 1))
        v, f = self._sphere
        self.scene.add_batched_meshes_simple(
            f"{self.root}/contacts_outline", v, f, wxyz, pos,
            batched_scales=np.full(len(pos), OUTLINE_SCALE, np.float32),
            batched_colors=OUTLINE_COLOR, side="back", cast_shadow=False, lod="off",
        )  # fmt: skip
        self.contacts_node = self.scene.add_batched_meshes_simple(
            f"{self.root}/contacts", v, f, wxyz, pos,
            batched_colors=colors, cast_shadow=False, lod="off",
        )  # fmt: skip
        seg = np.stack(
            [contacts.p_object, contacts.p_object - NORMAL_LENGTH_MM * contacts.n_object], axis=1
        )
        self.scene.add_line_segments(
            f"{self.root}/normals",
            points=to_scene(seg),
            colors=np.repeat(colors[:, None, :], 2, axis=1),
            thickness=3.0,
            thickness_units="screen",
        )
        self.n_contacts = len(contacts)
        self.classes = {
            k for k, c in CONTACT_COLORS.items() if (colors == np.array(c, np.uint8)).all(1).any()
        }
