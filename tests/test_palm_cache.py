"""The palm stage (thumbless approach, back-off, long fingers) is design-independent, the
base stage built on it equals one computed from scratch, and the disk cache returns it bit
for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.settings import SimSettings
from app.runs import palm_cache
from app.runs.tasks import Task, run_task
from app.sim.closing import ClosingStats
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import (
    BaseGrasp,
    PalmGrasp,
    _approach_links,
    cached_kit,
    simulate_base,
    simulate_palm,
)

S = SimSettings()


def same_palm(a: PalmGrasp, b: PalmGrasp) -> bool:
    """Bit-for-bit equality, dtypes included."""
    ca, cb = a.contacts, b.contacts

    def eq(x: np.ndarray, y: np.ndarray) -> bool:
        return x.dtype == y.dtype and x.shape == y.shape and bool(np.array_equal(x, y))

    return (
        a.start_mm == b.start_mm
        and (a.s_mm == b.s_mm or (math.isnan(a.s_mm) and math.isnan(b.s_mm)))
        and eq(a.T_object_palm, b.T_object_palm)
        and eq(a.q, b.q)
        and eq(ca.p_object, cb.p_object)
        and eq(ca.n_object, cb.n_object)
        and ca.link.dtype == cb.link.dtype
        and [str(x) for x in ca.link] == [str(x) for x in cb.link]
        and eq(ca.palmar, cb.palmar)
        and a.queries == b.queries
    )


def same_base(a: BaseGrasp, b: BaseGrasp) -> bool:
    return (
        a.approached == b.approached
        and np.array_equal(a.T_object_palm, b.T_object_palm)
        and np.array_equal(a.q, b.q)
        and np.array_equal(a.contacts.p_object, b.contacts.p_object)
        and a.queries == b.queries
    )


@pytest.mark.parametrize("key", ["plastic_pear", "washer"])
def test_palm_stage_does_not_depend_on_the_thumb_design(key: str) -> None:
    obj, hyps = load_object(key), cached_hypotheses(key)
    kits = [cached_kit(0.0, 0.0, "ulnar"), cached_kit(45.0, 90.0, "radial")]
    for i in range(0, len(hyps), max(1, len(hyps) // 6)):
        a, b = (simulate_palm(k, obj, hyps, i, S) for k in kits)
        assert same_palm(a, b), (key, i)


def test_base_on_a_given_palm_equals_base_from_scratch() -> None:
    """Including hypotheses where the open thumb touches first (the drill at CMC 0°: the long
    fingers close again from the thumb's stop, which is later on the ray than the palm's)."""
    obj, hyps = load_object("power_drill"), cached_hypotheses("power_drill")
    kit = cached_kit(0.0, 0.0, "ulnar")
    thumb_first = 0
    for i in range(0, 150, 5):
        palm = simulate_palm(kit, obj, hyps, i, S)
        given = simulate_base(kit, obj, hyps, i, S, palm=palm)
        assert same_base(given, simulate_base(kit, obj, hyps, i, S)), i
        s_thumb = _approach_links(
            kit, obj, hyps, i, kit.thumb_links, palm.start_mm, S.closing, ClosingStats()
        )
        if not math.isnan(s_thumb) and (math.isnan(palm.s_mm) or s_thumb > palm.s_mm):
            thumb_first += 1
            # the approach stopped at the thumb's first contact, then backed off
            ray, R = hyps.ray_object[i], hyps.R_object_palm[i]
            P = hyps.target_object + (s_thumb + hyps.standoff_mm[i]) * ray
            assert np.allclose(given.T_object_palm[:3, 3] + R @ kit.hand.approach_point_palm, P)
            assert not np.array_equal(given.T_object_palm, palm.T_object_palm)
        elif given.approached:
            assert np.array_equal(given.T_object_palm, palm.T_object_palm)
            assert np.array_equal(given.q, palm.q)
    assert thumb_first > 0  # the case is exercised


def test_disk_cache_round_trip_is_exact(tmp_path, monkeypatch) -> None:  # noqa: ANN001
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    palm_cache.clear_tables()
    n = 6
    table = palm_cache.PalmTable("power_drill", S, n)
    rows = [table.get(i) for i in range(n)]
    assert table.complete and table.save()
    assert table.path().parent == tmp_path / "handbench" / "palms"
    again = palm_cache.PalmTable("power_drill", S, n)
    assert again.load() and again.from_disk
    for i in range(n):
        assert same_palm(again.get(i), rows[i]), i
    # a file of another hypothesis count, or a corrupt one, is ignored
    assert not palm_cache.PalmTable("power_drill", S, n + 1).load()
    table.path().write_bytes(b"not an npz")
    assert not palm_cache.PalmTable("power_drill", S, n).load()


def test_tasks_give_the_same_outcomes_with_a_cached_palm_table(tmp_path, monkeypatch) -> None:  # noqa: ANN001
    """A task served from a cached (disk) table scores exactly as one that computes."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    palm_cache.clear_tables()
    designs = (ThumbDesign(0.0, 45.0), ThumbDesign(30.0, 75.0))
    task = Task("power_drill", tuple(range(0, 60, 6)), designs, S)
    computed = run_task(task)
    table = palm_cache.palm_table("power_drill", S)
    assert not table.from_disk
    for i in range(len(table)):  # complete the table cheaply: only the task's rows matter
        if table._rows[i] is None:
            table._rows[i] = table._rows[0]
    assert table.save()
    palm_cache.clear_tables()
    assert palm_cache.palm_table("power_drill", S).from_disk
    cached = run_task(task)
    assert [(d, g) for d, g, _ in cached] == [(d, g) for d, g, _ in computed]
    for (_, gid, a), (_, _, b) in zip(cached, computed, strict=True):
        assert a.same_as(b), gid
    palm_cache.clear_tables()


