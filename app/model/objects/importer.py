"""Import a user mesh (STL/OBJ/PLY) as a grasp object with the set-up of a shipped object.

The CLI (``handbench objects import PATH --like NAME [--units mm|m] [--key KEY]``) calls
:func:`import_object`. Every failure a user can cause raises ``MeshImportError`` with the
reason and the fix; repairs that are safe (triangulating polygons, dropping degenerate
faces, filling small holes, re-orienting faces) are done with a ``warnings.warn``.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import trimesh

from app.errors import MeshImportError
from app.model.objects.model import GraspObject, load_object, register_object
from app.model.objects.shapes import from_mesh
from app.model.objects.spec import OBJECT_KEYS, ObjectSpec, spec_to_toml

#: File extensions the importer reads.
MESH_EXTENSIONS = (".stl", ".obj", ".ply")
#: Length units of an imported file, and their factor to millimetres.
UNITS_TO_MM = {"mm": 1.0, "m": 1000.0}
#: Plausible range of an object's largest extent, mm (a hand grasps things in between).
SIZE_RANGE_MM = (5.0, 1000.0)

_KEY_RE = re.compile(r"^[a-z][a-z0-9_]*$")


def _key_from_stem(stem: str) -> str:
    k = re.sub(r"[^a-z0-9_]+", "_", stem.lower()).strip("_")
    if not k or not k[0].isalpha():
        k = "obj_" + k
    return k


def _count_polygon_faces(path: Path) -> int:
    """Faces with more than three corners in a text OBJ / ASCII PLY file (0 if unknown)."""
    try:
        text = path.read_text(errors="strict")
    except (UnicodeDecodeError, OSError):
        return 0
    if path.suffix.lower() == ".obj":
        return sum(1 for ln in text.splitlines() if ln.startswith("f ") and len(ln.split()) > 4)
    if path.suffix.lower() == ".ply" and "format ascii" in text[:200]:
        head, _, body = text.partition("end_header")
        m_v = re.search(r"element vertex (\d+)", head)
        m_f = re.search(r"element face (\d+)", head)
        if not (m_v and m_f):
            return 0
        rows = body.strip().splitlines()
        nv, nf = int(m_v.group(1)), int(m_f.group(1))
        faces = rows[nv : nv + nf]
        return sum(1 for r in faces if r.split() and r.split()[0] not in ("3",))
    return 0


#: Holes (boundary loops) with at most this many edges are filled on import.
MAX_HOLE_EDGES = 8


def _fix_winding(mesh: trimesh.Trimesh) -> None:
    """Make neighbouring faces wind consistently (breadth-first over face adjacency)."""
    if mesh.is_winding_consistent or len(mesh.face_adjacency) == 0:
        return
    faces = np.array(mesh.faces)
    adj = np.asarray(mesh.face_adjacency)
    edge = np.asarray(mesh.face_adjacency_edges)

    def forward(f: np.ndarray) -> np.ndarray:
        """True where the shared edge runs u -> v inside face f (cyclic order)."""
        tri = faces[f]
        nxt = np.roll(tri, -1, axis=1)
        return ((tri == edge[:, :1]) & (nxt == edge[:, 1:])).any(axis=1)

    same = forward(adj[:, 0]) == forward(adj[:, 1])  # same direction: one of them is flipped
    nbrs: list[list[tuple[int, bool]]] = [[] for _ in range(len(faces))]
    for (a, b), s in zip(adj.tolist(), same.tolist(), strict=True):
        nbrs[a].append((b, s))
        nbrs[b].append((a, s))
    flip = np.zeros(len(faces), dtype=bool)
    seen = np.zeros(len(faces), dtype=bool)
    for start in range(len(faces)):
        if seen[start]:
            continue
        seen[start] = True
        queue = [start]
        while queue:
            f = queue.pop()
            for g, s in nbrs[f]:
                if not seen[g]:
                    seen[g] = True
                    flip[g] = flip[f] ^ s
                    queue.append(g)
    if flip.any():
        faces[flip] = faces[flip][:, ::-1]
        mesh.faces = faces


def _fill_small_holes(mesh: trimesh.Trimesh, max_edges: int = MAX_HOLE_EDGES) -> int:
    """Close boundary loops of at most ``max_edges`` edges with a fan around their centroid.

    Returns the number of holes filled. Loops through non-manifold vertices are left open.
    """
    faces = np.asarray(mesh.faces)
    directed = np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = directed[count[inv.ravel()] == 1]
    if len(boundary) == 0:
        return 0
    nxt: dict[int, int] = {}
    for a, b in boundary.tolist():
        if a in nxt:
            return 0  # non-manifold boundary: leave it to the user
        nxt[a] = b
    verts = [np.asarray(mesh.vertices)]
    new_faces = [faces]
    n_v = len(mesh.vertices)
    filled = 0
    done: set[int] = set()
    for a0 in list(nxt):
        if a0 in done:
            continue
        loop = [a0]
        while nxt.get(loop[-1], a0) != a0 and len(loop) <= len(nxt):
            loop.append(nxt[loop[-1]])
        done.update(loop)
        if nxt.get(loop[-1]) != a0 or len(loop) > max_edges:
            continue
        c = np.asarray(mesh.vertices)[loop].mean(axis=0)
        verts.append(c[None])
        lp = np.array(loop)
        # boundary edge a -> b belongs to an existing face; the new face holds b -> a
        new_faces.append(np.column_stack([np.roll(lp, -1), lp, np.full(len(lp), n_v)]))
        n_v += 1
        filled += 1
    if filled:
        mesh.vertices = np.vstack(verts)
        mesh.faces = np.vstack(new_faces)
    return filled


def read_mesh(path: str | Path, units: str = "mm", allow_open: bool = False) -> trimesh.Trimesh:
    """Read, check and repair a mesh file; returns a watertight mesh in mm.

    Raises MeshImportError for a missing or unreadable file, an unknown extension, an empty
    mesh, NaN/inf vertices, an absurd size, or an open surface (unless ``allow_open``).
    """
    p = Path(path)
    if units not in UNITS_TO_MM:
        raise MeshImportError(f"unknown units {units!r}; valid: {', '.join(UNITS_TO_MM)}")
    ext = p.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise MeshImportError(
            f"{p}: unknown mesh extension {ext or '(none)'!r}; valid: {', '.join(MESH_EXTENSIONS)}"
        )
    if not p.is_file():
        raise MeshImportError(f"{p}: file not found")
    if p.stat().st_size == 0:
        raise MeshImportError(f"{p}: the file is empty")
    try:
        loaded = trimesh.load(str(p), file_type=ext[1:], force="mesh", process=False)
    except Exception as e:  # trimesh raises many kinds on malformed input
        raise MeshImportError(f"{p}: cannot read the mesh ({type(e).__name__}: {e})") from e
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshImportError(f"{p}: the file holds no triangles (empty mesh)")
    mesh = loaded
    v = np.asarray(mesh.vertices, dtype=float)
    if not np.all(np.isfinite(v)):
        bad = int((~np.isfinite(v)).any(axis=1).sum())
        raise MeshImportError(f"{p}: {bad} vertices have NaN or infinite coordinates")
    n_poly = _count_polygon_faces(p)
    if n_poly:
        warnings.warn(
            f"{p}: {n_poly} polygon faces with more than 3 corners were triangulated",
            stacklevel=2,
        )
    mesh = trimesh.Trimesh(v * UNITS_TO_MM[units], np.asarray(mesh.faces), process=False)
    mesh.merge_vertices()
    good = mesh.nondegenerate_faces(height=1e-9)
    unique = mesh.unique_faces()
    keep = good & unique
    if not keep.all():
        warnings.warn(
            f"{p}: removed {int((~keep).sum())} degenerate or duplicate faces", stacklevel=2
        )
        mesh.update_faces(keep)
        mesh.remove_unreferenced_vertices()
    if len(mesh.faces) == 0:
        raise MeshImportError(f"{p}: no non-degenerate triangles left (empty mesh)")
    extent = float(mesh.extents.max())
    lo, hi = SIZE_RANGE_MM
    if not (lo <= extent <= hi):
        other = "m" if units == "mm" else "mm"
        raise MeshImportError(
            f"{p}: largest extent {extent:.4g} mm after unit conversion ({units}) is outside "
            f"[{lo:g}, {hi:g}] mm; if the file is in {'metres' if other == 'm' else 'millimetres'}"
            f", use --units {other}"
        )
    _fix_winding(mesh)
    if not mesh.is_watertight:
        n_filled = _fill_small_holes(mesh)
        _fix_winding(mesh)
        if mesh.is_watertight:
            warnings.warn(
                f"{p}: the surface had {n_filled} small holes; they were filled", stacklevel=2
            )
        elif allow_open:
            warnings.warn(
                f"{p}: the surface is not closed; inside/outside (SDF sign) is unreliable",
                stacklevel=2,
            )
        else:
            raise MeshImportError(
                f"{p}: the surface is not closed (not watertight) and has holes larger than "
                f"{MAX_HOLE_EDGES} edges or non-manifold edges; close it in a mesh editor, "
                "or pass allow_open=True"
            )
    if mesh.is_watertight and mesh.volume < 0:
        mesh.invert()
    return mesh


def _perp(v: np.ndarray, n: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """v made perpendicular to unit n (Gram-Schmidt); fallback if v is parallel to n."""
    for c in (v, fallback, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        w = c - (c @ n) * n
        if np.linalg.norm(w) > 1e-3:
            return w / np.linalg.norm(w)
    raise AssertionError("unreachable")


def spec_like(mesh: trimesh.Trimesh, ref: GraspObject, key: str, source: str) -> ObjectSpec:
    """Grasp set-up of ``ref`` transferred to ``mesh``.

    Target: the reference target's position relative to the reference bounding box, mapped
    into the mesh's bounding box, then snapped to the closest mesh point; normal: the normal
    of the mesh face there. Grip axis and palm hint: the reference ones made perpendicular to
    the new normal (palm hint = grip axis x normal for CG, with the reference's sign).
    """
    rs = ref.spec
    rb = ref.mesh.bounds
    u = (rs.target_object - rb[0]) / np.maximum(rb[1] - rb[0], 1e-9)
    b = mesh.bounds
    guess = b[0] + u * (b[1] - b[0])
    closest, _, tri = trimesh.proximity.closest_point(mesh, guess[None])
    target = closest[0]
    normal = np.array(mesh.face_normals[int(tri[0])], dtype=float)
    normal /= np.linalg.norm(normal)
    grip = None
    if rs.grip_axis_object is not None:
        grip = _perp(rs.grip_axis_object, normal, rs.palm_y_hint_object)
        hint = np.cross(grip, normal)
        if hint @ rs.palm_y_hint_object < 0:
            hint = -hint
    else:
        hint = _perp(rs.palm_y_hint_object, normal, np.cross(normal, rs.normal_object))
    return ObjectSpec(
        key=key,
        name=f"{key} (imported, like {rs.name})",
        grasp_type=rs.grasp_type,
        target_object=target,
        normal_object=normal,
        grip_axis_object=grip,
        palm_y_hint_object=hint,
        setup=rs.setup,
        shape={"kind": "mesh", "file": f"{key}.ply", "like": rs.key},
        source=source,
    )


def import_object(
    path: str | Path,
    like: str,
    units: str = "mm",
    key: str | None = None,
    *,
    allow_open: bool = False,
    register: bool = True,
    save_to: str | Path | None = None,
) -> GraspObject:
    """Import a mesh file as a grasp object with the grasp set-up of the object ``like``.

    path: STL/OBJ/PLY file; units: "mm" or "m" (converted to mm); key: object key (default:
    the file name, lower-cased); register: make ``load_object(key)`` find it in this
    process; save_to: folder where ``<key>.ply`` and ``<key>.toml`` are written (point
    ``HANDBENCH_USER_OBJECTS`` at it to find them in later processes).
    Collision uses one fcl.BVHModel (about 45 µs per capsule query instead of about 5 µs
    for the shipped objects' convex pieces); the SDF is exact but slow (closest point + rays).

    Raises MeshImportError (bad file, see :func:`read_mesh`; bad key) and UnknownObjectError
    (``like`` is not a known object).
    """
    ref = load_object(like)
    p = Path(path)
    k = key if key is not None else _key_from_stem(p.stem)
    if not _KEY_RE.match(k):
        raise MeshImportError(
            f"invalid object key {k!r}: use lower-case letters, digits and '_', "
            "starting with a letter"
        )
    if k in OBJECT_KEYS:
        raise MeshImportError(
            f"key {k!r} is a shipped object; choose another key (e.g. --key my_{k})"
        )
    mesh = read_mesh(p, units=units, allow_open=allow_open)
    spec = spec_like(mesh, ref, k, f"imported from {p}")
    obj = GraspObject(spec, from_mesh(mesh))
    if save_to is not None:
        folder = Path(save_to)
        folder.mkdir(parents=True, exist_ok=True)
        mesh.export(str(folder / f"{k}.ply"))
        text = spec_to_toml(
            replace(spec, source=str(folder / f"{k}.toml")),
            f"{k}: imported from {p} ({units}), grasp set-up like {ref.spec.key}",
        )
        (folder / f"{k}.toml").write_text(text)
    if register:
        register_object(obj)
    return obj
