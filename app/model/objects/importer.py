"""Import a user mesh (STL/OBJ/PLY) as a grasp object with the set-up of a shipped object.

The CLI (``handbench objects import PATH --like NAME [--units mm|m] [--key KEY]``) calls
:func:`import_object`. Every failure a user can cause raises ``MeshImportError`` with the
reason and the fix; repairs that are safe (triangulating polygons, dropping degenerate
faces, filling small holes, re-orienting faces) are done with a ``warnings.warn``.
"""

from __future__ import annotations

import logging
import math
import re
import stat
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import trimesh

from app.errors import MeshImportError
from app.model.objects.model import GraspObject, load_object, register_object
from app.model.objects.shapes import from_mesh
from app.model.objects.spec import OBJECT_KEYS, ObjectSpec, spec_to_toml, user_dir

#: File extensions the importer reads.
MESH_EXTENSIONS = (".stl", ".obj", ".ply")
#: Length units of an imported file, and their factor to millimetres.
UNITS_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0}
#: Plausible range of an object's largest extent, mm (a hand grasps things in between).
SIZE_RANGE_MM = (5.0, 600.0)

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

    Loops are traced edge by edge, so two holes touching at one vertex are two loops.
    Returns the number of holes filled.
    """
    faces = np.asarray(mesh.faces)
    directed = np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    boundary = directed[count[inv.ravel()] == 1].tolist()
    if not boundary:
        return 0
    out: dict[int, list[int]] = {}
    for i, (a, _b) in enumerate(boundary):
        out.setdefault(a, []).append(i)
    used = [False] * len(boundary)
    verts = [np.asarray(mesh.vertices)]
    new_faces = [faces]
    n_v = len(mesh.vertices)
    filled = 0
    for e0 in range(len(boundary)):
        if used[e0]:
            continue
        used[e0] = True
        start, cur = boundary[e0]
        loop = [start]
        closed = True
        while cur != start:
            nxt = next((e for e in out.get(cur, []) if not used[e]), None)
            if nxt is None:
                closed = False
                break
            used[nxt] = True
            loop.append(cur)
            cur = boundary[nxt][1]
        if not closed or len(loop) < 3 or len(loop) > max_edges:
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


#: Files larger than this are refused before reading (a 200 MB STL would need several GB;
#: decimate such a scan first, e.g. to 100k faces in MeshLab or Blender).
MAX_FILE_BYTES = 100_000_000
#: Meshes with more faces than this are refused after reading.
MAX_FACES = 1_000_000
#: Vertices closer than this fraction of the largest extent are merged (file units, so the
#: tolerance is the same for a file in metres and one in millimetres).
MERGE_REL_TOL = 1e-7
#: A face on a non-manifold edge whose smallest height is below this fraction of its
#: longest edge is a scanner sliver and is dropped.
SLIVER_REL_HEIGHT = 0.1
#: Objects thinner than this (mm) cannot be told apart from a contact (the default
#: ``ContactSettings.contact_tol_mm``): refused.
MIN_THICKNESS_MM = 1.0


def _stat_regular(p: Path) -> int:
    """Size in bytes of a regular file; MeshImportError for anything else."""
    try:
        st = p.stat()
    except FileNotFoundError:
        raise MeshImportError(f"{p}: file not found") from None
    except OSError as e:
        raise MeshImportError(f"{p}: cannot open the file ({e.strerror or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise MeshImportError(f"{p}: is a folder, not a mesh file")
    if not stat.S_ISREG(st.st_mode):
        raise MeshImportError(
            f"{p}: is not a regular file (a device, a pipe or a socket); give a mesh file"
        )
    if st.st_size == 0:
        raise MeshImportError(f"{p}: the file is empty")
    if st.st_size > MAX_FILE_BYTES:
        raise MeshImportError(
            f"{p}: the file is {st.st_size / 1e6:.0f} MB, more than the "
            f"{MAX_FILE_BYTES / 1e6:.0f} MB limit; decimate the mesh first (e.g. to 100,000 "
            "faces in MeshLab or Blender)"
        )
    return st.st_size


def _check_stl_size(p: Path, size: int) -> None:
    """A binary STL must be 84 + 50 n bytes for the n triangles its header announces."""
    with open(p, "rb") as fh:
        head = fh.read(84)
    if head[:5].lower() == b"solid" and b"facet" in open(p, "rb").read(4096):
        return  # ASCII STL
    if len(head) < 84:
        raise MeshImportError(f"{p}: too short for a binary STL ({size} bytes, header is 84)")
    n = int(np.frombuffer(head[80:84], dtype="<u4")[0])
    if n == 0:
        raise MeshImportError(f"{p}: the binary STL header announces 0 triangles")
    if 84 + 50 * n != size:
        raise MeshImportError(
            f"{p}: the binary STL header announces {n} triangles ({84 + 50 * n} bytes) but "
            f"the file has {size} bytes (truncated or not an STL file)"
        )


def _load_arrays(p: Path, ext: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) float and faces (m, 3) int as the file holds them; MeshImportError
    (with the loader's reason) for anything trimesh cannot read."""
    log = logging.getLogger("trimesh")
    level = log.level
    log.setLevel(logging.CRITICAL)  # trimesh logs parse problems; we report them ourselves
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            loaded = trimesh.load(str(p), file_type=ext[1:], force="mesh", process=False)
        v = np.asarray(loaded.vertices) if hasattr(loaded, "vertices") else np.zeros((0, 3))
        f = np.asarray(loaded.faces) if hasattr(loaded, "faces") else np.zeros((0, 3))
    except MemoryError:
        raise MeshImportError(f"{p}: the mesh does not fit in memory") from None
    except Exception as e:  # trimesh raises many kinds on malformed input
        reason = " ".join(str(e).split())[:200] or type(e).__name__
        raise MeshImportError(f"{p}: cannot read the mesh ({reason})") from None
    finally:
        log.setLevel(level)
    if f.size == 0 or v.size == 0:
        raise MeshImportError(f"{p}: the file holds no triangles (empty mesh)")
    if v.ndim != 2 or v.shape[1] != 3:
        k = v.shape[1] if v.ndim == 2 else v.ndim
        raise MeshImportError(f"{p}: vertices have {k} coordinates, not 3 (x y z)")
    if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise MeshImportError(f"{p}: faces are not triangles of vertex indices")
    if f.min() < 0 or f.max() >= len(v):
        bad = int(f.max()) if f.max() >= len(v) else int(f.min())
        raise MeshImportError(
            f"{p}: a face refers to vertex {bad}, but the file has vertices 0-{len(v) - 1} "
            "(a wrong vertex count in the header, or a corrupt file)"
        )
    if len(f) > MAX_FACES:
        raise MeshImportError(
            f"{p}: {len(f)} faces, more than {MAX_FACES}; decimate the mesh first"
        )
    return np.asarray(v, dtype=float), np.asarray(f, dtype=np.int64)


