"""Collision-driven closing: tolerance, no penetration, semantics, modes, invariance."""

from __future__ import annotations

import dataclasses

import fcl
import numpy as np
import pytest

from app.errors import SettingsError
from app.model.hand.model import build_hand
from app.quality.settings import SimSettings
from app.sim.closing import ClosingStats, Obstacles, close_finger, fcl_transform, pair_distance
from app.sim.closing_naive import close_finger_naive
from app.sim.closing_settings import ClosingSettings
from app.sim.contacts import ContactSettings
from app.sim.simulate import HandKit, simulate_base, simulate_thumb
from tests.utils import AnalyticCylinder, can_hypotheses


def link_distances(kit: HandKit, grasp, obj) -> np.ndarray:
    """(16,) signed FCL distance of every link to the object at the final grasp."""
    T_links = grasp.T_object_palm @ kit.hand.link_poses(grasp.q)
    out = []
    for j, body in enumerate(kit.moving):
        body.setTransform(fcl_transform(T_links[j] @ kit.T_link_fcl[j]))
        out.append(min(pair_distance(body, p) for p in obj.collision_objects()))
    return np.array(out)


@pytest.fixture(scope="module")
def can_grasps():
    obj = AnalyticCylinder()
    hyps = can_hypotheses()
    kit = HandKit(build_hand(0, 45))
    s = SimSettings()
    picks = range(0, len(hyps), 23)
    grasps = [simulate_thumb(kit, obj, simulate_base(kit, obj, hyps, i, s), s) for i in picks]
    return obj, kit, s, grasps


def test_closing_stops_within_tolerance_without_penetration(can_grasps) -> None:
    obj, kit, s, grasps = can_grasps
    tol = s.closing.stop_tol_mm
    for g in grasps:
        d = link_distances(kit, g, obj)
        assert d.min() > 0.0, "a link penetrates the object"
        touching = d <= s.contact.contact_tol_mm
        assert touching.sum() >= 4  # a cylindrical wrap touches with several links
        # every closing joint that stopped short of its limit did so at a contact: the
        # most distal link of its finger is within the stop tolerance
        for finger in ("index", "middle", "ring", "little"):
            ch = kit.chains[finger]
            q = g.q[list(ch.joints)]
            if (q < ch.q_upper - 1e-9).any():
                assert d[list(ch.link_indices)].min() <= tol + 1e-6, finger


def test_gap_stays_within_any_stop_tolerance() -> None:
    obj, hyps = AnalyticCylinder(), can_hypotheses()
    kit = HandKit(build_hand(0, 45))
    for tol in (0.1, 0.3, 1.0):
        s = SimSettings(closing=ClosingSettings(stop_tol_mm=tol), contact=ContactSettings(1.0))
        for i in (5, 211):
            g = simulate_thumb(kit, obj, simulate_base(kit, obj, hyps, i, s), s)
            d = link_distances(kit, g, obj)
            assert d.min() > 0.0
            for finger in ("thumb", "index", "middle"):
                ch = kit.chains[finger]
                if (g.q[list(ch.joints)] < ch.q_upper - 1e-9).any():
                    assert d[list(ch.link_indices)].min() <= tol + 1e-6


@pytest.mark.parametrize("i", [0, 57, 140, 305])
def test_final_angles_are_the_limit_of_fixed_step_closing(i: int) -> None:
    """No step size in our closing: fixed-step closing converges to our angles as h -> 0.

    Fixed stepping stops up to one step past the first touch in each stage; a near-tangent
    contact can amplify that in the next stage, so the error shrinks with h rather than
    being below h.
    """
    obj, hyps = AnalyticCylinder(), can_hypotheses()
    kit = HandKit(build_hand(0, 45))
    s = SimSettings()
    base = simulate_base(kit, obj, hyps, i, s)
    obstacles = Obstacles(list(obj.collision_objects()), 1)
    for finger in ("index", "middle", "ring"):
        ch = kit.chains[finger]
        ours = close_finger(
            ch, kit.bodies(finger), base.T_object_palm, obstacles, s.closing, ClosingStats()
        )
        errors = []
        for h in (0.004, 0.0004):
            ref = close_finger_naive(
                ch,
                kit.bodies(finger),
                base.T_object_palm,
                obstacles,
                s.closing,
                ClosingStats(),
                step_rad=h,
            )
            errors.append(np.rad2deg(np.abs(ours - ref)).max())
        assert errors[1] <= errors[0] + 1e-9 or errors[1] < 0.1, (finger, errors)
        assert errors[1] < 1.0, (finger, errors)


