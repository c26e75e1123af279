"""Tests of app.model.objects: data files, meshes, SDF, FCL pieces, import of user meshes."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import fcl
import numpy as np
import pytest
import trimesh

from app.errors import MeshImportError, UnknownObjectError
from app.model.objects import (
    OBJECT_KEYS,
    GraspObject,
    available_keys,
    import_object,
    load_object,
    unregister_object,
)

METHOD_N_GH = {
    "small_marker": 1026,
    "plastic_pear": 648,
    "washer": 1026,
    "chips_can": 420,
    "coffee_can": 420,
    "power_drill": 720,
}


@pytest.fixture(scope="module", params=OBJECT_KEYS)
def obj(request: pytest.FixtureRequest) -> GraspObject:
    return load_object(request.param)


def _near_surface(o: GraspObject, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    res = trimesh.sample.sample_surface(o.mesh, n, seed=seed)
    return np.asarray(res[0]), np.asarray(o.mesh.face_normals[res[1]])


def _outside_points(o: GraspObject, n: int, seed: int, min_sdf: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = o.mesh.bounds[0] - 30.0, o.mesh.bounds[1] + 30.0
    p = rng.uniform(lo, hi, size=(4 * n, 3))
    return p[o.sdf(p) > min_sdf][:n]


def test_keys_order_and_unknown() -> None:
    assert OBJECT_KEYS == tuple(METHOD_N_GH)
    with pytest.raises(UnknownObjectError) as e:
        load_object("banana")
    msg = str(e.value)
    assert "banana" in msg and all(k in msg for k in OBJECT_KEYS)
    assert isinstance(e.value, KeyError)


def test_loads_cached_and_set_up(obj: GraspObject) -> None:
    s = obj.spec
    assert load_object(s.key) is obj
    assert s.setup.n_gh == METHOD_N_GH[s.key]
    assert s.grasp_type == ("CG" if s.key in ("chips_can", "coffee_can", "power_drill") else "PP")
    assert (s.grip_axis_object is not None) == (s.grasp_type == "CG")
    assert math.isclose(np.linalg.norm(s.setup.hand_vector_palm), 1.0)
    assert abs(s.palm_y_hint_object @ s.normal_object) < 1e-6
    if s.grip_axis_object is not None:  # CG: the palm +y runs around the grip axis
        assert abs(s.palm_y_hint_object @ s.grip_axis_object) < 1e-6
        assert abs(s.grip_axis_object @ s.normal_object) < 1e-6
    if s.key in ("chips_can", "coffee_can"):
        assert s.setup.roll_range_deg == (-20.0, -50.0)
        assert np.allclose(np.rad2deg(s.setup.rolls_rad)[[0, -1]], [-20.0, -50.0])
    assert obj.collision_objects() is obj.collision_objects()
    assert len(obj.mesh.faces) < 20_000


def test_mesh_watertight(obj: GraspObject) -> None:
    m = obj.mesh
    assert m.is_watertight and m.is_winding_consistent
    assert m.volume > 0
    assert np.all(obj.centroid_object > m.bounds[0]) and np.all(obj.centroid_object < m.bounds[1])
    assert obj.max_radius > 0.5 * np.linalg.norm(m.extents) * 0.5


def test_dimensions_match_data_file(obj: GraspObject) -> None:
    s, ext = obj.spec.shape, obj.mesh.extents
    key = obj.spec.key
    if key == "small_marker":
        expected = [s["length_mm"], s["barrel_diameter_mm"], s["barrel_diameter_mm"]]
    elif key == "plastic_pear":
        cp = np.asarray(s["profile_zr_mm"])
        expected = [2 * cp[:, 1].max(), 2 * cp[:, 1].max(), cp[-1, 0]]
        assert expected == [67.0, 67.0, 100.0]
    elif key == "washer":
        expected = [s["outer_diameter_mm"], s["outer_diameter_mm"], s["thickness_mm"]]
        # the hole: centre point is r_in away from the inner wall
        assert obj.sdf(np.array([[0.0, 0.0, 1.5]]))[0] == pytest.approx(
            s["inner_diameter_mm"] / 2, abs=0.3
        )
    elif key in ("chips_can", "coffee_can"):
        expected = [s["diameter_mm"], s["diameter_mm"], s["height_mm"]]
    else:
        expected = [185.0, 57.0, 188.0]  # METHOD: 185 long x 188 tall x 57 wide
    assert np.allclose(ext, expected, atol=1.0), (ext, expected)
    assert abs(obj.mesh.bounds[0, 2]) < 1e-6  # resting on the table z = 0


def test_sdf_sign_and_surface(obj: GraspObject) -> None:
    assert np.abs(obj.sdf(obj.mesh.vertices)).max() < 0.3
    p, n = _near_surface(obj, 400, seed=1)
    assert np.abs(obj.sdf(p)).max() < 0.3
    assert np.all(obj.sdf(p - 0.5 * n) < 0)
    assert np.all(obj.sdf(p + 0.5 * n) > 0)
    assert np.all(obj.sdf(obj.centroid_object[None]) < 0) or obj.spec.key == "washer"


def test_sdf_matches_fcl_pieces(obj: GraspObject) -> None:
    pts = _outside_points(obj, 60, seed=2, min_sdf=2.0)
    assert len(pts) >= 30
    radius = 1.0
    sphere = fcl.Sphere(radius)
    req = fcl.DistanceRequest()
    for p in pts:
        probe = fcl.CollisionObject(sphere, fcl.Transform(np.eye(3), p))
        d = min(fcl.distance(c, probe, req, fcl.DistanceResult()) for c in obj.collision_objects())
        assert d + radius == pytest.approx(obj.sdf(p[None])[0], abs=0.5), p


def test_normal_unit_and_outward(obj: GraspObject) -> None:
    p, _ = _near_surface(obj, 200, seed=3)
    p = np.vstack([p, _outside_points(obj, 100, seed=4, min_sdf=0.5)])
    n = obj.normal(p)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)
    assert np.all(obj.sdf(p + 1.0 * n) > obj.sdf(p))


def test_target_on_surface_and_normal(obj: GraspObject) -> None:
    s = obj.spec
    t = s.target_object[None]
    assert abs(obj.sdf(t)[0]) < 0.3
    n = obj.normal(t)[0]
    angle = math.degrees(math.acos(float(np.clip(n @ s.normal_object, -1.0, 1.0))))
    assert angle < 5.0


# ------------------------------------------------------------------------- import


def _write(path: Path, mesh: trimesh.Trimesh) -> Path:
    mesh.export(str(path))
    return path


def test_import_box_in_metres(tmp_path: Path) -> None:
    p = _write(tmp_path / "Small Box.stl", trimesh.creation.box((0.05, 0.04, 0.03)))
    try:
        o = import_object(p, like="coffee_can", units="m")
        assert o.spec.key == "small_box"
        assert load_object("small_box") is o and "small_box" in available_keys()
        assert np.allclose(o.mesh.extents, [50.0, 40.0, 30.0])
        assert o.mesh.is_watertight and o.spec.grasp_type == "CG"
        assert o.spec.setup == load_object("coffee_can").spec.setup
        assert abs(o.sdf(o.spec.target_object[None])[0]) < 1e-6
        # object frame: base centre at the origin, +z up (the box spans z 0..30); the mesh's
        # distance field is exact within 8 mm of the surface, within ~h (1 mm) deeper
        assert o.sdf(np.array([[0.0, 0.0, 4.0], [0.0, 0.0, 36.0]])) == pytest.approx([-4.0, 6.0])
        far = o.sdf(np.array([[0.0, 0.0, 15.0], [0.0, 0.0, 55.0]]))
        assert far == pytest.approx([-15.0, 25.0], abs=1.25)
        n = o.normal(o.spec.target_object[None])[0]
        assert n @ o.spec.normal_object > 0.99
        assert len(o.collision_objects()) == 1
    finally:
        unregister_object("small_box")
    with pytest.raises(UnknownObjectError):
        load_object("small_box")


def test_import_absurd_size_suggests_units(tmp_path: Path) -> None:
    p = _write(tmp_path / "box.stl", trimesh.creation.box((0.05, 0.04, 0.03)))
    with pytest.raises(MeshImportError, match="--units m"):
        import_object(p, like="coffee_can", units="mm", register=False)
    big = _write(tmp_path / "big.stl", trimesh.creation.box((50.0, 40.0, 30.0)))
    with pytest.raises(MeshImportError, match="--units mm"):
        import_object(big, like="coffee_can", units="m", register=False)


def test_import_bad_files(tmp_path: Path) -> None:
    empty = tmp_path / "empty.stl"
    empty.write_bytes(b"")
    with pytest.raises(MeshImportError, match="empty"):
        import_object(empty, like="washer", register=False)
    with pytest.raises(MeshImportError, match="not found"):
        import_object(tmp_path / "missing.ply", like="washer", register=False)
    odd = tmp_path / "thing.xyz"
    odd.write_text("1 2 3\n")
    with pytest.raises(MeshImportError, match=r"\.stl.*\.obj.*\.ply"):
        import_object(odd, like="washer", register=False)
    nan = tmp_path / "nan.obj"
    nan.write_text("v 0 0 0\nv 10 0 0\nv 0 nan 0\nv 0 0 10\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    with pytest.raises(MeshImportError, match="NaN"):
        import_object(nan, like="washer", register=False)
    noface = tmp_path / "noface.obj"
    noface.write_text("v 0 0 0\nv 10 0 0\n")
    with pytest.raises(MeshImportError, match="empty"):
        import_object(noface, like="washer", register=False)
    with pytest.raises(UnknownObjectError):
        import_object(noface, like="banana", register=False)
    with pytest.raises(MeshImportError, match="shipped"):
        import_object(noface, like="washer", key="washer", register=False)


def test_import_open_mesh(tmp_path: Path) -> None:
    tube = trimesh.creation.cylinder(radius=20.0, height=60.0, sections=32)
    side = np.abs(tube.face_normals[:, 2]) < 0.5
    open_tube = trimesh.Trimesh(tube.vertices, tube.faces[side])
    p = _write(tmp_path / "tube.ply", open_tube)
    with pytest.raises(MeshImportError, match="not closed"):
        import_object(p, like="chips_can", register=False)
    with pytest.warns(UserWarning, match="open; 2 larger holes were closed with flat caps"):
        o = import_object(p, like="chips_can", register=False, allow_open=True)
    assert o.mesh.is_watertight
    assert o.mesh.volume == pytest.approx(tube.volume, rel=1e-6)  # the caps close it
    # one missing triangle is a small hole: filled, with a warning
    box = trimesh.creation.box((30.0, 30.0, 30.0))
    holed = _write(tmp_path / "holed.ply", trimesh.Trimesh(box.vertices, box.faces[1:]))
    with pytest.warns(UserWarning, match="holes"):
        o = import_object(holed, like="coffee_can", register=False)
    assert o.mesh.is_watertight and o.mesh.volume == pytest.approx(27_000.0)


def test_import_repairs_polygons_and_degenerate(tmp_path: Path) -> None:
    cube = tmp_path / "cube.obj"
    v = "".join(f"v {x} {y} {z}\n" for x in (0, 20) for y in (0, 20) for z in (0, 20))
    quads = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    cube.write_text(v + quads)
    with pytest.warns(UserWarning, match="triangulated"):
        o = import_object(cube, like="washer", register=False)
    assert o.mesh.is_watertight and o.mesh.volume == pytest.approx(8000.0)
    box = trimesh.creation.box((30.0, 30.0, 30.0))
    faces = np.vstack([box.faces, [[0, 0, 1]]])
    deg = _write(tmp_path / "deg.ply", trimesh.Trimesh(box.vertices, faces, process=False))
    with pytest.warns(UserWarning, match="degenerate"):
        o = import_object(deg, like="washer", register=False)
    assert len(o.mesh.faces) == 12 and o.mesh.is_watertight


def test_import_save_and_reload_from_user_dir(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = _write(tmp_path / "ball.stl", trimesh.creation.icosphere(2, radius=30.0))
    user = tmp_path / "user"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        o = import_object(src, like="plastic_pear", key="my_ball", register=False, save_to=user)
    assert (user / "my_ball.ply").is_file() and (user / "my_ball.toml").is_file()
    with pytest.raises(UnknownObjectError):
        load_object("my_ball")
    monkeypatch.setenv("HANDBENCH_USER_OBJECTS", str(user))
    r = load_object("my_ball")
    assert r.spec.grasp_type == "PP" and r.spec.setup.n_gh == 648
    assert np.allclose(r.spec.target_object, o.spec.target_object, atol=1e-4)
    assert np.allclose(r.mesh.bounds, o.mesh.bounds, atol=1e-4)
    assert "my_ball" in available_keys()


def test_import_fixes_flipped_faces(tmp_path: Path) -> None:
    box = trimesh.creation.box((30.0, 20.0, 10.0))
    faces = np.array(box.faces)
    faces[[0, 3, 7]] = faces[[0, 3, 7]][:, ::-1]
    p = _write(tmp_path / "flipped.ply", trimesh.Trimesh(box.vertices, faces, process=False))
    o = import_object(p, like="washer", register=False)
    assert o.mesh.is_winding_consistent and o.mesh.volume == pytest.approx(6000.0)
    assert o.sdf(np.array([[0.0, 0.0, 5.0]]))[0] == pytest.approx(-5.0)  # base at z = 0


def test_orientation_up_axis_is_the_shortest_turn() -> None:
    from app.model.objects.importer import orientation_matrix

    R = orientation_matrix("+y")
    assert np.allclose(R @ [0, 1, 0], [0, 0, 1]) and np.allclose(R @ [1, 0, 0], [1, 0, 0])
    assert np.allclose(orientation_matrix("-z") @ [0, 0, -1], [0, 0, 1])
    with pytest.raises(MeshImportError, match=r"\+x"):
        orientation_matrix("w")


def test_target_normal_is_averaged_over_a_patch(tmp_path: Path) -> None:
    """A coarse, noisy cylinder: one triangle's normal is off; the patch mean is radial."""
    rng = np.random.default_rng(3)
    c = trimesh.creation.cylinder(radius=50.0, height=140.0, sections=48)
    c.vertices += rng.normal(0, 0.4, c.vertices.shape)
    p = _write(tmp_path / "can.ply", c)
    o = import_object(p, like="coffee_can", register=False)
    t, n = o.spec.target_object, o.spec.normal_object
    radial = np.array([t[0], t[1], 0.0]) / np.hypot(t[0], t[1])
    assert np.degrees(np.arccos(np.clip(n @ radial, -1, 1))) < 3.0
