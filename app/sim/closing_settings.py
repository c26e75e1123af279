"""Settings of the collision-driven closing (METHOD §4). One source for CLI and GUI."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal

from app.errors import SettingsError

ClosingMode = Literal["sequential", "independent_thumb", "coupled_tendon"]
CLOSING_MODES: tuple[str, ...] = ("sequential", "independent_thumb", "coupled_tendon")
ClosingEngine = Literal["fcl", "compiled"]
CLOSING_ENGINES: tuple[str, ...] = ("fcl", "compiled")

#: Pairs whose distance lower bound is below this are queried exactly each step (mm).
EXACT_BELOW_MM = 12.0
#: Cap on false-position probes refining a stage's stop to the first crossing of gap = tol.
REFINE_ITERS = 8
#: The refinement ends once the stop's gap is within this fraction of tol below tol.
REFINE_BAND = 0.002


@dataclass(frozen=True)
class ClosingSettings:
    """How the hand approaches and closes. Lengths mm."""

    mode: ClosingMode = "sequential"
    """'sequential' (published, OpenRAVE-style), 'independent_thumb' (CMC and MCP close
    together at ``thumb_rates``), or 'coupled_tendon' (a finger's joints close together at
    ``tendon_ratios``)."""
    stop_tol_mm: float = 0.5
    """A closing joint stops once a moving link is this close to the object (final gap in
    (0, stop_tol_mm]); final angles do not depend on any step size beyond it."""
    thumb_rates: tuple[float, float] = (1.0, 1.0)
    """Independent-thumb mode: relative closing rates of CMC and MCP."""
    tendon_ratios: tuple[float, float, float] = (1.0, 1.0, 0.8)
    """Coupled-tendon mode: relative closing rates of a finger's three joints."""
    max_steps: int = 400
    """Cap on conservative-advancement steps per closing stage (a stage that hits it stops
    where it is and is counted in the statistics)."""
    approach_clearance_mm: float = 250.0
    """The approach starts this far beyond the object's bounding sphere."""
    engine: ClosingEngine = "compiled"
    """Distance engine of the approach, closing and contacts: 'compiled' (the default: the
    same algorithm compiled with numba, exact GJK on the same convex pieces, compiled signed
    distances: ``app/sim/closing_compiled.py``, ``contacts_compiled.py``) or 'fcl' (the
    reference: python-fcl queries and numpy signed distances from Python). Imported meshes
    always use FCL and numpy."""

    def __post_init__(self) -> None:
        if self.mode not in CLOSING_MODES:
            raise SettingsError(
                f"closing mode {self.mode!r} unknown; choose one of {CLOSING_MODES}"
            )
        if not (0 < self.stop_tol_mm <= 5):
            raise SettingsError(f"stop_tol_mm must be in (0, 5] mm, got {self.stop_tol_mm}")
        if self.engine not in CLOSING_ENGINES:
            raise SettingsError(
                f"closing engine {self.engine!r} unknown; choose one of {CLOSING_ENGINES}"
            )
        for name in ("thumb_rates", "tendon_ratios"):
            v = getattr(self, name)
            if not all(math.isfinite(x) and x >= 0 for x in v) or max(v) <= 0:
                raise SettingsError(f"{name} must be non-negative with one positive, got {v}")
        if self.max_steps < 10:
            raise SettingsError(f"max_steps must be >= 10, got {self.max_steps}")
        c = self.approach_clearance_mm
        if not (math.isfinite(c) and 0 <= c <= 10_000):
            raise SettingsError(f"approach_clearance_mm must be in [0, 10000] mm, got {c}")

    def as_dict(self) -> dict[str, object]:
        """Plain dict (for hashing and JSON)."""
        return asdict(self)
