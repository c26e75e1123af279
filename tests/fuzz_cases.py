"""Seeded generators of bad (and good) mesh files and of bad command lines.

Used by ``tests/test_fuzz.py`` (fast tier) and ``benchmarks/fuzz_cli_meshes.py`` (counts
before/after). Imports only numpy and trimesh, never ``app``, so the benchmark can point it
at any checkout of the code.

A mesh case is ``MeshCase(name, family, path, like, extra)``: ``extra`` are flags to add to
``objects import`` (e.g. ``--units m``). A flag case is ``FlagCase(name, argv)``; every flag
case is an error a user can make, so the wanted outcome is exit 2 with one line.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh


@dataclass(frozen=True)
class MeshCase:
    """One generated mesh file and how to import it."""

    name: str
    """Unique case name (family and seed)."""
    family: str
    """Which generator made it."""
    path: Path
    """The file (or folder, FIFO, device link) to import."""
    like: str
    """Shipped object whose grasp set-up the import takes."""
    extra: tuple[str, ...] = field(default=())
    """More ``objects import`` flags, e.g. ``("--units", "m")``."""


# ----------------------------------------------------------------------------- helpers
def _ascii_ply(v: np.ndarray, f: np.ndarray, n_v_header: int | None = None) -> str:
    nv = len(v) if n_v_header is None else n_v_header
    head = (
        "ply\nformat ascii 1.0\n"
        f"element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rows = [f"{a:.6f} {b:.6f} {c:.6f}" for a, b, c in v]
    rows += ["3 " + " ".join(str(int(i)) for i in t) for t in f]
    return head + "\n".join(rows) + "\n"


def _binary_ply(v: np.ndarray, f: np.ndarray, label: str) -> bytes:
    """A little-endian body; ``label`` is the format the header claims."""
    head = (
        f"ply\nformat {label} 1.0\n"
        f"element vertex {len(v)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode()
    body = b"".join(struct.pack("<3f", *p) for p in v)
    body += b"".join(struct.pack("<B3i", 3, *t) for t in f)
    return head + body


def _obj(v: np.ndarray, f: np.ndarray) -> str:
    return "".join(f"v {a:.6f} {b:.6f} {c:.6f}\n" for a, b, c in v) + "".join(
        "f " + " ".join(str(int(i) + 1) for i in t) + "\n" for t in f
    )


def _export(mesh: trimesh.Trimesh, path: Path) -> Path:
    mesh.export(str(path))
    return path


def _box(rng: np.random.Generator, lo: float = 20.0, hi: float = 150.0) -> trimesh.Trimesh:
    return trimesh.creation.box(rng.uniform(lo, hi, 3))


# ----------------------------------------------------------------------------- families
# each: (folder, rng, i) -> (file path, like, extra flags)
Gen = Callable[[Path, np.random.Generator, int], tuple[Path, str, tuple[str, ...]]]


def fam_box(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    ext = (".stl", ".obj", ".ply")[i % 3]
    return _export(_box(rng), d / f"box{ext}"), "coffee_can", ()


def fam_sphere_metres(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    r = rng.uniform(0.02, 0.05)
    m = trimesh.creation.icosphere(2, radius=r)
    extra = ("--units", "m") if i % 2 else ()  # half rely on the size guess
    return _export(m, d / "ball.ply"), "plastic_pear", extra


def fam_flipped(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    f = np.array(b.faces)
    k = rng.choice(len(f), 3, replace=False)
    f[k] = f[k][:, ::-1]
    m = trimesh.Trimesh(b.vertices, f, process=False)
    return _export(m, d / "flipped.ply"), "coffee_can", ()


def fam_small_hole(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    m = trimesh.creation.icosphere(2, radius=rng.uniform(20, 40))
    drop = rng.integers(len(m.faces))
    m = trimesh.Trimesh(m.vertices, np.delete(m.faces, drop, axis=0), process=False)
    return _export(m, d / "holed.stl"), "plastic_pear", ()


def fam_open_bottom(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    """A can scan without its bottom cap (YCB chips can)."""
    c = trimesh.creation.cylinder(radius=rng.uniform(30, 50), height=rng.uniform(80, 200))
    keep = ~(c.face_normals[:, 2] < -0.9)
    c.apply_translation([0, 0, c.extents[2] / 2])
    m = trimesh.Trimesh(c.vertices, c.faces[keep], process=False)
    extra = ("--allow-open",) if i % 2 else ()
    return _export(m, d / "can_open.stl"), "chips_can", extra


def fam_scan(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    """A realistic synthetic scan: metres, noise, unmerged vertices (STL), a few non-manifold
    sliver faces hanging off the surface, open bottom on odd seeds."""
    m = trimesh.creation.capsule(height=0.06, radius=0.03, count=[24, 24])
    m.apply_translation([0, 0, 0.06])
    v = m.vertices + rng.normal(0, 2e-5, m.vertices.shape)
    faces = np.array(m.faces)
    if i % 2:
        faces = faces[m.triangles_center[:, 2] > 0.004]  # cut off the bottom: open
    # slivers: a third face on an existing edge (non-manifold), nearly flat
    slivers = []
    nv = len(v)
    extra_v = []
    for t in faces[rng.choice(len(faces), 3, replace=False)]:
        a, b = t[0], t[1]
        extra_v.append((v[a] + v[b]) / 2 + rng.normal(0, 1e-6, 3))
        slivers.append([a, b, nv + len(extra_v) - 1])
    v = np.vstack([v, np.array(extra_v)])
    faces = np.vstack([faces, np.array(slivers)])
    mm = trimesh.Trimesh(v, faces, process=False)
    extra = ("--allow-open",) if i % 2 else ()
    return _export(mm, d / "scan.stl"), "plastic_pear", extra


def fam_quads(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    s = rng.uniform(15, 80)
    v = "".join(f"v {x} {y} {z}\n" for x in (0, s) for y in (0, s) for z in (0, s))
    q = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    p = d / "quads.obj"
    p.write_text(v + q)
    return p, "coffee_can", ()


def fam_duplicates(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    f = np.vstack([b.faces, b.faces[: 1 + i % 4], [[0, 0, 1]]])
    m = trimesh.Trimesh(b.vertices, f, process=False)
    return _export(m, d / "dups.ply"), "coffee_can", ()


def fam_single_triangle(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    v = rng.uniform(0, 60, (3, 3))
    ext = (".stl", ".obj", ".ply")[i % 3]
    return _export(trimesh.Trimesh(v, [[0, 1, 2]], process=False), d / f"tri{ext}"), "washer", ()


def fam_flat_square(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    s = rng.uniform(20, 80)
    v = np.array([[0, 0, 0], [s, 0, 0], [s, s, 0], [0, s, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    if i % 2:  # both sides: a closed but zero-volume sheet
        f = np.vstack([f, f[:, ::-1]])
    return _export(trimesh.Trimesh(v, f, process=False), d / "square.obj"), "washer", ()


def fam_truncated_obj(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    text = _obj(b.vertices, b.faces)
    cut = int(rng.uniform(0.3, 0.95) * len(text))
    p = d / "trunc.obj"
    p.write_text(text[:cut])
    return p, "coffee_can", ()


def fam_truncated_binary(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = trimesh.creation.icosphere(1, radius=30)
    raw = b.export(file_type=("stl", "ply")[i % 2])
    assert isinstance(raw, bytes)
    cut = int(rng.uniform(0.2, 0.95) * len(raw))
    p = d / ("trunc.stl", "trunc.ply")[i % 2]
    p.write_bytes(raw[:cut])
    return p, "plastic_pear", ()


def fam_ply_index_out_of_range(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    f = np.array(b.faces)
    f[rng.integers(len(f)), rng.integers(3)] = len(b.vertices) + int(rng.integers(1, 50))
    p = d / "oor.ply"
    if i % 2:
        p.write_bytes(_binary_ply(b.vertices, f, "binary_little_endian"))
    else:
        p.write_text(_ascii_ply(b.vertices, f))
    return p, "coffee_can", ()


def fam_ply_header_count(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    """Header announces fewer vertices than the faces use (4 of 8)."""
    b = _box(rng)
    p = d / "hdr.ply"
    p.write_text(_ascii_ply(b.vertices, b.faces, n_v_header=4 + i % 3))
    return p, "coffee_can", ()


def fam_ply_wrong_endian(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    p = d / "endian.ply"
    p.write_bytes(_binary_ply(b.vertices, b.faces, "binary_big_endian"))
    return p, "coffee_can", ()


def fam_obj_2d(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    text = "".join(f"v {a:.4f} {c:.4f}\n" for a, c, _ in b.vertices)
    text += "".join("f " + " ".join(str(k + 1) for k in t) + "\n" for t in b.faces)
    p = d / "flat2d.obj"
    p.write_text(text)
    return p, "coffee_can", ()


def fam_nonfinite(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    v = np.array(b.vertices)
    v[rng.integers(len(v)), rng.integers(3)] = (np.nan, np.inf, -np.inf)[i % 3]
    p = d / ("nan.obj", "nan.ply")[i % 2]
    p.write_text(_obj(v, b.faces) if i % 2 == 0 else _ascii_ply(v, b.faces))
    return p, "coffee_can", ()


def fam_stl_count_mismatch(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    raw = bytearray(b.export(file_type="stl"))  # type: ignore[arg-type]
    wrong = (0, 13, 11, 1000, 2**31)[i % 5]
    raw[80:84] = struct.pack("<I", wrong)
    p = d / "count.stl"
    p.write_bytes(bytes(raw))
    return p, "coffee_can", ()


def fam_empty(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    ext = (".stl", ".obj", ".ply")[i % 3]
    p = d / f"empty{ext}"
    p.write_bytes(b"" if i < 3 else b"\n \n")
    return p, "washer", ()


def fam_garbage(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    ext = (".stl", ".obj", ".ply")[i % 3]
    p = d / f"garbage{ext}"
    head = (b"solid x\n", b"ply\n", b"", b"v 1 2 3\n")[i % 4]
    p.write_bytes(
        head + rng.integers(0, 256, int(rng.integers(10, 4000)), dtype=np.uint8).tobytes()
    )
    return p, "washer", ()


def fam_points_only(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    p = d / "points.obj"
    p.write_text("".join(f"v {a} {b} {c}\n" for a, b, c in rng.uniform(0, 50, (8, 3))))
    return p, "washer", ()


def fam_size(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    """Boxes far too small or too large for a hand, with and without --units."""
    s = (0.5, 2.0, 3000.0, 20000.0, 0.0005, 5.0)[i % 6]
    m = trimesh.creation.box([s, s * 0.8, s * 0.6])
    extra = ("--units", "m") if i % 6 in (4, 5) else ()
    return _export(m, d / "size.stl"), "coffee_can", extra


def fam_thin(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    t = (0.01, 0.05, 0.2, 0.4)[i % 4]
    m = trimesh.creation.box([rng.uniform(30, 60), rng.uniform(30, 60), t])
    return _export(m, d / "sheet.stl"), "washer", ()


def fam_nonmanifold_fin(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    """A box with an extra large fin triangle on one edge (not a sliver: a real defect)."""
    b = _box(rng)
    e = b.edges_unique[rng.integers(len(b.edges_unique))]
    tip = b.vertices[e].mean(axis=0) + rng.normal(0, 1, 3) * 40
    v = np.vstack([b.vertices, tip])
    f = np.vstack([b.faces, [[e[0], e[1], len(b.vertices)]]])
    return _export(trimesh.Trimesh(v, f, process=False), d / "fin.ply"), "coffee_can", ()


def fam_bad_obj_index(
    d: Path, rng: np.random.Generator, i: int
) -> tuple[Path, str, tuple[str, ...]]:
    b = _box(rng)
    text = _obj(b.vertices, b.faces)
    bad = ("f 0 1 2\n", "f 1 2 999\n", "f -1 -2 -40\n", "f a b c\n")[i % 4]
    p = d / "badidx.obj"
    p.write_text(text + bad)
    return p, "coffee_can", ()


def fam_two_parts(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    a = _box(rng, 20, 50)
    b = _box(rng, 20, 50)
    b.apply_translation([rng.uniform(60, 120), 0, 0])
    both = trimesh.util.concatenate([a, b])
    assert isinstance(both, trimesh.Trimesh)
    return _export(both, d / "two.stl"), "coffee_can", ()


def fam_not_a_file(d: Path, rng: np.random.Generator, i: int) -> tuple[Path, str, tuple[str, ...]]:
    kind = i % 4
    if kind == 0:
        p = d / "folder.stl"
        p.mkdir()
    elif kind == 1:
        p = d / "pipe.stl"
        os.mkfifo(p)
    elif kind == 2:
        p = d / "zero.stl"
        p.symlink_to("/dev/zero")
    else:
        p = d / "missing.obj"
    return p, "washer", ()


FAMILIES: dict[str, tuple[Gen, int]] = {
    # name: (generator, number of seeded cases)
    "box": (fam_box, 6),
    "sphere_metres": (fam_sphere_metres, 6),
    "flipped": (fam_flipped, 4),
    "small_hole": (fam_small_hole, 4),
    "open_bottom": (fam_open_bottom, 6),
    "scan": (fam_scan, 6),
    "quads": (fam_quads, 3),
    "duplicates": (fam_duplicates, 4),
    "single_triangle": (fam_single_triangle, 6),
    "flat_square": (fam_flat_square, 6),
    "truncated_obj": (fam_truncated_obj, 8),
    "truncated_binary": (fam_truncated_binary, 8),
    "ply_index_out_of_range": (fam_ply_index_out_of_range, 6),
    "ply_header_count": (fam_ply_header_count, 6),
    "ply_wrong_endian": (fam_ply_wrong_endian, 6),
    "obj_2d": (fam_obj_2d, 6),
    "nonfinite": (fam_nonfinite, 6),
    "stl_count_mismatch": (fam_stl_count_mismatch, 5),
    "empty": (fam_empty, 6),
    "garbage": (fam_garbage, 12),
    "points_only": (fam_points_only, 3),
    "size": (fam_size, 12),
    "thin": (fam_thin, 8),
    "nonmanifold_fin": (fam_nonmanifold_fin, 6),
    "bad_obj_index": (fam_bad_obj_index, 8),
    "two_parts": (fam_two_parts, 3),
    "not_a_file": (fam_not_a_file, 8),
}


def mesh_cases(folder: Path, seed: int = 0) -> list[MeshCase]:
    """Write every family's files under ``folder`` (one sub-folder per case)."""
    out: list[MeshCase] = []
    for fi, (fam, (gen, n)) in enumerate(FAMILIES.items()):
        for i in range(n):
            rng = np.random.default_rng([seed, fi, i])
            d = folder / f"{fam}_{i}"
            d.mkdir(parents=True, exist_ok=True)
            path, like, extra = gen(d, rng, i)
            out.append(MeshCase(f"{fam}_{i}", fam, path, like, extra))
    return out


