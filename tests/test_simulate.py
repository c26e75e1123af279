"""Simulating hypotheses: the design-independent base stage, the thumb stage, the kit cache."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.model.design import ThumbDesign
from app.model.hand.model import build_hand
from app.quality.settings import SimSettings
from app.runs.tasks import Task, run_task
from app.sim.simulate import (
    BASE_MCP_DEG,
    HandKit,
    base_kit,
    cached_kit,
    closing_fingers,
    simulate_base,
    simulate_thumb,
)
from tests.utils import AnalyticCylinder, can_hypotheses


def test_closing_fingers_follow_the_grasp_type() -> None:
    assert closing_fingers("PP") == ("thumb", "index")
    assert closing_fingers("CG") == ("thumb", "index", "middle", "ring", "little")


def test_cached_kit_is_one_kit_per_design() -> None:
    a = cached_kit(15.0, 60.0, "ulnar")
    assert cached_kit(15.0, 60.0, "ulnar") is a
    b = cached_kit(15.0, 75.0, "ulnar")
    assert b is not a
    assert (a.hand.design.cmc_deg, a.hand.design.mcp_deg) == (15.0, 60.0)
    assert (b.hand.design.cmc_deg, b.hand.design.mcp_deg) == (15.0, 75.0)


@pytest.mark.parametrize("i", [0, 140, 305])
def test_base_stage_does_not_depend_on_the_mcp_angle(i: int) -> None:
    """Approach, back-off and the long fingers are the same for every MCP design angle."""
    obj, hyps, s = AnalyticCylinder(), can_hypotheses(), SimSettings()
    bases = [simulate_base(HandKit(build_hand(15.0, m)), obj, hyps, i, s) for m in (0.0, 90.0)]
    a, b = bases
    assert a.approached == b.approached
    assert np.allclose(a.T_object_palm, b.T_object_palm, atol=1e-9)
    assert np.allclose(a.q[3:], b.q[3:], atol=1e-9)  # long fingers
    assert np.allclose(a.q[:3], 0.0) and np.allclose(b.q[:3], 0.0)  # thumb still open


def test_pulp_pinch_moves_only_the_thumb_and_index() -> None:
    obj = AnalyticCylinder(radius=8.0, height=120.0, grasp_type="PP")
    hyps = can_hypotheses(target=(8.0, 0, 60.0), n_rays=8)
    kit, s = HandKit(build_hand(0.0, 45.0)), SimSettings()
    moved_index = False
    for i in range(0, len(hyps), 11):
        g = simulate_thumb(kit, obj, simulate_base(kit, obj, hyps, i, s), s)
        assert np.allclose(g.q[6:], kit.q_open[6:])  # middle, ring, little never close
        moved_index |= bool(np.any(g.q[3:6] > kit.q_open[3:6]))
    assert moved_index


@pytest.mark.parametrize("cmc", [0.0, 30.0])
def test_thumb_cmc_stage_shared_across_mcp_designs_changes_nothing(cmc: float) -> None:
    """With MCP and IP open the thumb's capsules lie on the metacarpal's line, so the CMC
    stage is the same for every MCP design angle: a base shared by designs (its memo of the
    CMC stage reused) gives the grasps each design gets on a fresh base."""
    obj, hyps = AnalyticCylinder(), can_hypotheses()
    s = SimSettings()
    kits = [HandKit(build_hand(cmc, m)) for m in (0.0, 45.0, 90.0)]
    for i in (0, 140, 305):
        shared = simulate_base(kits[0], obj, hyps, i, s)
        for kit in kits:
            fresh = simulate_thumb(kit, obj, simulate_base(kit, obj, hyps, i, s), s)
            reused = simulate_thumb(kit, obj, shared, s)
            assert np.allclose(fresh.q, reused.q, atol=1e-9), (cmc, i)
            assert fresh.events == reused.events
        assert "thumb" in shared.thumb_first_stage  # the memo was used


def test_base_kit_is_one_kit_per_cmc_angle() -> None:
    k = base_kit(ThumbDesign(30.0, 75.0))
    assert k is base_kit(ThumbDesign(30.0, 15.0))
    assert (k.hand.design.cmc_deg, k.hand.design.mcp_deg) == (30.0, BASE_MCP_DEG)


def test_outcomes_do_not_depend_on_the_designs_sharing_a_task() -> None:
    """A design's outcomes are the same whether it is simulated alone or after other designs
    with the same CMC angle (a sweep's task grouping, the explorer's single design)."""
    s = SimSettings()
    d = ThumbDesign(15.0, 60.0)
    gh = (0, 101, 333, 700)
    alone = run_task(Task("washer", gh, (d,), s))
    grouped = run_task(Task("washer", gh, (ThumbDesign(15.0, 90.0), d), s))
    mine = [(gid, o) for di, gid, o in grouped if di == 1]
    assert [gid for _, gid, _ in alone] == [gid for gid, _ in mine]
    for (_, _, a), (_, b) in zip(alone, mine, strict=True):
        # the query count is bookkeeping: a reused CMC-stage memo spends fewer queries
        assert a.same_as(dataclasses.replace(b, n_queries=a.n_queries))


def test_warm_runs_the_compiled_engine(monkeypatch: pytest.MonkeyPatch) -> None:
    """``python -m app.sim.warm`` (run by ``make setup``) simulates a touching hypothesis on
    the compiled engine: the closing and contact kernels are called (and so cached)."""
    from app.sim import closing_compiled, contacts_compiled
    from app.sim.warm import warm

    calls: list[str] = []
    for mod, name in ((closing_compiled, "advance_stage_compiled"),
                      (contacts_compiled, "contacts_compiled")):  # fmt: skip
        orig = getattr(mod, name)

        def spy(*a: object, _orig: object = orig, _name: str = name, **k: object) -> object:
            calls.append(_name)
            return _orig(*a, **k)  # type: ignore[operator]

        monkeypatch.setattr(mod, name, spy)
    assert warm("washer") > 0
    assert "advance_stage_compiled" in calls and "contacts_compiled" in calls
