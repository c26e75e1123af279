"""Stable content hashes: the keys that keep stored results of different inputs apart.

Base layer: imports numpy only, so every layer (settings, GQM settings, store keys) may use it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import fields, is_dataclass
from hashlib import sha256
from pathlib import Path
from typing import Any

import numpy as np


def _canonical(obj: Any) -> Any:
    """JSON-ready canonical form: floats rounded to 1e-9, arrays → lists, tuples → lists."""
    if isinstance(obj, np.ndarray):
        return _canonical(obj.tolist())
    if isinstance(obj, np.generic):
        return _canonical(obj.item())
    if obj is None or isinstance(obj, bool | str):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return obj
        return round(obj, 9) + 0.0  # + 0.0 turns -0.0 into 0.0
    if isinstance(obj, Mapping):
        return {str(k): _canonical(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_canonical(v) for v in obj]
    if isinstance(obj, Path):
        return str(obj)
    if is_dataclass(obj) and not isinstance(obj, type):
        return _canonical({f.name: getattr(obj, f.name) for f in fields(obj)})
    raise TypeError(f"stable_hash cannot hash a {type(obj).__name__}: {obj!r}")


def stable_hash(obj: Any) -> str:
    """16 hex chars of the sha256 of ``obj``'s canonical JSON.

    Canonical: dict keys sorted (and made str), floats ``round(x, 9)`` written by ``repr``
    (−0.0 as 0.0), numpy arrays and tuples as lists, numpy scalars as Python numbers,
    dataclasses as dicts of their fields. Equal data → equal hash across runs and machines.
    An int and the equal float (``45`` vs ``45.0``) hash differently; callers normalise.

    Raises:
        TypeError: ``obj`` holds a value of another type (set, arbitrary object...).
    """
    text = json.dumps(_canonical(obj), sort_keys=True, separators=(",", ":"))
    return sha256(text.encode()).hexdigest()[:16]
