"""The thumb design: one source of truth for the CLI flags and the explorer sliders."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Literal

from app.errors import DesignError

CMC_RANGE_DEG = (0.0, 45.0)
MCP_RANGE_DEG = (0.0, 90.0)
CMC_GRID_DEG = (0.0, 15.0, 30.0, 45.0)
MCP_GRID_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)
BASELINE_DEG = (0.0, 45.0)


@dataclass(frozen=True)
class ThumbDesign:
    """A design alternative (DA): the orientation of the thumb's CMC and MCP axes."""

    cmc_deg: float = field(default=BASELINE_DEG[0], metadata={"range": CMC_RANGE_DEG})
    """Thumb CMC axis orientation c: the palm +y axis tilted by c inside the palm plane (°)."""
    mcp_deg: float = field(default=BASELINE_DEG[1], metadata={"range": MCP_RANGE_DEG})
    """Thumb MCP axis orientation m: the CMC axis turned by m about the metacarpal (°)."""
    cmc_tilt: Literal["ulnar", "radial"] = "ulnar"
    """'ulnar' keeps the hand file's sense of c (its ``cmc_tilt_line``; the default hand leans
    the CMC axis radially, ``imma_right_v1`` ulnarly); 'radial' mirrors it."""

    def __post_init__(self) -> None:
        for f in fields(self):
            if "range" not in f.metadata:
                continue
            value = getattr(self, f.name)
            lo, hi = f.metadata["range"]
            if not isinstance(value, int | float) or not math.isfinite(value):
                raise DesignError(f"{f.name} must be a finite number of degrees, got {value!r}")
            if not lo <= value <= hi:
                raise DesignError(
                    f"{f.name} = {value} is outside the design range [{lo:g}, {hi:g}]°"
                )
            object.__setattr__(self, f.name, float(value))
        if self.cmc_tilt not in ("ulnar", "radial"):
            raise DesignError(f"cmc_tilt must be 'ulnar' or 'radial', got {self.cmc_tilt!r}")

    @property
    def label(self) -> str:
        """Short label, e.g. 'c15_m60'."""
        return f"c{self.cmc_deg:g}_m{self.mcp_deg:g}"

    def as_dict(self) -> dict[str, float | str]:
        """Plain dict for JSON and hashing."""
        return {"cmc_deg": self.cmc_deg, "mcp_deg": self.mcp_deg, "cmc_tilt": self.cmc_tilt}


def published_designs() -> list[ThumbDesign]:
    """The 28 published design alternatives, CMC-major order."""
    return [ThumbDesign(c, m) for c in CMC_GRID_DEG for m in MCP_GRID_DEG]


BASELINE = ThumbDesign(*BASELINE_DEG)
