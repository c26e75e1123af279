"""Contact extraction: the coarse screening of link samples is exact."""

from __future__ import annotations

import fcl
import numpy as np
import pytest

from app.model.hand.geometry import CapsuleShape
from app.model.hand.model import build_hand
from app.model.objects import load_object
from app.sim.contacts import _samples, near_surface


@pytest.mark.parametrize("key", ["power_drill", "plastic_pear", "washer", "chips_can"])
def test_screened_patch_points_equal_dense_evaluation(key: str) -> None:
    """Links placed with random poses touching or grazing the object: the screened selection
    equals evaluating the SDF on every sample, and so does the nearest sample."""
    obj = load_object(key)
    hand = build_hand(0.0, 45.0)
    rng = np.random.default_rng(7)
    surface = obj.mesh.vertices
    checked = 0
    for link in hand.links:
        p_link, _ = _samples(link.shape, 1.0)
        for _ in range(6):
            # a random rotation, shifted so that a random sample of the link lies within a
            # few mm of a random surface vertex
            R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            anchor = surface[rng.integers(len(surface))]
            k = rng.integers(len(p_link))
            T = np.eye(4)
            T[:3, :3] = R
            T[:3, 3] = anchor - R @ p_link[k] + rng.normal(scale=1.0, size=3)
            tol = float(rng.choice([0.5, 1.0, 3.0]))
            p_obj = p_link @ R.T + T[:3, 3]
            sd = obj.sdf(p_obj)
            dense = np.flatnonzero(sd <= tol)
            got, nearest = near_surface(obj, link.shape, T, tol, 1.0)
            assert np.array_equal(got, dense), (key, link.name)
            assert sd[nearest] == sd.min(), (key, link.name)
            checked += len(dense) > 0
    assert checked > 20  # most placements actually touch


def _lying(shape: object, centre: np.ndarray, axis: np.ndarray, up: np.ndarray) -> np.ndarray:
    """T_object_link of a capsule link whose axis lies along ``axis`` through ``centre``."""
    assert isinstance(shape, CapsuleShape)
    z = axis / np.linalg.norm(axis)
    x = up / np.linalg.norm(up)
    R = np.column_stack([x, np.cross(z, x), z])
    T_fcl = np.eye(4)
    T_fcl[:3, :3], T_fcl[:3, 3] = R, centre
    return T_fcl @ np.linalg.inv(shape.T_link_fcl())


def _rotated(T: np.ndarray, about: np.ndarray, angle: float, axis: np.ndarray) -> np.ndarray:
    """T turned by ``angle`` rad about the line through ``about`` along ``axis``."""
    from scipy.spatial.transform import Rotation

    R = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()
    out = T.copy()
    out[:3, :3] = R @ T[:3, :3]
    out[:3, 3] = R @ (T[:3, 3] - about) + about
    return out


# (object, link, capsule centre, axis, outward face normal): links lying flat, 0.5 mm off
# a flat face (the drill battery's box faces, the washer's top face; the last one spans
# the washer's hole and touches the ring in two separate places)
FLAT_CASES = [
    ("power_drill", "thumb_metacarpal", (-40.0, -28.5, 25.0), (1, 0, 0), (0, -1, 0)),
    ("power_drill", "index_proximal", (-90.0, 0.0, 25.0), (0, 1, 0), (-1, 0, 0)),
    ("washer", "thumb_distal", (12.75, 0.0, 3.0), (0, 1, 0), (0, 0, 1)),
    ("washer", "index_proximal", (0.0, 0.0, 3.0), (0, 1, 0), (0, 0, 1)),
]


