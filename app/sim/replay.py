"""Replay of one grasp hypothesis as key frames: approach, back-off, closing stage by stage.

The frames come from the same closing engine as the benchmark (the stages it actually ran),
so what the explorer animates is what was scored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from app.model.target import GraspTarget
from app.sim.closing import ClosingStats
from app.sim.hypotheses import Hypotheses
from app.sim.simulate import (
    BaseGrasp,
    Grasp,
    HandKit,
    SimulationSettings,
    simulate_base,
    simulate_thumb,
)


@dataclass(frozen=True)
class Frame:
    """One animation frame."""

    T_object_palm: np.ndarray
    """(4, 4) hand placement, object frame."""
    q: np.ndarray
    """(15,) joint angles, rad."""
    label: str
    """What is happening, e.g. 'approach', 'back-off 25 mm', 'index MCP closing'."""


@dataclass(frozen=True)
class Replay:
    """A hypothesis simulated with its frames."""

    frames: list[Frame]
    """Frames from the start of the approach to the final grasp."""
    base: BaseGrasp
    """The design-independent stage."""
    grasp: Grasp
    """The final grasp (same as the benchmark computes)."""


_JOINT_LABELS = {"thumb": ("CMC", "MCP", "IP")}


def _stage_label(finger: str, q0: np.ndarray, q1: np.ndarray, kind: str) -> str:
    names = _JOINT_LABELS.get(finger, ("MCP", "PIP", "DIP"))
    moved = [names[k] for k in range(3) if abs(q1[k] - q0[k]) > 1e-9]
    return f"{finger} {'+'.join(moved) or '-'} closing -> {kind}"


def replay(
    kit: HandKit,
    obj: GraspTarget,
    hyps: Hypotheses,
    i: int,
    settings: SimulationSettings,
    frames_per_stage: int = 12,
    base_kit: HandKit | None = None,
) -> Replay:
    """Simulate hypothesis ``i`` recording its stages and expand them into frames.

    ``base_kit`` computes the base stage (default ``kit``); pass
    ``app.sim.simulate.base_kit(...)`` to replay exactly what a sweep scores."""
    sb = ClosingStats(stages=[])
    base = simulate_base(base_kit or kit, obj, hyps, i, settings, sb)
    st = ClosingStats(stages=[])
    grasp = simulate_thumb(kit, obj, base, settings, st)
    R = hyps.R_object_palm[i]
    ray = hyps.ray_object[i]
    P = kit.hand.approach_point_palm

    def placed(s: float) -> np.ndarray:
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = hyps.target_object + s * ray - R @ P
        return T

    frames: list[Frame] = []
    q = kit.q_open.copy()
    if sb.approach_s is not None:
        s0, s1 = sb.approach_s
        s0 = min(s0, s1 + 150.0)  # start the animation near the object
        for s in np.linspace(s0, s1, frames_per_stage * 2):
            frames.append(Frame(placed(float(s)), q.copy(), "approach"))
        d = float(hyps.standoff_mm[i])
        if d > 0:
            for s in np.linspace(s1, s1 + d, frames_per_stage):
                frames.append(Frame(placed(float(s)), q.copy(), f"back-off {d:g} mm"))
    T = base.T_object_palm
    for finger, q0, q1, kind in (sb.stages or []) + (st.stages or []):
        joints = list(kit.chains[finger].joints)
        label = _stage_label(finger, q0, q1, kind)
        for a in np.linspace(0.0, 1.0, frames_per_stage):
            q[joints] = (1 - a) * q0 + a * q1
            frames.append(Frame(T, q.copy(), label))
    frames.append(Frame(T, grasp.q.copy(), "final grasp"))
    return Replay(frames, base, grasp)
