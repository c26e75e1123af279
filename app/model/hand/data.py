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

#: The repository's folder (resolved once: resolving walks the file system, and the hand
#: file's path is asked for on every hypothesis).
_REPO_ROOT = Path(__file__).resolve().parents[3]


#: Environment variable naming the folder that holds ``hand_models/`` and ``objects/``.
DATA_ENV = "HANDBENCH_DATA_DIR"


def data_root() -> Path:
    """The folder holding ``hand_models/`` and ``objects/`` (env ``HANDBENCH_DATA_DIR``)."""
    env = os.environ.get(DATA_ENV)
    return Path(env) if env else _REPO_ROOT


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
class ThumbReading:
    """How the design angles (c, m) place the thumb's joint axes (docs/validation.md).

    Vectors are in the palm frame, for the open hand (q = 0) at the design c = 0, m = 0.
    """

    rest_direction: np.ndarray
    """(3,) the straight open thumb's long axis (CMC toward the tip) at c = 0."""
    cmc_axis: np.ndarray
    """(3,) the CMC hinge axis at c = 0, signed: closing turns the thumb about it by the
    right-hand rule."""
    cmc_tilt_line: np.ndarray
    """(3,) c turns the CMC axis by +c about this line (right-hand rule); ``cmc_tilt=
    'radial'`` turns it by -c."""
    bones_turn: bool
    """True: the thumb's links are built perpendicular to their hinge axes and turn with
    them (the metacarpal turns with c; the first reading). False: the links keep their rest
    direction whatever the design; c and m only turn the hinge pins, which may then be
    oblique to the links."""
    mcp_turn_line: str
    """'metacarpal': the MCP axis is the CMC axis turned by m about the metacarpal's long
    axis (the open thumb stays straight); 'metacarpal_normal': turned about the metacarpal's
    palmar normal, the proximal phalanx turning with it (the open thumb bends by m at the
    MCP); 'cmc_tilt_line' (links that keep their rest direction only): turned about the
    same line as c (so the MCP axis sits at c + m)."""

    mcp_sense: float
    """+1 or -1: the sense in which m turns the MCP axis. With 'metacarpal', +1 is toward the
    metacarpal's palmar side (the first reading); with 'metacarpal_normal' and
    'cmc_tilt_line', +1 is the sense of c."""

    @property
    def open_thumb_depends_on_mcp(self) -> bool:
        """Whether the open thumb's shape depends on m (then the approach does too)."""
        return self.bones_turn and self.mcp_turn_line == "metacarpal_normal"


#: The first reading (``hand_models/imma_right_v1.toml``): the defaults for a hand file
#: without these keys.
V1_READING = {
    "rest_direction": [1.0, 0.0, 0.0],
    "cmc_axis": [0.0, -1.0, 0.0],
    "cmc_tilt_line": [0.0, 0.0, 1.0],
    "bones_turn": True,
    "mcp_turn_line": "metacarpal",
    "mcp_sense": 1,
}


def _unit(v: list[float], what: str, path: Path) -> np.ndarray:
    a = np.asarray(v, float)
    n = float(np.linalg.norm(a))
    if a.shape != (3,) or not np.isfinite(a).all() or n == 0.0:
        raise HandbenchError(f"{path}: thumb.{what} must be a nonzero 3-vector, got {v!r}")
    return a if n == 1.0 else a / n


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
    reading: ThumbReading
    """How the design angles orient the CMC and MCP axes."""


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


#: Environment variable selecting the default hand file: a path, or a name in hand_models/.
HAND_ENV = "HANDBENCH_HAND"


def hand_path(path: str | Path | None = None) -> Path:
    """The hand file to read: ``path``; else ``$HANDBENCH_HAND`` (a path, or a name such as
    ``imma_right_v1`` looked up in ``<data root>/hand_models/``); else ``imma_right.toml``."""
    if path is None:
        path = os.environ.get(HAND_ENV) or "imma_right"
        p = Path(path)
        if p.suffix != ".toml" and len(p.parts) == 1:
            return data_root() / "hand_models" / f"{path}.toml"
        return p
    return Path(path)


def load_hand_dims(path: str | Path | None = None) -> HandDims:
    """Read a hand model file (default: see ``hand_path``)."""
    if path is None:  # asked for on every hypothesis: the default's path per environment
        return _load_hand_dims(_default_path(os.environ.get(HAND_ENV), os.environ.get(DATA_ENV)))
    return _load_hand_dims(hand_path(path))


@lru_cache(maxsize=8)
def _default_path(hand_env: str | None, data_env: str | None) -> Path:
    """``hand_path()`` for these values of ``$HANDBENCH_HAND`` and ``$HANDBENCH_DATA_DIR``."""
    return hand_path()


@lru_cache(maxsize=8)
def _load_hand_dims(p: Path) -> HandDims:
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
    r = {k: t.get(k, v) for k, v in V1_READING.items()}
    reading = ThumbReading(
        rest_direction=_unit(r["rest_direction"], "rest_direction", p),
        cmc_axis=_unit(r["cmc_axis"], "cmc_axis", p),
        cmc_tilt_line=_unit(r["cmc_tilt_line"], "cmc_tilt_line", p),
        bones_turn=bool(r["bones_turn"]),
        mcp_turn_line=str(r["mcp_turn_line"]),
        mcp_sense=float(r["mcp_sense"]),
    )
    if reading.bones_turn and abs(float(reading.rest_direction @ reading.cmc_axis)) > 1e-9:
        raise HandbenchError(f"{p}: with bones_turn, thumb.cmc_axis must be ⟂ rest_direction")
    turn_lines = (
        ("metacarpal", "metacarpal_normal")
        if reading.bones_turn
        else (
            "metacarpal",
            "cmc_tilt_line",
        )
    )
    if reading.mcp_turn_line not in turn_lines:
        raise HandbenchError(
            f"{p}: thumb.mcp_turn_line must be one of {turn_lines} "
            f"(bones_turn = {reading.bones_turn}), got {reading.mcp_turn_line!r}"
        )
    if reading.mcp_sense not in (1.0, -1.0):
        raise HandbenchError(f"{p}: thumb.mcp_sense must be 1 or -1, got {r['mcp_sense']!r}")
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
            reading=reading,
        ),
    )
