"""Brute-force grasp hypotheses (METHOD §3b): grid, ray casting, counts, ids, store keys; the
brute-force comparison (METHOD §6): planning, simulation and GQM scoring, resumable."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
import trimesh

from app.errors import StoreError
from app.model.design import ThumbDesign
from app.model.hand.model import build_hand
from app.model.objects import OBJECT_KEYS, load_object
from app.quality.gqm import GQM_NAMES, GQMSettings
from app.quality.settings import SimSettings
from app.reports.table3 import write_comparison
from app.runs import gqm_compare as compare
from app.runs.executors import InlineExecutor
from app.runs.gqm_compare import run_comparison, simulate_bf
from app.runs.keys import design_key, object_key, set_object_key
from app.runs.store import ResultStore
from app.runs.tasks import Task, plan_tasks, run_task
from app.sim.bruteforce import (
    BF_HAND_VECTOR_PALM,
    BruteForceSettings,
    brute_force_hypotheses,
    cast_box_rays,
    face_grid,
    first_hits,
)
from app.sim.hypothesis_sets import hypotheses_of
from app.sim.simulate import cached_kit

ID_RE = re.compile(r"^[a-z_]+/bf/f[0-5]/i\d{2}j\d{2}/d[01]/t[0-4]$")


def test_face_grid_spacing_and_centre() -> None:
    lo, hi = np.array([-47.5, -10.0, 0.0]), np.array([47.5, 10.0, 270.0])
    for face in range(6):
        pts, ij = face_grid(lo, hi, face, 20.0)
        axis = face // 2
        assert np.allclose(pts[:, axis], hi[axis] if face % 2 == 0 else lo[axis])
        centre = 0.5 * (lo + hi)
        for a in (a for a in range(3) if a != axis):
            ticks = np.unique(pts[:, a])
            assert np.allclose(np.diff(ticks), 20.0)  # spacing d
            assert np.any(np.isclose(ticks, centre[a]))  # symmetric, holds the centre
            assert ticks.min() >= lo[a] - 1e-9 and ticks.max() <= hi[a] + 1e-9
            assert ticks.min() - 20.0 < lo[a]  # as many as fit
        assert len(np.unique(ij, axis=0)) == len(pts)


def test_first_hits_single_triangle() -> None:
    tri = np.array([[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]]])
    o = np.array([[1.0, 1.0, 5.0], [20.0, 20.0, 5.0], [1.0, -5.0, 0.0]])
    d = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    k, t = first_hits(o, d, tri, min_cos=0.1)
    assert k.tolist() == [0, -1, -1]  # hit, miss, grazing (in the triangle's plane)
    assert t[0] == pytest.approx(5.0)


def test_sphere_hits_and_misses() -> None:
    """A sphere r = 30: the grown box is ±40, grid {0, ±20, ±40}²; a ray hits iff a² + b² < r²."""
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=30.0)
    rays = cast_box_rays(mesh)
    assert rays.n_cast == 6 * 25
    assert len(rays.hit_object) == 6 * 9  # (0,0), (±20,0), (0,±20), (±20,±20)
    assert np.allclose(np.linalg.norm(rays.hit_object, axis=1), 30.0, atol=0.1)
    radial = rays.hit_object / np.linalg.norm(rays.hit_object, axis=1, keepdims=True)
    assert np.all(np.sum(radial * rays.normal_object, axis=1) > 0.99)  # outward


@pytest.mark.parametrize("key", OBJECT_KEYS)
def test_hypotheses_of_shipped_objects(key: str) -> None:
    obj = load_object(key)
    h = brute_force_hypotheses(obj)
    n_hits = len(h.hit_object)
    assert 0 < n_hits <= h.n_cast
    assert len(h) == n_hits * 2 * 5  # standoffs {0, 25} × rolls {0, π/2, π, 3π/2, 2π}
    assert len(set(h.ids)) == len(h) and all(ID_RE.match(i) for i in h.ids)
    # every hit on the surface
    assert np.max(np.abs(obj.sdf(h.hit_object))) < 0.5
    # approach = −normal: the palm normal (hand vector) points along −ray
    n_palm = np.einsum("nij,j->ni", h.R_object_palm, BF_HAND_VECTOR_PALM)
    assert np.allclose(n_palm, -h.ray_object, atol=1e-9)
    assert np.allclose(np.linalg.norm(h.ray_object, axis=1), 1.0)
    # the normal is outward: agrees with the SDF gradient away from edges
    cos = np.sum(obj.normal(h.hit_object) * h.ray_object[:: 2 * 5], axis=1)
    assert np.median(cos) > 0.99 and np.all(cos > 0.0)
    assert set(np.round(h.standoff_mm, 9)) == {0.0, 25.0}
    assert np.allclose(np.unique(h.roll_rad), [0, np.pi / 2, np.pi, 3 * np.pi / 2, 2 * np.pi])
    # the approach line of GH i goes through its own hit
    i = len(h) - 1
    line = h.approach_line(i)
    assert np.allclose(line.target_object, h.hit_object[h.ray_index[i]])


def test_rolls_turn_about_the_approach_and_duplicate_flag() -> None:
    obj = load_object("chips_can")
    h = brute_force_hypotheses(obj)
    R0, R4 = h.R_object_palm[0], h.R_object_palm[4]  # roll 0 and 2π of ray 0
    assert np.allclose(R0, R4, atol=1e-9)
    nodup = brute_force_hypotheses(obj, BruteForceSettings(drop_duplicate_roll=True))
    assert len(nodup) == len(nodup.hit_object) * 2 * 4
    assert set(nodup.ids) < set(h.ids)  # same ids minus t4: the store rows are shared


def test_store_keys_distinct() -> None:
    okey = object_key("washer")
    assert set_object_key("washer") == okey
    assert set_object_key("washer", "brute_force") == okey + ":bf"
    assert set_object_key("washer", "brute_force_nodup") == okey + ":bf"
    assert len(hypotheses_of("washer", "brute_force")) == len(
        brute_force_hypotheses(load_object("washer"))
    )


def test_run_task_closes_all_fingers_and_keeps_pose() -> None:
    h = hypotheses_of("small_marker", "brute_force")
    gh = (0, 11)
    design = ThumbDesign(0, 45)
    res = run_task(Task("small_marker", gh, (design,), SimSettings(), "brute_force"))
    assert [r[1] for r in res] == [h.ids[i] for i in gh]
    q_open = build_hand(0, 45).q_open
    for (_, _, o), i in zip(res, gh, strict=True):
        T = np.asarray(o.extra["T_object_palm"])
        assert np.allclose(T[:3, :3], h.R_object_palm[i]) and np.allclose(T[3], [0, 0, 0, 1])
        # P lies on the approach line hit + s·ray
        P = T[:3, :3] @ np.array([10.0, 70.0, 0.0]) + T[:3, 3]
        off = P - h.hit_object[h.ray_index[i]]
        assert np.linalg.norm(np.cross(off, h.ray_object[i])) < 1e-6
        # a PP object, yet middle, ring and little closed too (all fingers close)
        assert np.all((o.q_final_rad[6:] - q_open[6:]).reshape(3, 3).max(axis=1) > 0.1)


# ----------------------------------------------------------------------------- planning
def test_plan_tasks_hypothesis_set(tmp_path) -> None:
    """The benchmark's plan is unchanged by default; a brute-force plan covers that set."""
    designs = [ThumbDesign(0, 45), ThumbDesign(15, 60)]
    s = SimSettings()
    with ResultStore(tmp_path / "r.sqlite") as store:
        anthro = plan_tasks(store, designs, ["washer"], s)
        n_anthro = len(hypotheses_of("washer"))
        assert sum(len(t.gh) for t in anthro) == n_anthro
        assert {t.hypothesis_set for t in anthro} == {"anthropomorphic"}
        assert all(t.designs == tuple(designs) for t in anthro)
        bf = plan_tasks(store, designs, ["washer"], s, chunk=7, hypothesis_set="brute_force")
        h = hypotheses_of("washer", "brute_force")
        assert sorted(i for t in bf for i in t.gh) == list(range(len(h)))
        assert {t.hypothesis_set for t in bf} == {"brute_force"} and max(len(t.gh) for t in bf) == 7
        # a stored brute-force outcome is planned no more, for that design only; the
        # benchmark's plan does not see it (another object key)
        o = run_task(Task("washer", (0,), (designs[0],), s, "brute_force"))[0][2]
        store.put_many(design_key(designs[0]), set_object_key("washer", "brute_force"), s.key(),
                       {h.ids[0]: o})  # fmt: skip
        bf2 = plan_tasks(store, designs, ["washer"], s, chunk=7, hypothesis_set="brute_force")
        assert [t.designs for t in bf2 if 0 in t.gh] == [(designs[1],)]
        assert sum(len(t.gh) * len(t.designs) for t in bf2) == 2 * len(h) - 1
        assert plan_tasks(store, designs, ["washer"], s) == anthro