def test_a_finger_in_free_space_closes_to_its_limits() -> None:
    kit = HandKit(build_hand(0, 45))
    far = fcl.CollisionObject(fcl.Sphere(5.0), fcl.Transform(np.array([0, 0, 5000.0])))
    for mode in ("sequential", "coupled_tendon", "independent_thumb"):
        s = ClosingSettings(mode=mode)  # type: ignore[arg-type]
        for finger in ("thumb", "index", "little"):
            ch = kit.chains[finger]
            q = close_finger(
                ch, kit.bodies(finger), np.eye(4), Obstacles([far], 1), s, ClosingStats()
            )
            assert np.allclose(q, ch.q_upper), (mode, finger)


def test_sequential_distal_contact_keeps_proximal_joints() -> None:
    """A wall the index fingertip meets while the MCP closes: PIP and DIP stay open."""
    kit = HandKit(build_hand(0, 45))
    ch = kit.chains["index"]
    # index tip at y ~ 164 at q = 0; a box just palmar of the tip region
    wall = fcl.CollisionObject(fcl.Box(60, 20, 10), fcl.Transform(np.array([21.0, 158.0, 40.0])))
    stats = ClosingStats()
    q = close_finger(
        ch, kit.bodies("index"), np.eye(4), Obstacles([wall], 1), ClosingSettings(), stats
    )
    assert 0 < q[0] < ch.q_upper[0]
    assert q[1] == 0.0 and q[2] == 0.0
    assert stats.events == ["index:[0]:contact"]


def test_sequential_proximal_contact_then_distal_joints_close() -> None:
    """A bar under the proximal phalanx: MCP stops on it, then PIP and DIP close."""
    kit = HandKit(build_hand(0, 45))
    ch = kit.chains["index"]
    bar = fcl.CollisionObject(fcl.Box(60, 8, 8), fcl.Transform(np.array([21.0, 95.0, 25.0])))
    stats = ClosingStats()
    q = close_finger(
        ch, kit.bodies("index"), np.eye(4), Obstacles([bar], 1), ClosingSettings(), stats
    )
    assert 0 < q[0] < ch.q_upper[0]
    assert q[1] > 0.3  # the PIP closed afterwards
    assert stats.events[0] == "index:[0]:contact"
    assert stats.events[1].startswith("index:[1]:")


def test_coupled_tendon_moves_joints_together() -> None:
    kit = HandKit(build_hand(0, 45))
    ch = kit.chains["index"]
    wall = fcl.CollisionObject(fcl.Box(60, 80, 10), fcl.Transform(np.array([21.0, 110.0, 45.0])))
    s = ClosingSettings(mode="coupled_tendon", tendon_ratios=(1.0, 1.0, 0.8))
    stats = ClosingStats()
    q = close_finger(ch, kit.bodies("index"), np.eye(4), Obstacles([wall], 1), s, stats)
    assert stats.events[0] == "index:[0, 1, 2]:contact"
    assert q[1] == pytest.approx(q[0]) or q[1] > q[0]  # PIP at least as closed as MCP
    assert q[0] > 0


def test_thumb_self_collision_never_penetrates_the_fingers(can_grasps) -> None:
    obj, kit, s, grasps = can_grasps
    for g in grasps:
        T_links = g.T_object_palm @ kit.hand.link_poses(g.q)
        thumb = kit.chains["thumb"].link_indices
        for j in range(len(kit.names)):
            kit.static[j].setTransform(fcl_transform(T_links[j] @ kit.T_link_fcl[j]))
        for t in thumb[1:]:
            kit.moving[t].setTransform(fcl_transform(T_links[t] @ kit.T_link_fcl[t]))
            for j, name in enumerate(kit.names):
                if name.startswith("thumb"):
                    continue
                assert pair_distance(kit.moving[t], kit.static[j]) > 0.0, (kit.names[t], name)


def random_rigid(rng: np.random.Generator) -> np.ndarray:
    A = rng.normal(size=(3, 3))
    Q, R = np.linalg.qr(A)
    Q *= np.sign(np.diag(R))
    if np.linalg.det(Q) < 0:
        Q[:, 0] *= -1
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = Q, rng.uniform(-300, 300, 3)
    return T


