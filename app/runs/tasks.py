"""The work unit of a run: one object, a chunk of its hypotheses, the designs lacking them.

A worker computes each hypothesis' ``BaseGrasp`` once per CMC angle and then closes the
thumb of every listed design on it (docs/cost-model.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.judge import judge
from app.quality.outcome import GraspOutcome
from app.quality.settings import SimSettings
from app.runs.keys import design_key, set_object_key
from app.runs.palm_cache import palm_table
from app.runs.store import ResultStore
from app.sim.bruteforce import ALL_FINGERS, BruteForceHypotheses
from app.sim.hypothesis_sets import hypotheses_of
from app.sim.simulate import (
    BaseGrasp,
    PalmGrasp,
    base_kit,
    base_mcp_deg,
    cached_kit,
    simulate_base,
    simulate_palm,
    simulate_thumb,
)

#: Hypotheses per task: small enough for a live progress bar, large enough to amortise.
DEFAULT_CHUNK = 60


@dataclass(frozen=True)
class Task:
    """Hypotheses ``gh`` of ``object_name`` for the designs in ``designs``."""

    object_name: str
    """Object key, e.g. 'chips_can'."""
    gh: tuple[int, ...]
    """Hypothesis indices."""
    designs: tuple[ThumbDesign, ...]
    """Designs to evaluate on every listed hypothesis."""
    settings: SimSettings
    """Simulation settings."""
    hypothesis_set: str = "anthropomorphic"
    """One of ``HYPOTHESIS_SETS``."""


def run_task(
    task: Task, on_hypothesis: Callable[[int], None] | None = None
) -> list[tuple[int, str, GraspOutcome]]:
    """Simulate one task; returns (design index in task, GH id, outcome) triples.

    ``on_hypothesis(i)`` is called before hypothesis index ``i`` is simulated (the process
    pool records it, to name the hypothesis if the worker dies).

    Brute-force sets close all fingers, and their outcomes keep the hand placement in
    ``extra["T_object_palm"]`` (4×4 nested list, mm) for the GQMs and pictures.
    """
    obj = load_object(task.object_name)
    hyps = hypotheses_of(task.object_name, task.hypothesis_set)
    s = task.settings
    kits = [cached_kit(*d.as_dict().values()) for d in task.designs]  # type: ignore[arg-type]
    # per design: its base stage's key (CMC angle, tilt, the base kit's MCP) and kit
    open_thumbs = [(d.cmc_deg, d.cmc_tilt, base_mcp_deg(d)) for d in task.designs]
    base_kits = [base_kit(d) for d in task.designs]
    out: list[tuple[int, str, GraspOutcome]] = []
    bf = isinstance(hyps, BruteForceHypotheses)
    palms = None if bf else palm_table(task.object_name, s)
    for i in task.gh:
        if on_hypothesis is not None:
            on_hypothesis(i)
        # the open thumb (part of the approach) depends on the CMC angle only: one base
        # stage per (CMC angle, tilt), shared by every MCP angle (docs/cost-model.md), always
        # computed by the same kit (``base_kit``) whatever designs share the task
        bases: dict[tuple[float, str, float], BaseGrasp] = {}
        # the thumbless hand: one per hypothesis for every design (the process' palm table)
        palm: PalmGrasp | None = palms.get(i) if palms is not None else None
        h, fingers = (hyps.approach_line(i), ALL_FINGERS) if bf else (hyps, None)
        for di, (kit, open_thumb, bk) in enumerate(zip(kits, open_thumbs, base_kits, strict=True)):
            base = bases.get(open_thumb)
            if base is None:
                if palm is None:
                    palm = simulate_palm(bk, obj, h, i, s, fingers=fingers)
                base = simulate_base(bk, obj, h, i, s, fingers=fingers, palm=palm)
                bases[open_thumb] = base
            g = simulate_thumb(kit, obj, base, s)
            o = judge(g, obj, s, base.queries + g.queries)
            if bf:
                o = replace(o, extra={**o.extra, "T_object_palm": g.T_object_palm.tolist()})
            out.append((di, hyps.ids[i], o))
    return out


def plan_tasks(
    store: ResultStore,
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    settings: SimSettings,
    chunk: int = DEFAULT_CHUNK,
    gh_stride: int = 1,
    hypothesis_set: str = "anthropomorphic",
    shuffle_seed: int | None = None,
    first_n: int | None = None,
) -> list[Task]:
    """Tasks for every (design, object, GH) not yet in the store (every ``gh_stride``-th GH).

    ``hypothesis_set`` (one of ``HYPOTHESIS_SETS``) picks the hypotheses and the store's
    object key (``hypotheses_of``/``set_object_key``); the default is the benchmark's.
    ``shuffle_seed``: when given, each object's hypotheses are taken in a seeded random order
    (the same for every call), so the outcomes finished at any moment are a simple random
    sample of the object's hypotheses: an honest running estimate. Outcomes do not depend on
    the order. ``first_n``: only the first n hypotheses of each object's order (with a
    shuffle seed: the first n of its random order, the explorer's first sample).
    """
    skey = settings.key()
    dkeys = [design_key(d) for d in designs]
    tasks: list[Task] = []
    first = {d: k for k, d in enumerate(designs)}  # a batch's place: its first design's
    for name in object_names:
        obj_tasks: list[Task] = []
        hyps = hypotheses_of(name, hypothesis_set)
        okey = set_object_key(name, hypothesis_set)
        present = [store.present_ids(dk, okey, skey) for dk in dkeys]
        subset = list(range(0, len(hyps), gh_stride))
        if shuffle_seed is not None:
            order = np.random.default_rng([shuffle_seed, len(subset)]).permutation(len(subset))
            subset = [subset[k] for k in order]
        if first_n is not None:
            subset = subset[:first_n]
        for start in range(0, len(subset), chunk):
            idx = subset[start : start + chunk]
            # group designs by which of these GHs they lack (usually: all or none)
            groups: dict[tuple[int, ...], list[ThumbDesign]] = {}
            for d, have in zip(designs, present, strict=True):
                missing = tuple(i for i in idx if hyps.ids[i] not in have)
                if missing:
                    groups.setdefault(missing, []).append(d)
            for missing, ds in groups.items():
                for batch in design_batches(ds):
                    obj_tasks.append(Task(name, missing, batch, settings, hypothesis_set))
        # batch after batch (each chunk in its order): a worker's consecutive tasks share
        # their designs' kits, however many designs the run has
        obj_tasks.sort(key=lambda t: first[t.designs[0]])
        tasks.extend(obj_tasks)
    return tasks


#: Designs per task at most: a worker keeps the kits of its recent designs (``cached_kit``,
#: 256, ~0.25 MB each), and tasks cycling through more designs than that rebuild every kit
#: on every task (the 5° map's 190-design tasks took 9 min instead of under 6).
MAX_DESIGNS_PER_TASK = 48


def design_batches(
    designs: Sequence[ThumbDesign], limit: int = MAX_DESIGNS_PER_TASK
) -> list[tuple[ThumbDesign, ...]]:
    """``designs`` in batches of at most ``limit``, each CMC angle's designs together where
    they fit (they share a hypothesis' base stage), in the order given otherwise."""
    groups: dict[tuple[float, str], list[ThumbDesign]] = {}
    for d in designs:
        groups.setdefault((d.cmc_deg, d.cmc_tilt), []).append(d)
    batches: list[list[ThumbDesign]] = []
    for g in groups.values():
        for i in range(0, len(g), limit):
            part = g[i : i + limit]
            if batches and len(batches[-1]) + len(part) <= limit:
                batches[-1].extend(part)
            else:
                batches.append(list(part))
    return [tuple(b) for b in batches]
