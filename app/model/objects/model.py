"""GraspObject (spec + geometry), the object loader and the registry of imported objects."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import fcl
import numpy as np
import trimesh

from app.errors import UnknownObjectError
from app.model.objects.shapes import Geometry, Piece, SdfPart, build
from app.model.objects.spec import OBJECT_KEYS, ObjectSpec, data_dir, read_spec, user_dir

#: Central-difference step (mm) of the numerical SDF gradient.
NORMAL_STEP_MM = 0.05


class GraspObject:
    """One graspable object: its spec (data file) and its geometry, object frame, mm."""

    spec: ObjectSpec
    """The data file content."""
    mesh: trimesh.Trimesh
    """Watertight triangle mesh, object frame, mm."""
    centroid_object: np.ndarray
    """(3,) centre of mass of the mesh (uniform density), mm."""
    max_radius: float
    """Largest distance from the centroid to a mesh vertex, mm."""

    def __init__(self, spec: ObjectSpec, geometry: Geometry) -> None:
        self.spec = spec
        self._geometry = geometry
        self.mesh = geometry.mesh
        self.centroid_object = np.asarray(self.mesh.center_mass, dtype=float)
        self.max_radius = float(
            np.linalg.norm(self.mesh.vertices - self.centroid_object, axis=1).max()
        )
        self._collision: list[Any] | None = None

    def __repr__(self) -> str:
        return (
            f"GraspObject({self.spec.key!r}, {self.spec.grasp_type}, "
            f"{len(self.mesh.faces)} faces, {len(self._geometry.pieces)} pieces)"
        )

    @property
    def key(self) -> str:
        """The object key."""
        return self.spec.key

    def sdf(self, p_object: np.ndarray) -> np.ndarray:
        """Signed distance (mm) of points (N, 3) in the object frame -> (N,), negative inside.

        Exact outside; inside, unions of primitives give the largest primitive depth (a
        lower bound of the true depth). Imported meshes: exact within 8 mm of the surface,
        within about 1 mm (the distance field's spacing) farther (``distance_field``).
        """
        p = np.asarray(p_object, dtype=float).reshape(-1, 3)
        return self._geometry.sdf(p)

    def normal(self, p_object: np.ndarray) -> np.ndarray:
        """Outward unit normal (N, 3) at points (N, 3): the SDF gradient (central differences)."""
        p = np.asarray(p_object, dtype=float).reshape(-1, 3)
        n_pts = len(p)
        h = NORMAL_STEP_MM
        offsets = np.vstack([np.eye(3) * h, -np.eye(3) * h])  # (6, 3)
        q = (p[None, :, :] + offsets[:, None, :]).reshape(-1, 3)
        d = self._geometry.sdf(q).reshape(6, n_pts)
        g = (d[:3] - d[3:]).T / (2 * h)
        norm = np.linalg.norm(g, axis=1, keepdims=True)
        return g / np.where(norm > 1e-12, norm, 1.0)

    def prepare_distance_field(self) -> tuple[float | None, str | None]:
        """Load or build an imported mesh's distance field now (``MeshSdf``): the seconds it
        took to build (None when it came from the disk cache or the object has none) and the
        cache folder (None for analytic objects)."""
        from app.model.objects.distance_field import cache_dir
        from app.model.objects.shapes import MeshSdf

        sdf = self._geometry.sdf
        if not isinstance(sdf, MeshSdf):
            return None, None
        sdf.field()
        return sdf.built_s, str(cache_dir())

    def mesh_pack(self) -> Any:
        """An imported mesh's distance field as compiled-code arrays
        (``DistanceField.pack``), or None for the analytic built-in objects."""
        from app.model.objects.shapes import MeshSdf

        sdf = self._geometry.sdf
        return sdf.field().pack() if isinstance(sdf, MeshSdf) else None

    def collision_objects(self) -> list[Any]:
        """FCL collision objects of the pieces, posed in the object frame (built once, cached).

        The caller must not move them: they are shared by every user of this object.
        """
        if self._collision is None:
            self._collision = [
                fcl.CollisionObject(
                    pc.geometry, fcl.Transform(pc.R_object_piece, pc.t_object_piece)
                )
                for pc in self._geometry.pieces
            ]
        return self._collision

    @property
    def pieces(self) -> tuple[Piece, ...]:
        """The collision pieces (FCL geometry, pose, hull vertices), ``collision_objects()``
        order."""
        return self._geometry.pieces

    @property
    def sdf_parts(self) -> tuple[SdfPart, ...] | None:
        """The signed distance as numbers (``SdfPart``; the compiled contact kernels), or None
        for an imported mesh."""
        return self._geometry.sdf_parts

    @property
    def sdf_bounds(self) -> np.ndarray | None:
        """(parts, 4) bounding spheres of a union's parts (``Geometry.sdf_bounds``), or None."""
        return self._geometry.sdf_bounds

    @property
    def piece_labels(self) -> tuple[str, ...]:
        """Label of each collision piece, in ``collision_objects()`` order."""
        return tuple(pc.label for pc in self._geometry.pieces)


# ------------------------------------------------------------------------ registry

_REGISTRY: dict[str, GraspObject] = {}


def register_object(obj: GraspObject) -> None:
    """Make ``load_object(obj.key)`` return this object in this process."""
    _REGISTRY[obj.key] = obj


def unregister_object(key: str) -> None:
    """Forget an imported object registered in this process (no error if absent)."""
    _REGISTRY.pop(key, None)


def _user_files() -> dict[str, Path]:
    d = user_dir()
    if d is None or not d.is_dir():
        return {}
    return {p.stem: p for p in sorted(d.glob("*.toml"))}


def available_keys() -> tuple[str, ...]:
    """Shipped keys (METHOD order), then registered imports, then saved user objects."""
    keys = list(OBJECT_KEYS)
    for k in [*_REGISTRY, *_user_files()]:
        if k not in keys:
            keys.append(k)
    return tuple(keys)


def object_from_file(path: Path, key: str | None = None) -> GraspObject:
    """Build an object from a data file (shipped or saved import)."""
    spec = read_spec(path, key)
    return GraspObject(spec, build(spec.shape, base_dir=path.parent))


@functools.cache
def _load_file_cached(path_str: str, key: str) -> GraspObject:
    return object_from_file(Path(path_str), key)


def load_object(key: str) -> GraspObject:
    """The object of a key: shipped, registered in this process, or saved in
    ``$HANDBENCH_USER_OBJECTS``. Cached per process.

    Raises UnknownObjectError listing the valid keys.
    """
    if key in _REGISTRY:
        return _REGISTRY[key]
    if key in OBJECT_KEYS:
        path = data_dir() / f"{key}.toml"
        return _load_file_cached(str(path), key)
    user = _user_files()
    if key in user:
        return _load_file_cached(str(user[key]), key)
    raise UnknownObjectError(
        f"unknown object {key!r}; valid objects: {', '.join(available_keys())}"
    )