@pytest.mark.parametrize("case", FLAT_CASES, ids=[f"{c[0]}-{c[1]}" for c in FLAT_CASES])
def test_flat_patch_is_stable_under_tiny_rotations(case: tuple) -> None:
    """A link lying parallel to a flat face touches along a band; its patch must not depend on
    where a nearest-point query lands on that band: turning the link by 1e-7 rad about random
    axes leaves the patch (points, normals, palmar flags) the same up to the motion itself."""
    from app.sim.contacts import ContactSettings, contacts_of_links

    key, link_name, face_point, axis, out = case
    obj = load_object(key)
    hand = build_hand(0.0, 45.0)
    j = [lk.name for lk in hand.links].index(link_name)
    shape = hand.links[j].shape
    assert isinstance(shape, CapsuleShape)
    out_v = np.asarray(out, float)
    centre = np.asarray(face_point, float) + (shape.radius + 0.5) * out_v
    T = _lying(shape, centre, np.asarray(axis, float), out_v)
    settings = ContactSettings()
    body = fcl.CollisionObject(shape.fcl_geometry(), fcl.Transform())
    T_fcl = shape.T_link_fcl()[None]

    def patch(Tl: np.ndarray):
        cs = contacts_of_links(obj, [link_name], [shape], [body], Tl[None], T_fcl, settings, 75.0)
        return cs

    ref = patch(T)
    assert len(ref) == settings.max_points_per_link
    # the patch spans the band (not a disc about one point): its extent along the link axis
    along = ref.p_object @ np.asarray(axis, float)
    assert np.ptp(along) > 0.5 * shape.length
    two_places = link_name == "index_proximal" and key == "washer"
    if not two_places:  # (across the hole, points near the inner edge face the edge)
        np.testing.assert_allclose(ref.n_object, np.tile(-out_v, (len(ref), 1)), atol=1e-6)
    rng = np.random.default_rng(3)
    for _ in range(12):
        Tp = _rotated(T, centre + rng.uniform(-20, 20, 3), 1e-7, rng.normal(size=3))
        got = patch(Tp)
        assert len(got) == len(ref)
        np.testing.assert_allclose(got.p_object, ref.p_object, atol=1e-4)
        np.testing.assert_allclose(got.n_object, ref.n_object, atol=1e-4)
        assert np.array_equal(got.palmar, ref.palmar)
    if two_places:  # both places are kept
        y = ref.p_object[:, 1]
        assert (y < -8.0).any() and (y > 8.0).any()


@pytest.mark.parametrize("key", ["small_marker", "plastic_pear", "washer", "chips_can",
                                 "coffee_can", "power_drill"])  # fmt: skip
def test_compiled_sdf_equals_numpy(key: str) -> None:
    """The compiled signed distance of every built-in object equals the numpy one (random
    points near the surface, inside, and far outside the tables)."""
    from app.sim.sdf_compiled import object_program, sdf_many

    obj = load_object(key)
    prog = object_program(obj)
    assert prog is not None
    rng = np.random.default_rng(11)
    v = obj.mesh.vertices
    p = np.vstack([
        v[rng.integers(len(v), size=3000)] + rng.normal(scale=s, size=(3000, 3))
        for s in (0.3, 3.0, 30.0, 80.0)
    ])  # fmt: skip
    np.testing.assert_allclose(sdf_many(p, prog), obj.sdf(p), rtol=0, atol=1e-9)


@pytest.mark.parametrize("key", ["plastic_pear", "washer", "coffee_can", "power_drill"])
def test_compiled_contacts_equal_numpy(key: str) -> None:
    """The compiled contact path gives the numpy path's contact set (points, normals, links,
    palmar flags) for hands posed touching the object, wherever GJK and FCL agree on which
    links are within tol (they differ by FCL's ~1e-4 mm error only)."""
    from app.sim.contacts import ContactSettings, contacts_of_links
    from app.sim.contacts_compiled import contacts_compiled
    from app.sim.simulate import cached_kit

    obj = load_object(key)
    kit = cached_kit(0.0, 45.0, "ulnar")
    settings = ContactSettings()
    rng = np.random.default_rng(5)
    surface = obj.mesh.vertices
    n_touch = 0
    for _ in range(25):
        q = kit.q_open + rng.uniform(0.0, 1.2, kit.q_open.shape)
        T_palm = np.eye(4)
        T_palm[:3, :3], _ = np.linalg.qr(rng.normal(size=(3, 3)))
        T_links = kit.hand.link_poses(q)
        j = int(rng.integers(len(T_links)))
        p_link, _ = _samples(kit.shapes[j], 1.0)
        anchor = surface[rng.integers(len(surface))]
        # link j's first sample on a random surface vertex, give or take a millimetre
        p_palm = T_links[j][:3, :3] @ p_link[0] + T_links[j][:3, 3]
        T_palm[:3, 3] = anchor - T_palm[:3, :3] @ p_palm + rng.normal(scale=0.7, size=3)
        T = T_palm @ T_links
        a = contacts_of_links(obj, kit.names, kit.shapes, kit.moving, T, kit.T_link_fcl,
                              settings, 75.0)  # fmt: skip
        c = contacts_compiled(obj, kit.names, kit.shapes, T, settings, 75.0)
        assert c is not None
        assert a.links == c.links
        assert np.array_equal(a.link, c.link)
        np.testing.assert_allclose(c.p_object, a.p_object, rtol=0, atol=1e-9)
        np.testing.assert_allclose(c.n_object, a.n_object, rtol=0, atol=1e-9)
        assert np.array_equal(a.palmar, c.palmar)
        n_touch += len(a) > 0
    assert n_touch >= 15


