"""Warm numba's on-disk cache of the compiled engine: ``python -m app.sim.warm``.

The compiled kernels (``app.sim.gjk``, ``closing_compiled``, ``sdf_compiled``,
``contacts_compiled``) are compiled on their first call, about a minute on a 2-core machine,
and cached next to their modules (``cache=True``) for every later process. ``make setup``
runs this once so that the first live score, sweep or test does not pay the compile. It
simulates one hypothesis of one object with the compiled engine (approach, long fingers,
thumb stages, contacts) and prints how long that took.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

from app.sim.closing_settings import ClosingSettings
from app.sim.contacts import ContactSettings


@dataclass(frozen=True)
class _Palmar:
    palmar_angle_deg: float = 75.0


@dataclass(frozen=True)
class _Settings:
    """The part of the settings simulating reads (``SimulationSettings``)."""

    closing: ClosingSettings = field(
        default_factory=lambda: dataclasses.replace(ClosingSettings(), engine="compiled")
    )
    contact: ContactSettings = field(default_factory=ContactSettings)
    grasp_type: _Palmar = field(default_factory=_Palmar)


def warm(key: str = "washer") -> float:
    """Simulate one hypothesis of ``key`` (the first whose approach touches) on the compiled
    engine; seconds taken. Any built-in object compiles every kernel: numba compiles a
    function for its argument types, all branches of the signed distance included."""
    from app.model.design import ThumbDesign
    from app.model.objects import load_object
    from app.sim.hypothesis_sets import cached_hypotheses
    from app.sim.simulate import base_kit, cached_kit, simulate_base, simulate_thumb

    t0 = time.perf_counter()
    obj, hyps = load_object(key), cached_hypotheses(key)
    s = _Settings()
    design = ThumbDesign(0.0, 45.0)
    base = simulate_base(base_kit(design), obj, hyps, 0, s)
    for i in range(1, min(len(hyps), 50)):  # one that touches: closing and contacts run too
        if base.approached:
            break
        base = simulate_base(base_kit(design), obj, hyps, i, s)
    simulate_thumb(cached_kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt), obj, base, s)
    return time.perf_counter() - t0


def main() -> None:
    """Warm the cache and say how long it took."""
    dt = warm()
    print(f"compiled engine ready (numba cache warm): one hypothesis took {dt:.1f} s")


if __name__ == "__main__":
    main()
