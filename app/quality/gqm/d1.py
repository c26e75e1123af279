"""Q_D1, posture of the hand's finger joints (Roa & Suárez 2014, §D.1; Liégeois 1977).

A joint far from its limits leaves room to adapt. With mid-range a_i = (lo_i + hi_i)/2 and
half-range h_i = (hi_i − lo_i)/2, over the n closing joints J:

    Q_D1 = 1 − (1/n) Σ_{i ∈ J} |q_i − a_i| / h_i   ∈ [0, 1]

1 with every joint at mid-range, 0 with every joint at a limit. (R&S sum the squared
ratios and minimise; we use the mean absolute ratio as a bounded score.)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def q_d1(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, joints: Sequence[int]) -> float:
    """Posture score of joint angles ``q`` (n_q,) with limits ``lower``/``upper`` (n_q,),
    over joint indices ``joints``."""
    idx = np.asarray(joints, int)
    q, lo, hi = (np.asarray(a, float)[idx] for a in (q, lower, upper))
    half = 0.5 * (hi - lo)
    dev = np.clip(np.abs(q - 0.5 * (lo + hi)) / np.where(half > 0, half, 1.0), 0.0, 1.0)
    return float(1.0 - dev.mean()) if len(idx) else 0.0