# ----------------------------------------------------------------------------- comparison
DESIGN = ThumbDesign(0, 45)


@pytest.fixture(scope="module")
def bf_store(tmp_path_factory) -> Path:
    """A throwaway store with the washer's brute-force outcomes (40 GHs) for DESIGN."""
    path = tmp_path_factory.mktemp("bf") / "r.sqlite"
    with ResultStore(path) as store:
        n = simulate_bf(
            [DESIGN], ["washer"], store, SimSettings(), InlineExecutor(), progress=False
        )
    assert n == len(hypotheses_of("washer", "brute_force"))
    return path


def test_simulate_bf_stores_outcomes_and_resumes(bf_store: Path, tmp_path) -> None:
    s = SimSettings()
    h = hypotheses_of("washer", "brute_force")
    store_copy = tmp_path / "r.sqlite"
    with ResultStore(bf_store, readonly=True) as src:
        okey = set_object_key("washer", "brute_force")
        got = src.get_many(design_key(DESIGN), okey, s.key(), h.ids)
        assert set(got) == set(h.ids)  # every brute-force GH, under the ':bf' key
        assert src.count(design_key(DESIGN), object_key("washer"), s.key()) == 0
        assert dict(src.objects())[okey] == {"key": "washer", "hypothesis_set": "brute_force"}
        for gh, o in got.items():
            T = np.asarray(o.extra["T_object_palm"])
            assert T.shape == (4, 4)
            assert np.allclose(T[:3, :3], h.R_object_palm[h.ids.index(gh)])
            assert o.is_correct <= o.is_fc
        assert any(o.is_fc for o in got.values())
        with ResultStore(store_copy) as dst:  # a second store: the rerun must not simulate
            dst.put_many(design_key(DESIGN), okey, s.key(), got)
            again = simulate_bf([DESIGN], ["washer"], dst, s, InlineExecutor(), progress=False)
            assert again == 0
            assert dst.count(design_key(DESIGN), okey, s.key()) == len(h)