def test_grasps_are_invariant_under_a_rigid_motion_of_hand_and_object() -> None:
    rng = np.random.default_rng(3)
    T = random_rigid(rng)
    R, t = T[:3, :3], T[:3, 3]
    a_obj, b_obj = AnalyticCylinder(), AnalyticCylinder(T_world_cyl=T)
    a_h = can_hypotheses()
    b_h = dataclasses.replace(
        a_h,
        ray_object=a_h.ray_object @ R.T,
        target_object=R @ a_h.target_object + t,
        R_object_palm=np.einsum("ij,njk->nik", R, a_h.R_object_palm),
    )
    kit, s = HandKit(build_hand(15, 60)), SimSettings()
    for i in (0, 101, 333):
        ga = simulate_thumb(kit, a_obj, simulate_base(kit, a_obj, a_h, i, s), s)
        gb = simulate_thumb(kit, b_obj, simulate_base(kit, b_obj, b_h, i, s), s)
        assert np.allclose(T @ ga.T_object_palm, gb.T_object_palm, atol=1e-6)
        assert np.rad2deg(np.abs(ga.q - gb.q)).max() < 0.5
        assert ga.contacts.links == gb.contacts.links
        assert ga.contacts.palmar_links() == gb.contacts.palmar_links()


def test_settings_validation_lists_choices() -> None:
    with pytest.raises(SettingsError, match="sequential"):
        ClosingSettings(mode="wiggle")  # type: ignore[arg-type]
    with pytest.raises(SettingsError, match="stop_tol_mm"):
        ClosingSettings(stop_tol_mm=0)


# ------------------------------------------------------------ the compiled engine


def _compiled(s: SimSettings) -> SimSettings:
    return dataclasses.replace(s, closing=dataclasses.replace(s.closing, engine="compiled"))


def _fcl(s: SimSettings) -> SimSettings:
    return dataclasses.replace(s, closing=dataclasses.replace(s.closing, engine="fcl"))


def test_compiled_engine_is_the_default() -> None:
    assert ClosingSettings().engine == "compiled"
    assert SimSettings().key() == _compiled(SimSettings()).key()


def _both_engines(kit: HandKit, obj, hyps, i: int, s: SimSettings):
    out = []
    for settings in (_fcl(s), _compiled(s)):
        st = ClosingStats()
        base = simulate_base(kit, obj, hyps, i, settings, st)
        g = simulate_thumb(kit, obj, base, settings, ClosingStats())
        out.append((base.T_object_palm, g.q, tuple(st.events), g.events, st.queries))
    return out


def test_compiled_engine_matches_fcl_on_the_analytic_cylinder() -> None:
    obj, hyps = AnalyticCylinder(), can_hypotheses()
    kit = HandKit(build_hand(0, 45))
    for i in (0, 57, 140, 211, 305):
        (T_f, q_f, ev_f, th_f, n_f), (T_c, q_c, ev_c, th_c, n_c) = _both_engines(
            kit, obj, hyps, i, SimSettings()
        )
        assert n_c > 0 and n_f > 0
        assert ev_c == ev_f and th_c == th_f  # same stage events, thumb included
        assert np.abs(T_c - T_f).max() < 1e-3  # approach stop, mm
        assert np.abs(q_c - q_f).max() < 1e-3  # rad


