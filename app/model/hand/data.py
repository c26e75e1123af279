"""Hand dimensions, read from a commented TOML file in ``hand_models/``."""

from __future__ import annotations

import hashlib
import os
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from app.errors import HandbenchError


def data_root() -> Path:
    """The folder holding ``hand_models/`` and ``objects/`` (env ``HANDBENCH_DATA_DIR``)."""
    env = os.environ.get("HANDBENCH_DATA_DIR")
    return Path(env) if env else Path(__file__).resolve().parents[3]


@dataclass(frozen=True)
class FingerDims:
    """One long finger (index, middle, ring, little)."""

    name: str
    """Finger name."""
    mcp_palm: np.ndarray
    """(3,) MCP joint centre in the palm frame, mm."""
    lengths: tuple[float, float, float]
    """Proximal, middle, distal phalanx lengths (joint to joint; distal to the tip), mm."""
    radius: float
    """Capsule radius of the phalanges, mm."""
    limits_deg: tuple[tuple[float, float], ...]
    """(lo, hi) of MCP, PIP, DIP in degrees."""


@dataclass(frozen=True)
class ThumbDims:
    """The thumb: metacarpal (CMC), proximal (MCP) and distal (IP) links."""

    cmc_palm: np.ndarray
    """(3,) CMC joint centre in the palm frame, mm."""
    lengths: tuple[float, float, float]
    """Metacarpal, proximal, distal lengths, mm."""
    radii: tuple[float, float, float]
    """Capsule radii of the three links, mm."""
    limits_deg: tuple[tuple[float, float], ...]
    """(lo, hi) of CMC, MCP, IP in degrees."""


@dataclass(frozen=True)
class PalmDims:
    """The palm block (rounded box) in the palm frame."""

    x_min: float
    """Ulnar edge, mm."""
    x_max: float
    """Radial edge, mm."""
    y_min: float
    """Proximal edge (wrist), mm."""
    y_max: float
    """Distal edge (MCP line), mm."""
    thickness: float
    """Thickness along z, centred on z = 0, mm."""
    corner_radius: float
    """Rounding of the visual palm, mm."""


@dataclass(frozen=True)
class HandDims:
    """All dimensions of a hand model file."""

    name: str
    """Model name."""
    path: Path
    """The file it was read from."""
    content_hash: str
    """sha256 (16 hex) of the file contents: part of every stored result's key."""
    approach_point_palm: np.ndarray
    """(3,) the approach reference point P in the palm frame, mm."""
    palm: PalmDims
    """The palm block."""
    fingers: tuple[FingerDims, ...]
    """Long fingers, radial to ulnar."""
    thumb: ThumbDims
    """The thumb."""


def _pairs(x: list[list[float]]) -> tuple[tuple[float, float], ...]:
    return tuple((float(a), float(b)) for a, b in x)


@lru_cache(maxsize=8)
def load_hand_dims(path: str | Path | None = None) -> HandDims:
    """Read a hand model file (default ``hand_models/imma_right.toml``)."""
    p = Path(path) if path is not None else data_root() / "hand_models" / "imma_right.toml"
    try:
        raw = p.read_bytes()
        d = tomllib.loads(raw.decode())
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise HandbenchError(f"cannot read hand model {p}: {e}") from e
    fingers = tuple(
        FingerDims(
            name=f["name"],
            mcp_palm=np.asarray(f["mcp"], float),
            lengths=tuple(float(v) for v in f["lengths"]),  # type: ignore[arg-type]
            radius=float(f["radius"]),
            limits_deg=_pairs(f["limits"]),
        )
        for f in d["finger"]
    )
    t = d["thumb"]
    return HandDims(
        name=d["name"],
        path=p,
        content_hash=hashlib.sha256(raw).hexdigest()[:16],
        approach_point_palm=np.asarray(d["approach_point"], float),
        palm=PalmDims(**{k: float(v) for k, v in d["palm"].items()}),
        fingers=fingers,
        thumb=ThumbDims(
            cmc_palm=np.asarray(t["cmc"], float),
            lengths=tuple(float(v) for v in t["lengths"]),  # type: ignore[arg-type]
            radii=tuple(float(v) for v in t["radii"]),  # type: ignore[arg-type]
            limits_deg=_pairs(t["limits"]),
        ),
    )