def test_store_gqms_roundtrip(tmp_path) -> None:
    vals = {
        "a/1": {"Q_A1": 0.1 + 0.2, "Q_C1": 1e-300, "Q_C2": float("nan")},
        "a/2": {"Q_A1": -0.0, "Q_C1": float("inf"), "Q_C2": 1 / 3},
    }
    path = tmp_path / "r.sqlite"
    with ResultStore(path) as store:
        assert store.get_gqms("d", "o", "s", "g", ["a/1"]) == {} and store.count_gqms() == 0
    with ResultStore(path, readonly=True) as ro:  # a store without the table: no GQMs
        assert ro.get_gqms("d", "o", "s", "g", ["a/1"]) == {} and ro.count_gqms() == 0
        with pytest.raises(StoreError):
            ro.put_gqms("d", "o", "s", "g", vals)
    with ResultStore(path) as store:
        store.put_gqms("d", "o", "s", "g", vals)
        store.put_gqms("d", "o", "s", "g2", {"a/1": {"Q_A1": 2.0}})
        got = store.get_gqms("d", "o", "s", "g", ["a/1", "a/2", "a/3"])
        assert store.count_gqms() == 3 and store.count_gqms("g") == 2
    assert set(got) == {"a/1", "a/2"}
    for gh, v in vals.items():
        assert list(got[gh]) == list(v)  # names in order
        for k, x in v.items():
            y = got[gh][k]
            assert (math.isnan(x) and math.isnan(y)) or (
                x == y and math.copysign(1, x) == math.copysign(1, y)
            )


def _copy_store(src: Path, dst: Path) -> None:
    with ResultStore(src, readonly=True) as a, ResultStore(dst) as b:
        s = SimSettings()
        okey = set_object_key("washer", "brute_force")
        ids = hypotheses_of("washer", "brute_force").ids
        b.put_many(
            design_key(DESIGN), okey, s.key(), a.get_many(design_key(DESIGN), okey, s.key(), ids)
        )