def test_compiled_contacts_on_an_imported_mesh_equal_numpy(tmp_path, monkeypatch) -> None:
    """On an imported mesh the compiled contact path (the field's node bounds screen the
    samples, ``mesh_select``; exact values where they straddle tol) gives the numpy path's
    contact set (every screened sample's exact distance) for hands posed touching or
    grazing the scan, grazing links (no sample within tol) included."""
    from app.model.objects import import_object
    from app.model.objects.model import unregister_object
    from app.sim.closing_compiled import link_mesh_distance
    from app.sim.contacts import ContactSettings, contacts_of_links
    from app.sim.contacts_compiled import contacts_compiled
    from app.sim.simulate import cached_kit

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    path = tmp_path / "pear_scan.ply"
    load_object("plastic_pear").mesh.export(str(path))
    obj = import_object(path, like="plastic_pear", units="mm", key="pear_scan_test")
    try:
        pk = obj.mesh_pack()
        kit = cached_kit(0.0, 45.0, "ulnar")
        settings = ContactSettings()
        tol = settings.contact_tol_mm
        rng = np.random.default_rng(8)
        surface = obj.mesh.vertices
        n_touch = n_links = n_grazing = 0
        for k in range(40):
            q = kit.q_open + rng.uniform(0.0, 1.2, kit.q_open.shape)
            T_palm = np.eye(4)
            T_palm[:3, :3], _ = np.linalg.qr(rng.normal(size=(3, 3)))
            T_links = kit.hand.link_poses(q)
            j = int(rng.integers(len(T_links)))
            p_link, _ = _samples(kit.shapes[j], 1.0)
            anchor = surface[rng.integers(len(surface))]
            p_palm = T_links[j][:3, :3] @ p_link[0] + T_links[j][:3, 3]
            T_palm[:3, 3] = anchor - T_palm[:3, :3] @ p_palm + rng.normal(scale=0.7, size=3)
            T = T_palm @ T_links
            if k % 2:  # link j moved along x until it is 0.01 mm inside tol: often grazing
                d = link_mesh_distance(kit.shapes[j], T[j] @ kit.T_link_fcl[j], pk, 1e9)
                for _ in range(30):
                    if abs(d - (tol - 0.01)) < 1e-3:
                        break
                    T[:, 0, 3] += d - (tol - 0.01)
                    d = link_mesh_distance(kit.shapes[j], T[j] @ kit.T_link_fcl[j], pk, 1e9)
            a = contacts_of_links(
                obj, kit.names, kit.shapes, kit.moving, T, kit.T_link_fcl, settings, 75.0,
                link_distance=lambda sh, Tf: link_mesh_distance(sh, Tf, pk, tol),
            )  # fmt: skip
            c = contacts_compiled(obj, kit.names, kit.shapes, T, settings, 75.0)
            assert c is not None
            assert np.array_equal(a.link, c.link)
            np.testing.assert_allclose(c.p_object, a.p_object, rtol=0, atol=1e-9)
            np.testing.assert_allclose(c.n_object, a.n_object, rtol=0, atol=1e-9)
            assert np.array_equal(a.palmar, c.palmar)
            n_touch += len(a) > 0
            for name in set(a.link.tolist()):
                n_links += 1
                p = a.p_object[a.link == name]
                n_grazing += len(p) == 1 and float(obj.sdf(p)[0]) > tol
        assert n_touch >= 15 and n_links >= 25
        assert n_grazing >= 1  # the exact fallback ran too
    finally:
        unregister_object("pear_scan_test")
