"""Replays: the frames end in exactly the benchmark's grasp, and move without jumps."""

from __future__ import annotations

import numpy as np
import pytest

from app.model.hand.model import build_hand
from app.quality.settings import SimSettings
from app.sim.replay import replay
from app.sim.simulate import HandKit, simulate_base, simulate_thumb
from tests.utils import AnalyticCylinder, can_hypotheses


@pytest.mark.parametrize("i", [0, 57, 305])
def test_replay_ends_in_the_scored_grasp(i: int) -> None:
    obj, hyps, s = AnalyticCylinder(), can_hypotheses(), SimSettings()
    kit = HandKit(build_hand(15.0, 60.0))
    r = replay(kit, obj, hyps, i, s, frames_per_stage=6)
    g = simulate_thumb(kit, obj, simulate_base(kit, obj, hyps, i, s), s)
    assert np.array_equal(r.grasp.q, g.q)
    assert np.array_equal(r.frames[-1].q, g.q)
    assert np.allclose(r.frames[-1].T_object_palm, g.T_object_palm)
    assert r.frames[-1].label == "final grasp"
    assert r.frames[0].label == "approach"
    assert np.array_equal(r.frames[0].q, kit.q_open)


def test_replay_frames_are_continuous() -> None:
    """Within a stage, consecutive frames move each joint by at most its stage span / (n-1)."""
    obj, hyps, s = AnalyticCylinder(), can_hypotheses(), SimSettings()
    kit = HandKit(build_hand(0.0, 45.0))
    n = 8
    r = replay(kit, obj, hyps, 140, s, frames_per_stage=n)
    closing = [f for f in r.frames if "closing" in f.label]
    assert closing, "no closing stage recorded"
    span = np.ptp(np.stack([f.q for f in r.frames]), axis=0).max()
    for a, b in zip(closing, closing[1:], strict=False):
        if a.label == b.label:
            assert np.abs(b.q - a.q).max() <= span / (n - 1) + 1e-9
    # joints only close during the replay: never beyond their final value
    q_final = r.frames[-1].q
    for f in r.frames:
        assert np.all(f.q <= q_final + 1e-9)
