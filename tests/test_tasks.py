"""Planning tasks: every missing hypothesis once, chunked, optionally in a seeded random order."""

from __future__ import annotations

from pathlib import Path

from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.executors import InlineExecutor
from app.runs.store import ResultStore
from app.runs.sweep import run_sweep
from app.runs.tasks import plan_tasks
from app.sim.hypothesis_sets import cached_hypotheses

D = (ThumbDesign(0.0, 45.0),)


def _ghs(tasks) -> list[int]:
    return [i for t in tasks for i in t.gh]


def test_tasks_cover_every_hypothesis_once(tmp_path: Path) -> None:
    n = len(cached_hypotheses("washer"))
    with ResultStore(tmp_path / "s.sqlite") as store:
        plain = plan_tasks(store, D, ["washer"], SimSettings(), chunk=50)
        shuffled = plan_tasks(store, D, ["washer"], SimSettings(), chunk=50, shuffle_seed=0)
    assert _ghs(plain) == list(range(n))
    assert sorted(_ghs(shuffled)) == list(range(n))
    assert all(len(t.gh) <= 50 for t in shuffled)


def test_the_shuffled_order_is_seeded_and_spread(tmp_path: Path) -> None:
    with ResultStore(tmp_path / "s.sqlite") as store:
        a = _ghs(plan_tasks(store, D, ["washer"], SimSettings(), chunk=50, shuffle_seed=0))
        b = _ghs(plan_tasks(store, D, ["washer"], SimSettings(), chunk=50, shuffle_seed=0))
        c = _ghs(plan_tasks(store, D, ["washer"], SimSettings(), chunk=50, shuffle_seed=1))
    assert a == b and a != c
    # the first task samples the whole object, not one ray's block of hypotheses
    first = sorted(a[:50])
    assert first[-1] - first[0] > 500


def test_order_does_not_change_scores(tmp_path: Path) -> None:
    """The same design and subset, computed in run order and in a shuffled order."""
    kw = {"settings": SimSettings(), "executor": InlineExecutor(), "progress": False,
          "gh_stride": 40}  # fmt: skip
    with ResultStore(tmp_path / "a.sqlite") as sa, ResultStore(tmp_path / "b.sqlite") as sb:
        ra = run_sweep(list(D), ["washer"], store=sa, **kw)
        rb = run_sweep(list(D), ["washer"], store=sb, shuffle_seed=3, **kw)
    assert ra is not None and rb is not None
    assert ra.scores[0].objects == rb.scores[0].objects


def test_first_sample_is_the_prefix_of_the_seeded_order(tmp_path: Path) -> None:
    """``first_n``: the first n hypotheses of each object's seeded order, so a first sample
    followed by the rest is one random order (the union stays a simple random sample)."""
    with ResultStore(tmp_path / "r.sqlite") as store:
        objs = ["washer", "chips_can"]
        full = plan_tasks(store, D, objs, SimSettings(), chunk=7, shuffle_seed=0)
        first = plan_tasks(store, D, objs, SimSettings(), chunk=24, shuffle_seed=0, first_n=24)
    assert [t.object_name for t in first] == objs  # one task per object
    for t in first:
        order = [i for u in full if u.object_name == t.object_name for i in u.gh]
        assert list(t.gh) == order[:24]


def test_many_designs_are_batched_by_cmc_angle(tmp_path: Path) -> None:
    """The 5° map's 190 designs: tasks of at most MAX_DESIGNS_PER_TASK designs (a worker's kit
    cache holds them), every (design, hypothesis) once, a CMC angle's designs together where
    they fit."""
    from app.runs.tasks import MAX_DESIGNS_PER_TASK, design_batches

    designs = [ThumbDesign(float(c), float(m)) for c in range(0, 50, 5) for m in range(0, 95, 5)]
    batches = design_batches(designs)
    key = lambda d: (d.cmc_deg, d.mcp_deg)  # noqa: E731
    assert sorted(map(key, (d for b in batches for d in b))) == sorted(map(key, designs))
    assert all(len(b) <= MAX_DESIGNS_PER_TASK for b in batches)
    by_cmc = {c: {i for i, b in enumerate(batches) for d in b if d.cmc_deg == c} for c in
              {d.cmc_deg for d in designs}}  # fmt: skip
    assert all(len(v) == 1 for v in by_cmc.values())  # 19 designs per angle: never split
    big = [ThumbDesign(10.0, float(m)) for m in range(91)]  # one angle, more than fits
    assert [len(b) for b in design_batches(big)] == [48, 43]
    with ResultStore(tmp_path / "s.sqlite") as store:
        tasks = plan_tasks(store, designs, ["washer"], SimSettings(), chunk=100)
    pairs = [(d, i) for t in tasks for d in t.designs for i in t.gh]
    assert len(pairs) == len(set(pairs)) == len(designs) * len(cached_hypotheses("washer"))
