"""Object specifications: the grasp set-up of METHOD §3a and the data-file (TOML) reader.

Files are in millimetres and degrees (the cone angle is also accepted in radians,
``cone_angle_rad``, because METHOD's table gives it so); inside, angles are radians.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from app.errors import HandbenchError

#: The six shipped objects, in METHOD §2 order.
OBJECT_KEYS: tuple[str, ...] = (
    "small_marker",
    "plastic_pear",
    "washer",
    "chips_can",
    "coffee_can",
    "power_drill",
)

GRASP_TYPES = ("PP", "CG")


class ObjectFileError(HandbenchError, ValueError):
    """An object data file (TOML) that is missing a field or holds an invalid value."""


def data_dir() -> Path:
    """Folder of the shipped object files: ``$HANDBENCH_DATA_DIR/objects`` or ``<repo>/objects``."""
    env = os.environ.get("HANDBENCH_DATA_DIR")
    if env:
        return Path(env) / "objects"
    return Path(__file__).resolve().parents[3] / "objects"


def user_dir() -> Path | None:
    """The folder of saved imported objects: ``$HANDBENCH_USER_OBJECTS``, else
    ``$XDG_DATA_HOME/handbench/objects`` (default ``~/.local/share/handbench/objects``)."""
    env = os.environ.get("HANDBENCH_USER_OBJECTS")
    if env:
        return Path(env)
    data = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(data) / "handbench" / "objects"


@dataclass(frozen=True)
class GraspSetup:
    """Grasp-hypothesis parameters of one object (METHOD §3a table)."""

    hand_vector_palm: np.ndarray
    """(3,) unit hand vector n in the palm frame; the ray through P along n hits the target."""
    cone_angle_rad: float
    """Full opening angle alpha of the approach cone, radians."""
    n_rays: int
    """Number of approach rays N_alpha spread over the cone (axis ray included)."""
    standoffs_mm: tuple[float, ...]
    """Standoffs delta (mm): 0 = stop at first contact, >0 = back off that much, then close."""
    roll_range_deg: tuple[float, float]
    """(theta_i, theta_f) roll about the ray, degrees, both ends included, order kept."""
    n_rolls: int
    """Number of roll values N_theta, evenly spaced from theta_i to theta_f."""

    @property
    def n_gh(self) -> int:
        """Number of grasp hypotheses N_GH = N_alpha * N_delta * N_theta."""
        return self.n_rays * len(self.standoffs_mm) * self.n_rolls

    @property
    def rolls_rad(self) -> np.ndarray:
        """(n_rolls,) roll values in radians, from theta_i to theta_f inclusive."""
        a, b = self.roll_range_deg
        return np.deg2rad(np.linspace(a, b, self.n_rolls))


@dataclass(frozen=True)
class ObjectSpec:
    """Everything an object's data file says, in the object frame (mm)."""

    key: str
    """Object key, e.g. ``"chips_can"``."""
    name: str
    """Display name."""
    grasp_type: str
    """``"PP"`` (pulp pinch) or ``"CG"`` (cylindrical grip)."""
    target_object: np.ndarray
    """(3,) target point on the surface, object frame, mm."""
    normal_object: np.ndarray
    """(3,) unit outward surface normal at the target: the approach-cone axis."""
    grip_axis_object: np.ndarray | None
    """(3,) unit grip axis (can axis, handle axis) for CG objects, None for PP."""
    palm_y_hint_object: np.ndarray
    """(3,) unit palm +y direction (finger direction) at roll 0, object frame."""
    setup: GraspSetup
    """Grasp-hypothesis parameters (METHOD §3a)."""
    shape: dict[str, Any] = field(default_factory=dict)
    """The raw shape parameters from the file (``kind`` plus its dimensions, mm)."""
    source: str = ""
    """The data file path, or ``"imported from <path>"``."""


def _unit(v: Any, what: str, where: str) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ObjectFileError(f"{where}: {what} must be 3 finite numbers, got {v!r}")
    n = float(np.linalg.norm(a))
    if n < 1e-9:
        raise ObjectFileError(f"{where}: {what} must not be the zero vector")
    return a / n


def _get(d: dict[str, Any], name: str, where: str) -> Any:
    if name not in d:
        raise ObjectFileError(f"{where}: missing field '{name}'")
    return d[name]