@pytest.mark.parametrize(
    "key", ["small_marker", "plastic_pear", "washer", "chips_can", "coffee_can", "power_drill"]
)
def test_compiled_engine_matches_fcl_on_shipped_objects(key: str) -> None:
    from app.model.objects import load_object
    from app.sim.hypothesis_sets import cached_hypotheses

    obj, hyps = load_object(key), cached_hypotheses(key)
    kit = HandKit(build_hand(30, 75))
    for i in range(3, len(hyps), len(hyps) // 3):
        (T_f, q_f, ev_f, th_f, _), (T_c, q_c, ev_c, th_c, _) = _both_engines(
            kit, obj, hyps, i, SimSettings()
        )
        assert ev_c == ev_f and th_c == th_f, i
        assert np.abs(T_c - T_f).max() < 1e-3
        assert np.abs(q_c - q_f).max() < 1e-3


def test_close_finger_on_both_engines() -> None:
    from app.sim.closing_compiled import object_arrays

    obj = AnalyticCylinder()
    kit = HandKit(build_hand(0, 45))
    T = np.eye(4)
    T[:3, 3] = [-20.0, -60.0, 100.0]  # palm beside the can: the index wraps it
    ch = kit.chains["index"]
    pieces = obj.collision_objects()
    arrays = object_arrays(obj)
    assert arrays is not None
    qs, events = [], []
    for engine in ("fcl", "compiled"):
        settings = ClosingSettings(engine=engine)
        st = ClosingStats()
        obst = Obstacles(list(pieces), len(pieces), arrays=arrays)
        qs.append(close_finger(ch, kit.bodies("index"), T, obst, settings, st))
        events.append(st.events)
    assert any(e.endswith("contact") for e in events[0])  # the finger meets the can
    assert events[0] == events[1]
    assert np.abs(qs[0] - qs[1]).max() < 1e-3


def test_compiled_engine_leaves_meshes_to_fcl() -> None:
    import trimesh

    from app.model.objects.shapes import from_mesh
    from app.sim.closing_compiled import object_arrays

    class MeshTarget:
        pieces = from_mesh(trimesh.creation.box((10.0, 10.0, 10.0))).pieces

    assert object_arrays(MeshTarget()) is None


def test_engine_setting_is_validated() -> None:
    with pytest.raises(SettingsError, match="engine"):
        ClosingSettings(engine="warp")  # type: ignore[arg-type]


def test_engine_enters_the_settings_key_only_when_compiled() -> None:
    s = _fcl(SimSettings())
    compiled = _compiled(s)
    assert compiled.key() != s.key()
    d = s.as_dict()
    del d["closing"]["engine"]  # type: ignore[index]
    from app.hashing import stable_hash
    from app.quality.settings import ENGINE_VERSION

    assert s.key() == stable_hash({"engine_version": ENGINE_VERSION, **d})  # keys as before


# ------------------------------------------------------- imported meshes, compiled engine


def _mesh_can(tmp_path, monkeypatch):
    """A faceted can (like coffee_can) imported as a mesh, its field cached under tmp."""
    import trimesh

    from app.model.objects import import_object

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    path = tmp_path / "mesh_can.stl"
    trimesh.creation.cylinder(radius=50.0, height=140.0, sections=96).export(str(path))
    return import_object(path, like="coffee_can", units="mm", key="mesh_can_test")


def test_mesh_distance_matches_fcl(tmp_path, monkeypatch) -> None:
    """Capsule and box against an imported mesh: the field + GJK distance equals FCL's
    BVH distance where they are apart, and both say 'touching' where they are not."""
    from scipy.spatial.transform import Rotation

    from app.sim import gjk
    from app.sim.closing import pair_distance
    from app.sim.mesh_distance import mesh_distance

    obj = _mesh_can(tmp_path, monkeypatch)
    try:
        pk, piece = obj.mesh_pack(), obj.collision_objects()[0]
        rng = np.random.default_rng(7)
        n_apart = 0
        for k in range(120):
            R = Rotation.from_quat(rng.normal(size=4)).as_matrix()
            t = np.array([0.0, 0.0, 70.0]) + rng.normal(size=3) * [45.0, 45.0, 60.0]
            if k % 2:
                prm, geom, typ = np.array([8.0, 15.0, 0.0]), fcl.Capsule(8.0, 30.0), gjk.CAPSULE
            else:
                prm, geom, typ = np.array([20.0, 10.0, 5.0]), fcl.Box(40.0, 20.0, 10.0), gjk.BOX
            d_fcl = pair_distance(fcl.CollisionObject(geom, fcl.Transform(R, t)), piece)
            d = mesh_distance(typ, prm, R, t, pk, 1e9)
            if d_fcl > 1e-3:
                n_apart += 1
                assert abs(d - d_fcl) < 2e-3, (k, d, d_fcl)
            else:
                assert d <= 1e-3, (k, d, d_fcl)
            # the cheap answer above the threshold is a lower bound of the exact one
            assert mesh_distance(typ, prm, R, t, pk, 0.5) <= d + 1e-9
        assert n_apart > 30
    finally:
        from app.model.objects.model import unregister_object

        unregister_object("mesh_can_test")


def test_compiled_engine_closes_on_imported_meshes(tmp_path, monkeypatch) -> None:
    """An imported mesh closes on the compiled engine (its distance field) like on FCL's BVH:
    the same stage events, and stops within the approach's stop band (it stops where the gap
    is in [tol/2, tol]; the distances differ by FCL's ~1e-4 mm error, which can take one
    more or one fewer step, 0.25 mm at most, and turn the fingers' stops by a fraction of a
    degree)."""
    from app.sim.closing_compiled import object_arrays
    from app.sim.hypothesis_sets import cached_hypotheses
    from app.sim.mesh_distance import MESH

    obj = _mesh_can(tmp_path, monkeypatch)
    try:
        arrays = object_arrays(obj)
        assert arrays is not None and list(arrays.typ) == [MESH]
        hyps = cached_hypotheses("mesh_can_test")
        kit = HandKit(build_hand(30, 75))
        n_same = n = 0
        for i in range(0, len(hyps), 24):
            (T_f, q_f, ev_f, th_f, _), (T_c, q_c, ev_c, th_c, _) = _both_engines(
                kit, obj, hyps, i, SimSettings()
            )
            n += 1
            n_same += ev_c == ev_f and th_c == th_f
            assert np.abs(T_c - T_f).max() <= 0.25 + 1e-6, i
            if ev_c == ev_f and th_c == th_f:
                assert np.abs(q_c - q_f).max() < np.radians(2.0), i
        assert n >= 15 and n_same >= n - 1
    finally:
        from app.model.objects.model import unregister_object

        unregister_object("mesh_can_test")


def test_segment_triangle_distance_is_exact() -> None:
    """The closed-form segment-triangle distance against a dense sampling of both."""
    from app.sim.mesh_distance import segment_triangle_distance

    rng = np.random.default_rng(3)
    u = np.linspace(0.0, 1.0, 61)
    for _ in range(40):
        a, b, c = rng.normal(size=(3, 3)) * 10
        s0, s1 = rng.normal(size=(2, 3)) * 10
        if rng.random() < 0.3:  # some segments through the triangle
            x = a + 0.3 * (b - a) + 0.3 * (c - a)
            s0, s1 = x - (s1 - s0) * 0.5, x + (s1 - s0) * 0.5
        d = segment_triangle_distance(s0, s1, a, b, c)
        ww = np.array([(x, y) for x in u for y in u if x + y <= 1.0])
        tri = a + ww[:, :1] * (b - a) + ww[:, 1:] * (c - a)
        seg = s0 + u[:, None] * (s1 - s0)
        ref = np.sqrt(((seg[:, None, :] - tri[None, :, :]) ** 2).sum(-1)).min()
        assert d <= ref + 1e-9  # never above a sampled pair
        assert ref - d < 0.5  # and within the sampling's resolution


def test_mesh_distance_equals_brute_force(tmp_path, monkeypatch) -> None:
    """Capsules and boxes posed at random near an imported mesh: ``mesh_distance`` (field
    bounds, bucket and sphere culling, closed form) equals the minimum over every triangle
    of GJK's distance to it (the triangle a 3-vertex convex shape) to 1e-7 mm, and above its
    threshold it returns a lower bound."""
    from scipy.spatial.transform import Rotation

    from app.sim import gjk
    from app.sim.mesh_distance import mesh_distance

    obj = _mesh_can(tmp_path, monkeypatch)
    try:
        pk = obj.mesh_pack()
        V, F = np.asarray(obj.mesh.vertices), np.asarray(obj.mesh.faces)
        surf, fi = obj.mesh.sample(60, return_index=True)  # type: ignore[misc]
        normals = obj.mesh.face_normals[fi]
        rng = np.random.default_rng(12)
        eye, zero = np.eye(3), np.zeros(3)
        n_exact = 0
        for k in range(60):
            R = Rotation.from_quat(rng.normal(size=4)).as_matrix()
            if k % 3:
                typ, prm = gjk.CAPSULE, np.array([rng.uniform(4, 9), rng.uniform(5, 25), 0.0])
                reach = prm[0] + prm[1] * abs(normals[k] @ R[:, 2])  # support along n
            else:
                typ, prm = gjk.BOX, rng.uniform(3.0, 15.0, 3)
                reach = float(np.abs(normals[k] @ R) @ prm)  # the box's support along n
            t = surf[k] + normals[k] * (reach + rng.uniform(-1.0, 6.0))
            ref = min(
                gjk.shape_distance(
                    typ,
                    prm,
                    R,
                    t,
                    gjk.POINTS,
                    zero,
                    eye,
                    zero,
                    np.ascontiguousarray(V[f]),
                    0,
                    0,
                    0,
                    3,
                )  # fmt: skip
                for f in F
            )
            d = mesh_distance(typ, prm, R, t, pk, 1e9)
            if ref > 1e-6:  # apart (GJK reports 0 for overlapping shapes)
                n_exact += 1
                assert abs(d - ref) < 1e-7, (k, d, ref)
            else:
                assert d <= 1e-6, (k, d, ref)
            assert mesh_distance(typ, prm, R, t, pk, 1.0) <= d + 1e-9
        assert n_exact >= 40
    finally:
        from app.model.objects.model import unregister_object

        unregister_object("mesh_can_test")