def guess_units(extent: float) -> str | None:
    """'mm' or 'm' from the largest extent in file units, or None when neither fits."""
    lo, hi = SIZE_RANGE_MM
    for u in ("mm", "m"):
        if lo <= extent * UNITS_TO_MM[u] <= hi:
            return u
    return None


def _drop_bad_faces(faces: np.ndarray, v: np.ndarray, scale: float) -> tuple[np.ndarray, int]:
    """Degenerate faces (repeated corner or zero height) and duplicates; a face present in
    both windings is a zero-thickness fin: both go. Returns kept faces and how many went."""
    tri = v[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    longest = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
    height = area2 / np.maximum(longest, 1e-300)
    ok = (
        (faces[:, 0] != faces[:, 1])
        & (faces[:, 1] != faces[:, 2])
        & (faces[:, 0] != faces[:, 2])
        & (height > 1e-9 * scale)
    )
    f = faces[ok]
    key = np.sort(f, axis=1)
    _, first, inv, count = np.unique(
        key, axis=0, return_index=True, return_inverse=True, return_counts=True
    )
    inv = inv.ravel()
    keep = np.zeros(len(f), dtype=bool)
    keep[first] = True
    # a face and its reverse: parity of the permutation that sorts it
    parity = ((f[:, 0] > f[:, 1]).astype(int) + (f[:, 0] > f[:, 2]) + (f[:, 1] > f[:, 2])) % 2
    dup = count[inv] > 1
    if dup.any():
        both = np.zeros(len(count), dtype=bool)
        for g in np.unique(inv[dup]):
            both[g] = len(set(parity[inv == g].tolist())) > 1
        keep &= ~both[inv]
    return f[keep], len(faces) - int(keep.sum())


def _nonmanifold_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(edges shared by more than two faces, face index of each directed edge occurrence)."""
    e = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    fid = np.tile(np.arange(len(faces)), 3)
    _, inv, count = np.unique(e, axis=0, return_inverse=True, return_counts=True)
    over = count[inv.ravel()] > 2
    return e[over], fid[over]


def _drop_slivers(faces: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, int, int]:
    """Drop thin faces on non-manifold edges. Returns (faces, dropped, non-manifold edges
    left)."""
    dropped = 0
    for _ in range(4):
        edges, fid = _nonmanifold_edges(faces)
        if len(edges) == 0:
            return faces, dropped, 0
        cand = np.unique(fid)
        tri = v[faces[cand]]
        area2 = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        longest = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
        thin = area2 / np.maximum(longest, 1e-300) ** 2 < SLIVER_REL_HEIGHT
        if not thin.any():
            break
        keep = np.ones(len(faces), dtype=bool)
        keep[cand[thin]] = False
        faces = faces[keep]
        dropped += int(thin.sum())
    edges, _ = _nonmanifold_edges(faces)
    return faces, dropped, len(np.unique(edges, axis=0))


def _warn(msg: str) -> None:
    warnings.warn(msg, UserWarning, stacklevel=3)


def read_mesh(
    path: str | Path,
    units: str | None = "mm",
    allow_open: bool = False,
) -> trimesh.Trimesh:
    """Read, check and repair a mesh file; returns a watertight mesh in mm (file frame).

    Refused (``MeshImportError`` naming the file and the reason): not a regular file, empty,
    too large, unreadable or inconsistent (face index out of range, 2-D vertices, STL size
    mismatch), non-finite coordinates, a largest extent outside ``SIZE_RANGE_MM`` after
    units, no volume, thinner than ``MIN_THICKNESS_MM``, an open surface (unless
    ``allow_open``), non-manifold edges that are not slivers.
    Repaired, each with a one-line warning: vertices merged (in file units), degenerate,
    duplicate and sliver faces dropped, polygons triangulated, winding made consistent,
    holes of up to ``MAX_HOLE_EDGES`` edges closed; with ``allow_open`` every hole is closed
    with a flat cap. ``units=None`` guesses mm or m from the size, with a warning.
    """
    p = Path(path)
    if units is not None and units not in UNITS_TO_MM:
        raise MeshImportError(f"unknown units {units!r}; valid: {', '.join(UNITS_TO_MM)}")
    ext = p.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise MeshImportError(
            f"{p}: unknown mesh extension {ext or '(none)'!r}; valid: {', '.join(MESH_EXTENSIONS)}"
        )
    size = _stat_regular(p)
    if ext == ".stl":
        _check_stl_size(p, size)
    v, faces = _load_arrays(p, ext)
    if not np.all(np.isfinite(v)):
        bad = int((~np.isfinite(v)).any(axis=1).sum())
        raise MeshImportError(f"{p}: {bad} vertices have NaN or infinite coordinates")
    n_poly = _count_polygon_faces(p)
    if n_poly:
        _warn(f"{p}: {n_poly} polygon faces with more than 3 corners were triangulated")
    used = v[np.unique(faces)]
    extent = float((used.max(axis=0) - used.min(axis=0)).max())
    lo, hi = SIZE_RANGE_MM
    if units is None:
        guess = guess_units(extent)
        if guess is None:
            raise MeshImportError(
                f"{p}: largest extent {extent:.4g} (file units) fits no unit: a hand grasps "
                f"objects of {lo:g}-{hi:g} mm; pass --units mm|cm|m if the file is right"
            )
        units = guess
        if guess != "mm":
            _warn(
                f"{p}: no --units given; the largest extent is {extent:.4g}, so the file is "
                f"taken to be in {guess} ({extent * UNITS_TO_MM[guess]:.0f} mm); "
                "pass --units to override"
            )
    factor = UNITS_TO_MM[units]
    if not (lo <= extent * factor <= hi):
        fits = guess_units(extent)
        hint = f"; if the file is in {fits}, use --units {fits}" if fits else ""
        raise MeshImportError(
            f"{p}: largest extent {extent * factor:.4g} mm after unit conversion ({units}) is "
            f"outside [{lo:g}, {hi:g}] mm{hint}"
        )
    # repairs, in the file's own units
    mesh = trimesh.Trimesh(v, faces, process=False)
    digits = int(max(0, -math.floor(math.log10(MERGE_REL_TOL * extent))))
    mesh.merge_vertices(digits_vertex=digits)
    v = np.asarray(mesh.vertices, dtype=float)
    faces, n_bad = _drop_bad_faces(np.asarray(mesh.faces, dtype=np.int64), v, extent)
    faces, n_sliver, n_nonmanifold = _drop_slivers(faces, v)
    if n_bad or n_sliver:
        what = [f"{n_bad} degenerate or duplicate"] if n_bad else []
        what += [f"{n_sliver} non-manifold sliver"] if n_sliver else []
        _warn(f"{p}: removed {' and '.join(what)} faces")
    if len(faces) < 4:
        raise MeshImportError(
            f"{p}: only {len(faces)} usable triangles; a solid needs at least 4 (no volume)"
        )
    if n_nonmanifold:
        raise MeshImportError(
            f"{p}: {n_nonmanifold} non-manifold edges (three or more faces meet) that are not "
            "thin slivers; repair the mesh in a mesh editor (e.g. MeshLab: Remove Non-Manifold "
            "Edges)"
        )
    mesh = trimesh.Trimesh(v * factor, faces, process=False)
    mesh.remove_unreferenced_vertices()
    _fix_winding(mesh)
    if not mesh.is_watertight:
        n_filled = _fill_small_holes(mesh)
        n_capped = 0
        if not mesh.is_watertight and allow_open:
            n_capped = _fill_small_holes(mesh, max_edges=10**9)
        _fix_winding(mesh)
        if not mesh.is_watertight and allow_open:
            mesh = mesh.convex_hull
            _warn(
                f"{p}: the open surface could not be closed with flat caps (its holes touch "
                "each other); its convex hull is used instead (--allow-open): volume, inside "
                "tests, signed distance and collision see the hull"
            )
        elif mesh.is_watertight:
            if n_filled:
                _warn(f"{p}: {n_filled} small holes (up to {MAX_HOLE_EDGES} edges) were closed")
            if n_capped:
                _warn(
                    f"{p}: the surface was open; {n_capped} larger holes were closed with flat "
                    "caps (--allow-open): volume, inside tests and the signed distance use the "
                    "capped surface"
                )
        else:
            raise MeshImportError(
                f"{p}: the surface is not closed: it has holes larger than {MAX_HOLE_EDGES} "
                "edges or edges used by one face only; for a scan open at the bottom, pass "
                "--allow-open (holes are closed with flat caps), or close it in a mesh editor"
            )
    if mesh.volume < 0:
        mesh.invert()
    vol = float(mesh.volume)
    bbox_vol = float(np.prod(np.maximum(mesh.extents, 1e-12)))
    if not (vol > 1e-6 * bbox_vol and vol > 1e-3):
        raise MeshImportError(
            f"{p}: the mesh encloses no volume ({vol:.3g} mm³): a flat or self-cancelling "
            "surface, not a solid"
        )
    thickness = min(float(mesh.bounding_box_oriented.extents.min()), 2 * vol / mesh.area)
    if thickness < MIN_THICKNESS_MM:
        raise MeshImportError(
            f"{p}: the solid is {thickness:.3g} mm thick, below the {MIN_THICKNESS_MM:g} mm "
            "contact tolerance: a hand cannot tell touching it from pinching through it"
        )
    return mesh


def _perp(v: np.ndarray, n: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """v made perpendicular to unit n (Gram-Schmidt); fallback if v is parallel to n."""
    for c in (v, fallback, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        w = c - (c @ n) * n
        if np.linalg.norm(w) > 1e-3:
            return w / np.linalg.norm(w)
    raise AssertionError("unreachable")


#: Radius (mm) of the surface patch around the target whose face normals are averaged
#: (area-weighted) into the target normal: about a finger pad.
NORMAL_PATCH_MM = 8.0
#: The ``--up`` choices: the file axis that points up.
UP_AXES = ("+x", "-x", "+y", "-y", "+z", "-z")


def patch_normal(mesh: trimesh.Trimesh, point: np.ndarray, radius: float = NORMAL_PATCH_MM,
                 seed_face: int | None = None) -> np.ndarray:  # fmt: skip
    """Unit outward normal at a surface point: area-weighted mean of the normals of the
    faces within ``radius`` of it that face the same side as the closest face (so a thin
    wall's far side does not cancel it)."""
    if seed_face is None:
        _, _, tri = trimesh.proximity.closest_point(mesh, point[None])
        seed_face = int(tri[0])
    n0 = np.asarray(mesh.face_normals[seed_face], dtype=float)
    c = np.asarray(mesh.triangles_center)
    near = np.linalg.norm(c - point, axis=1) <= radius
    fn = np.asarray(mesh.face_normals)
    near &= fn @ n0 > 0
    near[seed_face] = True
    n = (fn[near] * np.asarray(mesh.area_faces)[near, None]).sum(axis=0)
    return n / np.linalg.norm(n)


def orientation_matrix(up: str | None = None, rotate_deg: tuple[float, float, float] | None = None
                       ) -> np.ndarray:  # fmt: skip
    """3×3 rotation taking file axes to the object frame: first ``rotate_deg`` (x, y, z
    Euler angles in degrees, applied in that order about the fixed axes), then the file axis
    ``up`` turned to +z by the shortest rotation. Raises MeshImportError for a bad axis."""
    R = np.eye(3)
    if rotate_deg is not None:
        if len(rotate_deg) != 3 or not all(math.isfinite(a) for a in rotate_deg):
            raise MeshImportError(f"--rotate takes three finite angles 'rx,ry,rz' in degrees, "
                                  f"got {rotate_deg}")  # fmt: skip
        R = trimesh.transformations.euler_matrix(*np.deg2rad(rotate_deg), axes="sxyz")[:3, :3]
    if up is not None:
        if up.lstrip("+") in ("x", "y", "z"):
            up = "+" + up.lstrip("+")
        if up not in UP_AXES:
            raise MeshImportError(f"--up {up!r} unknown; valid: {', '.join(UP_AXES)}")
        a = np.zeros(3)
        a["xyz".index(up[1])] = 1.0 if up[0] == "+" else -1.0
        a = R @ a
        z = np.array([0.0, 0.0, 1.0])
        if a @ z < -0.999999:
            U = np.diag([1.0, -1.0, -1.0])  # half turn about x
        else:
            k = np.cross(a, z)  # shortest rotation a -> z (Rodrigues): keeps the axis a x z
            K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            U = np.eye(3) + K + K @ K / (1.0 + a @ z)
        R = U @ R
    return R


def spec_like(mesh: trimesh.Trimesh, ref: GraspObject, key: str, source: str) -> ObjectSpec:
    """Grasp set-up of ``ref`` transferred to ``mesh``.

    Target: the reference target's position relative to the reference bounding box, mapped
    into the mesh's bounding box, then snapped to the closest mesh point; normal: the
    area-weighted mean face normal over a ``NORMAL_PATCH_MM`` patch around it (one scan
    triangle's normal can be off by 10° or more). Grip axis and palm hint: the reference
    ones made perpendicular to the new normal (palm hint = grip axis x normal for CG, with
    the reference's sign).
    """
    rs = ref.spec
    rb = ref.mesh.bounds
    u = (rs.target_object - rb[0]) / np.maximum(rb[1] - rb[0], 1e-9)
    b = mesh.bounds
    guess = b[0] + u * (b[1] - b[0])
    closest, _, tri = trimesh.proximity.closest_point(mesh, guess[None])
    target = closest[0]
    normal = patch_normal(mesh, target, seed_face=int(tri[0]))
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


def _axis_order_warning(mesh: trimesh.Trimesh, ref: GraspObject, p: Path) -> None:
    """Warn when the scan's extents are ordered unlike the reference's (lying on its side)."""
    e, r = np.asarray(mesh.extents), np.asarray(ref.mesh.extents)
    if np.argmax(e) == np.argmax(r) or abs(e.max() - np.sort(e)[1]) < 0.1 * e.max():
        tall_ok = True
    else:
        tall_ok = False
    thin_ok = np.argmin(e) == np.argmin(r) or abs(np.sort(e)[1] - e.min()) < 0.1 * e.min()
    if tall_ok and thin_ok:
        return
    fmt = ", ".join(f"{a} {x:.0f}" for a, x in zip("xyz", e, strict=True))
    rfmt = ", ".join(f"{a} {x:.0f}" for a, x in zip("xyz", r, strict=True))
    _warn(
        f"{p}: its extents ({fmt} mm) are ordered unlike {ref.key}'s ({rfmt} mm); if it "
        "lies on its side, pass --up AXIS (the file axis that points up) or --rotate rx,ry,rz"
    )


def user_objects_dir() -> Path:
    """Where imports are saved by default: ``$HANDBENCH_USER_OBJECTS``, else
    ``$XDG_DATA_HOME/handbench/objects`` (``~/.local/share/handbench/objects``)."""
    d = user_dir()
    assert d is not None
    return d


def import_object(
    path: str | Path,
    like: str,
    units: str | None = "mm",
    key: str | None = None,
    *,
    allow_open: bool = False,
    register: bool = True,
    save_to: str | Path | None = None,
    up: str | None = None,
    rotate_deg: tuple[float, float, float] | None = None,
) -> GraspObject:
    """Import a mesh file as a grasp object with the grasp set-up of the object ``like``.

    path: STL/OBJ/PLY file; units: "mm", "cm" or "m" (None: guessed from the size, with a
    warning); key: object key (default: the file name, lower-cased); up / rotate_deg: turn
    the file into the object frame (see :func:`orientation_matrix`); the mesh is then moved
    so that the centre of its bounding box's bottom face is the origin (the shipped objects'
    frame: base centre, +z up). register: make ``load_object(key)`` find it in this
    process; save_to: folder where ``<key>.ply`` and ``<key>.toml`` are written (the CLI
    saves to :func:`user_objects_dir`, which ``load_object`` searches in every process).
    Collision uses one fcl.BVHModel; the signed distance is a cached distance field, exact
    near the surface (:mod:`app.model.objects.distance_field`).

    Raises MeshImportError (bad file, see :func:`read_mesh`; bad key or axis) and
    UnknownObjectError (``like`` is not a known object).
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
    R = orientation_matrix(up, rotate_deg)
    mesh = read_mesh(p, units=units, allow_open=allow_open)
    T = np.eye(4)
    T[:3, :3] = R
    mesh.apply_transform(T)
    lo, hi = mesh.bounds
    mesh.apply_translation(-np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]]))
    if up is None and rotate_deg is None:
        _axis_order_warning(mesh, ref, p)
    spec = spec_like(mesh, ref, k, f"imported from {p}")
    spec = replace(
        spec,
        shape={
            **spec.shape,
            "imported_from": str(p.resolve()),
            "units": units or "guessed",
            "like": ref.spec.key,
        },
    )
    obj = GraspObject(spec, from_mesh(mesh))
    if save_to is not None:
        folder = Path(save_to)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            mesh.export(str(folder / f"{k}.ply"))
            text = spec_to_toml(
                replace(spec, source=str(folder / f"{k}.toml")),
                f"{k}: imported from {p} ({units or 'units guessed'}), grasp set-up like "
                f"{ref.spec.key}",
            )
            (folder / f"{k}.toml").write_text(text)
        except OSError as e:
            raise MeshImportError(
                f"cannot save {k} in {folder} ({e.strerror or e}); give a writable folder"
            ) from None
    if register:
        register_object(obj)
    return obj