@pytest.mark.pool
def test_run_comparison_resumes_gqms(bf_store: Path, tmp_path, monkeypatch) -> None:
    """A rerun reads every GQM from the store (0 computed) and finds the same values."""
    store_path = tmp_path / "r.sqlite"
    _copy_store(bf_store, store_path)
    monkeypatch.setattr(compare, "GQM_CHUNK", 1)  # three jobs: the first run uses the pool

    def run(out: str, **kw) -> compare.ComparisonResult:
        res = run_comparison(
            [DESIGN], ["washer"], store, executor=InlineExecutor(),
            max_grasps=3, progress=False, **kw,
        )  # fmt: skip
        write_comparison(res, [DESIGN], tmp_path / out, picture=False)
        return res

    with ResultStore(store_path) as store:
        first = run("a", workers=2)
        second = run("b")
        assert store.count_gqms(GQMSettings().key()) == 3
        # other GQM settings are another key: computed again, not mixed up
        link = run("c", gqm=GQMSettings(wrench_contacts="link"))
    assert first.simulated == 0 and first.gqm_computed == len(first.scored) == 3
    assert second.simulated == 0 and second.gqm_computed == 0
    assert [(s.gh_id, s.values) for s in first.scored] == [
        (s.gh_id, s.values) for s in second.scored
    ]
    assert all(tuple(s.values) == GQM_NAMES for s in second.scored)
    assert link.gqm_computed == 3
    for name in ("bruteforce_table.csv", "bruteforce_gqms.csv", "bruteforce_wins.csv"):
        assert (tmp_path / "a" / name).read_text() == (tmp_path / "b" / name).read_text()


class _Stop(Exception):
    pass


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.pool)])
def test_interrupted_scoring_keeps_finished_jobs(
    bf_store: Path, tmp_path, monkeypatch, workers: int
) -> None:
    """Jobs finished before an interruption are stored; the rerun computes only the rest."""
    store_path = tmp_path / "r.sqlite"
    _copy_store(bf_store, store_path)
    monkeypatch.setattr(compare, "GQM_CHUNK", 1)  # one job per grasp
    s = SimSettings()
    with ResultStore(store_path) as store:
        drawn = {("washer", DESIGN): compare.draw_fc(store, "washer", DESIGN, s, 3, 0)}

        def stop(n: int) -> None:
            raise _Stop

        with pytest.raises(_Stop):
            compare.score_grasps(drawn, None, workers, stop, store, s)
        assert store.count_gqms() == 1  # the first job landed before the interruption
        run = compare.score_grasps(drawn, None, 1, None, store, s)
    assert run.computed == 2 and len(run.scored) == 3
    fresh = compare.score_grasps(drawn)  # no store: everything computed, same values
    assert fresh.computed == 3
    assert [x.values for x in fresh.scored] == [x.values for x in run.scored]


def test_gqms_of_simulated_grasps_wrench_measures(bf_store: Path) -> None:
    """On simulated washer grasps: Q_C1 is the ε of the full hull of every patch point's
    primitive wrenches (1e-9 relative), Q_C2 the volume of the per-link contacts' hull."""
    from app.quality.force_closure import primitive_wrenches
    from app.quality.gqm import compute_gqms
    from app.quality.gqm.contacts import link_contacts
    from app.quality.gqm.wrench_space import wrench_hull

    s = SimSettings()
    obj = load_object("washer")
    hand = cached_kit(DESIGN.cmc_deg, DESIGN.mcp_deg, DESIGN.cmc_tilt).hand
    c, r = np.asarray(obj.centroid_object, float), float(obj.max_radius)
    with ResultStore(bf_store, readonly=True) as store:
        drawn = compare.draw_fc(store, "washer", DESIGN, s, 4, 0)
    assert drawn
    for _, o in drawn:
        cs = o.contacts
        pose = compare._Pose(o.q_final_rad, np.asarray(o.extra["T_object_palm"], float), cs)
        vals = compute_gqms(pose, obj, hand)  # type: ignore[arg-type]
        patch = wrench_hull(primitive_wrenches(cs.p_object, cs.n_object, c, r))
        lc = link_contacts(cs)
        link = wrench_hull(primitive_wrenches(lc.p, lc.n, c, r))
        assert vals["Q_C1"] == pytest.approx(max(patch.epsilon, 0.0), rel=1e-9, abs=1e-15)
        assert vals["Q_C2"] == link.volume
        assert len(link.W) < len(patch.W)
