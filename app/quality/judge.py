"""Judge a simulated grasp: force closure and grasp-type correctness -> a stored outcome."""

from __future__ import annotations

import numpy as np

from app.model.target import GraspTarget
from app.quality.force_closure import evaluate_fc
from app.quality.grasp_type import check_grasp_type
from app.quality.outcome import GraspOutcome
from app.quality.settings import SimSettings
from app.sim.simulate import Grasp


def judge(grasp: Grasp, obj: GraspTarget, settings: SimSettings, queries: int) -> GraspOutcome:
    """FC (qhull, strict interior) and, among FC grasps, PP/CG correctness (METHOD §5)."""
    spec = obj.spec
    if not grasp.approached:
        return GraspOutcome(
            q_final_rad=grasp.q,
            contacts=grasp.contacts,
            is_fc=False,
            is_correct=False,
            epsilon=0.0,
            reasons=("the approach never touched the object",),
            n_queries=queries,
        )
    fc = evaluate_fc(
        grasp.contacts,
        obj.centroid_object,
        obj.max_radius,
        settings.fc,
    )
    verdict = check_grasp_type(
        spec.grasp_type,
        grasp.contacts,
        grasp.thumb_n_main_object,
        spec.grip_axis_object,
        settings.grasp_type,
    )
    reasons = tuple(verdict.reasons)
    if not fc.is_fc:
        reasons = ("not force closure",) + reasons
    return GraspOutcome(
        q_final_rad=np.asarray(grasp.q, float),
        contacts=grasp.contacts,
        is_fc=bool(fc.is_fc),
        is_correct=bool(fc.is_fc and verdict.correct),
        epsilon=float(fc.epsilon),
        reasons=reasons,
        n_queries=queries,
    )
