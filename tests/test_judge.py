"""Judging a simulated grasp: the outcome agrees with force closure and grasp-type checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.model.contact_set import ContactSet
from app.model.hand.model import build_hand
from app.quality.force_closure import evaluate_fc
from app.quality.grasp_type import check_grasp_type
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.sim.simulate import HandKit, simulate_base, simulate_thumb
from tests.utils import AnalyticCylinder, can_hypotheses


@pytest.fixture(scope="module")
def judged():
    obj, hyps = AnalyticCylinder(), can_hypotheses()
    kit, s = HandKit(build_hand(30.0, 75.0)), SimSettings()
    out = []
    for i in range(0, len(hyps), 17):
        b = simulate_base(kit, obj, hyps, i, s)
        g = simulate_thumb(kit, obj, b, s)
        # the same grasp without the thumb's contacts (palm and fingers alone): the sample
        # then holds grasps of both verdicts whatever the hand file
        for gg in (g, dataclasses.replace(g, contacts=b.contacts)):
            out.append((gg, judge(gg, obj, s, 123)))
    return obj, s, out


def test_outcome_is_the_fc_and_type_verdicts(judged) -> None:
    obj, s, out = judged
    for g, o in out:
        fc = evaluate_fc(g.contacts, obj.centroid_object, obj.max_radius, s.fc)
        v = check_grasp_type("CG", g.contacts, g.thumb_n_main_object, obj.spec.grip_axis_object,
                             s.grasp_type)  # fmt: skip
        assert o.is_fc == fc.is_fc
        assert o.is_correct == (fc.is_fc and v.correct)
        assert o.epsilon == pytest.approx(fc.epsilon, nan_ok=True)
        assert ("not force closure" in o.reasons) == (not o.is_fc)
        assert (o.reasons == ()) == o.is_correct
        assert np.array_equal(o.q_final_rad, g.q) and o.n_queries == 123
    # the sample is not degenerate: both FC and non-FC grasps occur
    assert {o.is_fc for _, o in out} == {True, False}


def test_a_failed_approach_is_never_force_closure(judged) -> None:
    obj, s, out = judged
    g = dataclasses.replace(out[0][0], approached=False)
    o = judge(g, obj, s, 0)
    assert not o.is_fc and not o.is_correct and o.epsilon == 0.0
    assert o.reasons == ("the approach never touched the object",)


def test_no_contacts_is_not_force_closure(judged) -> None:
    obj, s, out = judged
    empty = ContactSet(np.zeros((0, 3)), np.zeros((0, 3)), np.empty(0, dtype=object),
                       np.zeros(0, bool))  # fmt: skip
    o = judge(dataclasses.replace(out[0][0], contacts=empty), obj, s, 0)
    assert not o.is_fc and not o.is_correct


def test_a_stricter_friction_never_adds_force_closure(judged) -> None:
    """FC with μ = 0.2 implies FC with μ = 0.4 (the cone only grows with μ)."""
    obj, s, out = judged
    low = dataclasses.replace(s, fc=dataclasses.replace(s.fc, mu=0.2))
    for g, o in out:
        if judge(g, obj, low, 0).is_fc:
            assert o.is_fc
