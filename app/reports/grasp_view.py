"""Simulate one hypothesis for a design and render its final grasp (off-screen).

Used by ``handbench render --gh``: the grasp comes from the same engine as the benchmark,
contacts coloured palmar / non-palmar / palm, with the verdict in the title.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from app.errors import UnknownHypothesisError
from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import base_kit, cached_kit, simulate_base, simulate_thumb

#: ``--gh`` values that pick from the store instead of naming a hypothesis.
PICKS = ("first-correct", "first-fc", "first-failed")


def pick_hypothesis(
    store: ResultStore, design: ThumbDesign, key: str, settings: SimSettings, pick: str
) -> int:
    """Index of the first stored hypothesis of ``design`` on ``key`` matching ``pick``."""
    hyps = cached_hypotheses(key)
    got = store.get_many(design_key(design), object_key(key), settings.key(), hyps.ids)
    for i, gh in enumerate(hyps.ids):
        o = got.get(gh)
        if o is None:
            continue
        if (
            (pick == "first-correct" and o.is_correct)
            or (pick == "first-fc" and o.is_fc)
            or (pick == "first-failed" and not o.is_fc)
        ):
            return i
    raise UnknownHypothesisError(
        f"no stored hypothesis of {key} at CMC {design.cmc_deg:g}°, MCP {design.mcp_deg:g}° "
        f"is '{pick}' ({len(got)} of {len(hyps)} stored): run `handbench evaluate` first"
    )


def grasp_view_angles(T_object_palm: np.ndarray) -> tuple[float, float]:
    """(elev, azim) in degrees of a camera on the hand's radial (thumb) side, a little
    distal and dorsal, so the thumb and the fingers wrapping the object are both visible."""
    R = T_object_palm[:3, :3]
    d = R @ np.array([1.0, 0.35, -0.45])
    d /= np.linalg.norm(d)
    return float(np.degrees(np.arcsin(d[2]))), float(np.degrees(np.arctan2(d[1], d[0])))


def render_grasp(
    path: str | Path,
    design: ThumbDesign,
    key: str,
    gh: str | int,
    settings: SimSettings | None = None,
) -> str:
    """Simulate hypothesis ``gh`` (id or index) and render it; returns a one-line verdict."""
    from app.reports.scene import render_scene

    s = settings or SimSettings()
    obj = load_object(key)
    hyps = cached_hypotheses(key)
    i = hyps.index_of(gh)
    kit = cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt)
    base = simulate_base(base_kit(design), obj, hyps, i, s)
    grasp = simulate_thumb(kit, obj, base, s)
    out = judge(grasp, obj, s, 0)
    verdict = (
        f"{hyps.ids[i]}: FC {'yes' if out.is_fc else 'no'}, correct "
        f"{'yes' if out.is_correct else 'no'}"
    )
    if out.reasons:
        verdict += " (" + "; ".join(out.reasons) + ")"
    title = (
        f"{obj.spec.name} ({obj.spec.grasp_type}), CMC {design.cmc_deg:g}°, "
        f"MCP {design.mcp_deg:g}°\n{hyps.ids[i]}: FC {'yes' if out.is_fc else 'no'}, "
        f"correct {'yes' if out.is_correct else 'no'}"
    )
    render_scene(
        path,
        hand=kit.hand,
        q=grasp.q,
        T_object_palm=grasp.T_object_palm,
        obj=obj,
        contacts=grasp.contacts,
        show_axes=False,
        title=title,
        view=grasp_view_angles(grasp.T_object_palm),
    )
    return verdict