def setup_from_dict(g: dict[str, Any], where: str) -> GraspSetup:
    """Build a :class:`GraspSetup` from the ``[grasp]`` table of a data file."""
    if ("cone_angle_rad" in g) == ("cone_angle_deg" in g):
        raise ObjectFileError(f"{where}: give exactly one of cone_angle_rad / cone_angle_deg")
    alpha = (
        float(g["cone_angle_rad"])
        if "cone_angle_rad" in g
        else math.radians(float(g["cone_angle_deg"]))
    )
    if not (0.0 <= alpha < math.pi):
        raise ObjectFileError(f"{where}: cone angle must be in [0, 180) degrees, got {alpha} rad")
    roll = tuple(float(x) for x in _get(g, "roll_deg", where))
    if len(roll) != 2:
        raise ObjectFileError(f"{where}: roll_deg must be [theta_i, theta_f], got {roll}")
    standoffs = tuple(float(x) for x in _get(g, "standoffs_mm", where))
    if not standoffs or any(s < 0 or not math.isfinite(s) for s in standoffs):
        raise ObjectFileError(f"{where}: standoffs_mm must be a non-empty list of values >= 0")
    n_rays, n_rolls = int(_get(g, "n_rays", where)), int(_get(g, "n_rolls", where))
    if n_rays < 1 or n_rolls < 1:
        raise ObjectFileError(f"{where}: n_rays and n_rolls must be >= 1")
    return GraspSetup(
        hand_vector_palm=_unit(_get(g, "hand_vector_palm", where), "hand_vector_palm", where),
        cone_angle_rad=alpha,
        n_rays=n_rays,
        standoffs_mm=standoffs,
        roll_range_deg=(roll[0], roll[1]),
        n_rolls=n_rolls,
    )


def spec_from_dict(d: dict[str, Any], key: str, source: str) -> ObjectSpec:
    """Build an :class:`ObjectSpec` from a parsed data file (see ``objects/*.toml``)."""
    where = source
    gt = str(_get(d, "grasp_type", where))
    if gt not in GRASP_TYPES:
        raise ObjectFileError(f"{where}: grasp_type must be one of {GRASP_TYPES}, got {gt!r}")
    normal = _unit(_get(d, "normal", where), "normal", where)
    grip = None
    if gt == "CG":
        grip = _unit(_get(d, "grip_axis", where), "grip_axis", where)
    hint = _unit(_get(d, "palm_y_hint", where), "palm_y_hint", where)
    if abs(float(hint @ normal)) > 0.999:
        raise ObjectFileError(f"{where}: palm_y_hint must not be parallel to the normal")
    target = np.asarray(_get(d, "target_mm", where), dtype=float)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise ObjectFileError(f"{where}: target_mm must be 3 finite numbers")
    shape = dict(_get(d, "shape", where))
    if "kind" not in shape:
        raise ObjectFileError(f"{where}: [shape] needs a 'kind'")
    return ObjectSpec(
        key=key,
        name=str(d.get("name", key)),
        grasp_type=gt,
        target_object=target,
        normal_object=normal,
        grip_axis_object=grip,
        palm_y_hint_object=hint,
        setup=setup_from_dict(dict(_get(d, "grasp", where)), where),
        shape=shape,
        source=source,
    )


def read_spec(path: Path, key: str | None = None) -> ObjectSpec:
    """Read one data file; the key defaults to the file stem."""
    try:
        with open(path, "rb") as f:
            d = tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise ObjectFileError(f"{path}: not valid TOML: {e}") from e
    return spec_from_dict(d, key or path.stem, str(path))


def spec_to_toml(spec: ObjectSpec, extra_comment: str = "") -> str:
    """Write a spec as TOML text (used to save imported objects); floats in mm / degrees."""

    def vec(v: np.ndarray) -> str:
        return "[" + ", ".join(f"{float(x):.6g}" for x in v) + "]"

    def val(x: Any) -> str:
        if isinstance(x, str):
            return '"' + x.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(x, bool):
            return "true" if x else "false"
        if isinstance(x, list | tuple):
            return "[" + ", ".join(val(y) for y in x) + "]"
        return repr(x)

    s = spec.setup
    lines = [f"# {extra_comment}" if extra_comment else "# imported object"]
    lines += [
        "# Object frame: the imported mesh's own frame (after unit conversion), mm.",
        f"name = {val(spec.name)}",
        f"grasp_type = {val(spec.grasp_type)}",
        f"target_mm = {vec(spec.target_object)}",
        f"normal = {vec(spec.normal_object)}",
    ]
    if spec.grip_axis_object is not None:
        lines.append(f"grip_axis = {vec(spec.grip_axis_object)}")
    lines += [
        f"palm_y_hint = {vec(spec.palm_y_hint_object)}",
        "",
        "[shape]",
        *(f"{k} = {val(v)}" for k, v in spec.shape.items()),
        "",
        "[grasp]",
        f"hand_vector_palm = {vec(s.hand_vector_palm)}",
        f"cone_angle_rad = {s.cone_angle_rad!r}",
        f"n_rays = {s.n_rays}",
        f"standoffs_mm = {val(list(s.standoffs_mm))}",
        f"roll_deg = {val(list(s.roll_range_deg))}",
        f"n_rolls = {s.n_rolls}",
        "",
    ]
    return "\n".join(lines)
