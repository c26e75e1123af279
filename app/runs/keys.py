"""Store keys: what makes two stored outcomes the same computation.

A key is a :func:`app.hashing.stable_hash` of everything that changes an outcome: the hand
file and the design (``design_key``), the object's mesh and grasp set-up (``object_key``,
with a suffix per brute-force hypothesis set), and the settings (``SimSettings.key()``).
"""

from __future__ import annotations

from functools import lru_cache

from app.hashing import stable_hash
from app.model.design import ThumbDesign
from app.model.hand.data import load_hand_dims
from app.model.objects import load_object
from app.sim.bruteforce import BF_SETS, bf_store_suffix
from app.sim.hypothesis_sets import check_set


def design_key(design: ThumbDesign) -> str:
    """Store key of a design: the hand model file's hash + the thumb design."""
    return stable_hash({"hand": load_hand_dims().content_hash, **design.as_dict()})


@lru_cache(maxsize=32)
def object_key(key: str) -> str:
    """Store key of an object: hash of its mesh and grasp set-up."""
    obj = load_object(key)
    s = obj.spec
    return stable_hash(
        {
            "key": s.key,
            "grasp_type": s.grasp_type,
            "target": s.target_object,
            "normal": s.normal_object,
            "grip": s.grip_axis_object,
            "hint": s.palm_y_hint_object,
            "setup": vars(s.setup),
            "mesh": stable_hash({"v": obj.mesh.vertices.round(6), "f": obj.mesh.faces}),
        }
    )


def set_object_key(key: str, hypothesis_set: str = "anthropomorphic") -> str:
    """Store object key of an object's hypothesis set: ``object_key`` for the benchmark,
    with a suffix (``':bf'``) for a brute-force set, so the two never mix."""
    check_set(hypothesis_set)
    if hypothesis_set == "anthropomorphic":
        return object_key(key)
    return object_key(key) + bf_store_suffix(BF_SETS[hypothesis_set])