def test_palm_key_changes_with_the_settings() -> None:
    import dataclasses

    other = dataclasses.replace(S, contact=dataclasses.replace(S.contact, contact_tol_mm=0.7))
    assert palm_cache.palm_key("washer", S) != palm_cache.palm_key("washer", other)
    assert palm_cache.palm_key("washer", S) != palm_cache.palm_key("chips_can", S)


def test_worker_start_up_loads_the_objects_and_never_fails() -> None:
    """``init_worker`` (the explorer's pool start-up) leaves the object's palm table loaded,
    and an object that cannot load does not break the worker (its tasks report it)."""
    from app.runs.executors import init_worker

    palm_cache.clear_tables()
    init_worker(("washer", "no_such_object"))
    table = palm_cache._TABLES[("washer", S.key())]
    assert any(r is not None for r in table._rows)
    palm_cache.clear_tables()


def test_import_caches_the_palm_table_and_runs_use_it(tmp_path, monkeypatch, capsys) -> None:  # noqa: ANN001
    """``objects import`` computes the imported object's palm table and caches it under the
    built-ins' key (mesh content included); a later process (registry and tables cleared)
    reads it from disk bit for bit equal to freshly computed stages, and its tasks take the
    stages from it (computing one would fail here) with the outcomes of computed ones."""
    import trimesh

    from app.cli.parser import main
    from app.model.objects.model import _load_file_cached, unregister_object
    from app.runs.keys import object_key

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setenv("HANDBENCH_USER_OBJECTS", str(tmp_path / "objects"))
    path = tmp_path / "can_scan.stl"
    trimesh.creation.cylinder(radius=50.0, height=140.0, sections=48).export(str(path))
    key = "can_scan_palm_test"
    palm_cache.clear_tables()
    try:
        assert main(["objects", "import", str(path), "--like", "coffee_can", "--key", key]) == 0
        assert f"palm stages of {key}: 420 hypotheses built" in capsys.readouterr().out
        unregister_object(key)  # as a new process: the saved file, the cached table
        palm_cache.clear_tables()
        table = palm_cache.palm_table(key, S)
        assert table.from_disk and table.complete
        assert table.path().parent == tmp_path / "cache" / "handbench" / "palms"
        obj, hyps = load_object(key), cached_hypotheses(key)
        kit = palm_cache._palm_kit()
        picks = range(0, len(hyps), 35)
        for i in picks:
            assert same_palm(table.get(i), simulate_palm(kit, obj, hyps, i, S)), i
        task = Task(key, tuple(picks), (ThumbDesign(0.0, 45.0),), S)
        monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "empty"))
        palm_cache.clear_tables()
        computed = run_task(task)  # no cached table: the stages are computed
        assert not palm_cache.palm_table(key, S).from_disk
        monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
        palm_cache.clear_tables()

        def no_palm(*a, **k):  # noqa: ANN002, ANN003, ANN202
            raise AssertionError("a palm stage was computed")

        monkeypatch.setattr(palm_cache, "simulate_palm", no_palm)
        monkeypatch.setattr("app.runs.tasks.simulate_palm", no_palm)
        served = run_task(task)  # the cached table serves every stage
        assert len(served) == len(picks) and any(o.is_fc for _, _, o in served)
        for (_, _, a), (_, _, b) in zip(served, computed, strict=True):
            assert a.same_as(b)
        # the mesh is in the key: another mesh under the same name has another table
        other = trimesh.creation.cylinder(radius=50.0, height=141.0, sections=48)
        other.export(str(path))
        assert main(["objects", "import", str(path), "--like", "coffee_can", "--key", key,
                     "--no-palm-stages"]) == 0  # fmt: skip
        unregister_object(key)
        _load_file_cached.cache_clear()  # (a new process would read the new file)
        object_key.cache_clear()
        palm_cache.clear_tables()
        assert not palm_cache.palm_table(key, S).from_disk
    finally:
        unregister_object(key)
        palm_cache.clear_tables()
