"""What a long-lived process (the explorer's server) keeps loaded between uses, and what it
drops.

Kept ("the warm engine", loaded once by ``load_engine``): the compiled kernels (numba's
machine code, loaded from its on-disk cache; compiled when the cache is cold) and, per
object, its mesh, its hypotheses, its collision arrays, its packed signed distance and its
pieces' bounding spheres. These depend on the objects only and every simulation of them
uses them.

Dropped (``drop_hand_caches``): what is built per hand, i.e. per design (simulation kits,
finger chain arrays, link tables, the links' surface samples and k-d trees, the links'
visual meshes), and the per-object arrays of objects outside the kept set (imported meshes,
objects a user opened once). Each design change builds a new hand, so these caches only
grow while they are used.

``load_engine`` followed by ``drop_hand_caches`` on the same keys leaves the process holding
exactly what ``drop_hand_caches(keys)`` keeps, so a server's level once ready is the level it
returns to when its users are gone.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Sequence
from typing import Any

from app.model.objects import load_object
from app.sim.hypothesis_sets import cached_hypotheses


def _kept_targets(keys: Sequence[str]) -> list[Any]:
    return [load_object(k) for k in keys]


def load_engine(keys: Sequence[str], cancel: threading.Event | None = None) -> float:
    """Load the warm engine for the objects ``keys`` (the first one also runs one simulation,
    which loads every compiled kernel); seconds taken. ``cancel`` stops between steps.

    The simulation leaves one hand's caches behind: a caller that wants the kept set only
    follows with ``drop_hand_caches(keys)`` (the explorer does, unless a tab is open)."""
    from app.sim.closing_compiled import object_arrays
    from app.sim.contacts_compiled import piece_spheres
    from app.sim.sdf_compiled import object_program
    from app.sim.warm import warm

    t0 = time.perf_counter()
    keys = tuple(dict.fromkeys(keys))
    for k in keys:
        if cancel is not None and cancel.is_set():
            break
        obj = load_object(k)
        cached_hypotheses(k)
        arr = object_arrays(obj)
        object_program(obj)
        if arr is not None:
            piece_spheres(arr)
    if keys and not (cancel is not None and cancel.is_set()):
        warm(keys[0])
    return time.perf_counter() - t0


def _keep_only(cache: Any, keep_ids: set[int]) -> None:
    """Remove the entries of an ``id(x) -> (x, value)`` dict whose ``x`` is not kept."""
    if not isinstance(cache, dict):
        return
    for key, entry in list(cache.items()):
        if id(entry[0]) not in keep_ids:
            cache.pop(key, None)


def drop_hand_caches(keep: Sequence[str] = ()) -> None:
    """Empty the per-process caches of hands, and the per-object caches of every object not in
    ``keep`` (object keys). Modules not loaded yet are not imported."""
    from app.model.hand import model as hand_model
    from app.sim import contacts
    from app.sim.simulate import cached_kit

    cached_kit.cache_clear()
    hand_model._visual_meshes.cache_clear()  # noqa: SLF001 - the drawn links of each design
    contacts._samples.cache_clear()  # noqa: SLF001 - link shapes' surface samples
    contacts._coarse.cache_clear()  # noqa: SLF001 - and their k-d tree screening
    closing = sys.modules.get("app.sim.closing_compiled")
    if closing is not None:
        closing._CHAIN_CACHE.clear()  # noqa: SLF001 - finger chains (one per hand)
    cc = sys.modules.get("app.sim.contacts_compiled")
    if cc is not None:
        cc.link_tables.cache_clear()  # one entry per hand
    # per-object caches: keep the kept objects' entries only
    targets = _kept_targets(keep) if keep else []
    keep_ids = {id(t) for t in targets}
    if closing is not None:
        _keep_only(closing._CACHE, keep_ids)  # noqa: SLF001
    sdf = sys.modules.get("app.sim.sdf_compiled")
    if sdf is not None:
        _keep_only(sdf._CACHE, keep_ids)  # noqa: SLF001
    if cc is not None:
        arrays = set()
        if closing is not None:
            for t in targets:
                hit = closing._CACHE.get(id(t))  # noqa: SLF001
                if hit is not None and hit[1] is not None:
                    arrays.add(id(hit[1]))
        _keep_only(cc._SPHERES, arrays)  # noqa: SLF001