def huge_sparse_stl(path: Path, size_bytes: int = 200_000_000) -> Path:
    """A binary STL whose header claims ``size_bytes`` worth of triangles, all zeros (sparse)."""
    n = (size_bytes - 84) // 50
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", n))
        fh.truncate(84 + 50 * n)
    return path


# ----------------------------------------------------------------------------- flags
@dataclass(frozen=True)
class FlagCase:
    """One bad command line."""

    name: str
    """Short description."""
    argv: tuple[str, ...]
    """Arguments after ``handbench``."""


def flag_cases(tmp: Path) -> list[FlagCase]:
    """At least 60 bad argument combinations; every one must exit 2 with one line.

    ``tmp`` is an empty folder: the cases create the files and folders they point at.
    """
    store = str(tmp / "store.sqlite")
    a_file = tmp / "a_file.txt"
    a_file.write_text("x")
    a_dir = tmp / "a_dir"
    a_dir.mkdir(exist_ok=True)
    garbage_db = tmp / "garbage.sqlite"
    garbage_db.write_bytes(b"not a database at all" * 10)
    box = tmp / "box.stl"
    trimesh.creation.box((40.0, 30.0, 20.0)).export(str(box))
    out = str(tmp / "out")
    ev = ("evaluate", "--cmc", "0", "--mcp", "45", "--object", "washer", "--store", store)
    sw = ("sweep", "--object", "washer", "--gh-stride", "500", "--out", out, "--store", store)
    rd = ("render", "--cmc", "0", "--mcp", "45")
    imp = ("objects", "import", str(box), "--like", "coffee_can")
    bf = ("bruteforce", "--cmc", "0", "--mcp", "45", "--object", "washer", "--store", store)
    table: list[tuple[str, tuple[str, ...]]] = [
        ("no command", ()),
        ("unknown command", ("fly",)),
        ("unknown flag", (*ev, "--foo")),
        ("evaluate workers -1", (*ev, "--workers", "-1")),
        ("evaluate workers 0", (*ev, "--workers", "0")),
        ("evaluate workers x", (*ev, "--workers", "x")),
        ("evaluate gh-stride 0", (*ev, "--gh-stride", "0")),
        ("evaluate gh-stride -3", (*ev, "--gh-stride", "-3")),
        ("evaluate cmc nan", ("evaluate", "--cmc", "nan", "--mcp", "45", "--store", store)),
        ("evaluate cmc 50", ("evaluate", "--cmc", "50", "--mcp", "45", "--store", store)),
        ("evaluate cmc -1", ("evaluate", "--cmc", "-1", "--mcp", "45", "--store", store)),
        ("evaluate mcp inf", ("evaluate", "--cmc", "0", "--mcp", "inf", "--store", store)),
        ("evaluate mcp missing", ("evaluate", "--cmc", "0", "--store", store)),
        ("evaluate unknown object", (*ev, "--object", "banana")),
        ("evaluate executor spark", (*ev, "--executor", "spark")),
        ("evaluate tilt sideways", (*ev, "--cmc-tilt", "sideways")),
        ("clearance -300", (*ev, "--approach-clearance-mm", "-300")),
        ("clearance nan", (*ev, "--approach-clearance-mm", "nan")),
        ("stop tol 0", (*ev, "--stop-tol-mm", "0")),
        ("stop tol 10", (*ev, "--stop-tol-mm", "10")),
        ("max steps 5", (*ev, "--max-steps", "5")),
        ("thumb rates negative", (*ev, "--thumb-rates", "-1", "-1")),
        ("tendon ratios nan", (*ev, "--tendon-ratios", "nan", "1", "1")),
        ("contact tol -1", (*ev, "--contact-tol-mm", "-1")),
        ("mu -1", (*ev, "--mu", "-1")),
        ("mu nan", (*ev, "--mu", "nan")),
        ("n-edges 0", (*ev, "--n-edges", "0")),
        ("n-edges 2.5", (*ev, "--n-edges", "2.5")),
        ("store is a folder", (*ev[:-2], "--store", str(a_dir))),
        ("store not writable", (*ev[:-2], "--store", "/proc/nope/results.sqlite")),
        ("store is garbage", (*ev[:-2], "--store", str(garbage_db))),
        ("sweep chunk 0", (*sw, "--chunk", "0")),
        ("sweep chunk -5", (*sw, "--chunk", "-5")),
        ("sweep mcp step 1e-9", (*sw, "--mcp", "0:90:1e-9")),
        ("sweep mcp step 0", (*sw, "--mcp", "0:90:0")),
        ("sweep cmc huge range", (*sw, "--cmc", "0:1e300:1")),
        ("sweep cmc empty item", (*sw, "--cmc", "0,,15")),
        ("sweep cmc only comma", (*sw, "--cmc", ",")),
        ("sweep cmc two parts", (*sw, "--cmc", "0:45")),
        ("sweep cmc letters", (*sw, "--cmc", "a,b")),
        ("sweep cmc reversed", (*sw, "--cmc", "45:0:5")),
        ("sweep cmc 60", (*sw, "--cmc", "0,60")),
        ("sweep mcp -5", (*sw, "--mcp", "-5")),
        (
            "sweep out /proc",
            ("sweep", "--object", "washer", "--out", "/proc/nope", "--store", store),
        ),
        ("sweep out is a file", ("sweep", "--object", "washer", "--out", str(a_file))),
        ("sweep workers 0", (*sw, "--workers", "0")),
        ("sweep workers -2", (*sw, "--workers", "-2")),
        ("sweep gh-stride 0", (*sw, "--gh-stride", "0")),
        ("sweep object missing value", (*sw, "--object")),
        ("render out /proc", (*rd, "--out", "/proc/nope.png")),
        ("render out .txt", (*rd, "--out", str(tmp / "x.txt"))),
        ("render out folder", (*rd, "--out", str(a_dir))),
        ("render out no extension", (*rd, "--out", str(tmp / "picture"))),
        ("render out empty", (*rd, "--out", "")),
        ("render gh without object", (*rd, "--out", str(tmp / "g.png"), "--gh", "3")),
        (
            "render gh out of range",
            (*rd, "--out", str(tmp / "g.png"), "--object", "washer", "--gh", "99999"),
        ),
        ("render unknown object", (*rd, "--out", str(tmp / "g.png"), "--object", "banana")),
        ("render cmc 99", ("render", "--cmc", "99", "--mcp", "0", "--out", str(tmp / "h.png"))),
        ("import save-to /proc", (*imp, "--save-to", "/proc/nope")),
        ("import save-to a file", (*imp, "--save-to", str(a_file))),
        ("import like banana", ("objects", "import", str(box), "--like", "banana")),
        ("import units km", (*imp, "--units", "km")),
        ("import bad key", (*imp, "--key", "Bad Key")),
        ("import shipped key", (*imp, "--key", "washer")),
        ("import missing file", ("objects", "import", str(tmp / "nope.stl"), "--like", "washer")),
        ("import a folder", ("objects", "import", str(a_dir), "--like", "washer")),
        ("import no action", ("objects",)),
        ("bruteforce max-grasps 0", (*bf, "--max-grasps", "0")),
        ("bruteforce workers 0", (*bf, "--workers", "0")),
        ("bruteforce out is a file", (*bf, "--out", str(a_file))),
        ("bruteforce seed x", (*bf, "--seed", "x")),
        ("serve port -1", ("serve", "--port", "-1")),
        ("serve port 70000", ("serve", "--port", "70000")),
        (
            "screenshot size abc",
            (
                "screenshot",
                "--cmc",
                "0",
                "--mcp",
                "0",
                "--out",
                str(tmp / "s.png"),
                "--size",
                "abc",
            ),
        ),
    ]
    return [FlagCase(n, a) for n, a in table]


#: Every subcommand path whose ``--help`` (and ``-h``) must exit 0.
HELP_PATHS: tuple[tuple[str, ...], ...] = (
    (),
    ("serve",),
    ("render",),
    ("evaluate",),
    ("sweep",),
    ("bruteforce",),
    ("objects",),
    ("objects", "list"),
    ("objects", "import"),
    ("screenshot",),
)
