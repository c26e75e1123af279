"""The brute-force comparison of METHOD §6: simulate the brute-force set, score FC grasps with
the ten GQMs, and find, per object and GQM, the design whose best grasp scores highest.

Pipeline (``run_comparison``):

1. Simulate the brute-force hypotheses (``app.sim.bruteforce``) of every object under every
   design with the sweep machinery (``app.runs.tasks.plan_tasks``,
   ``app.runs.sweep.execute_tasks`` and an executor). Results go to the same results store
   under the object key ``object_key(name) + ':bf'``; a rerun computes only what is missing.
2. Per object and design: the stored FC grasps, of which up to ``max_grasps`` are drawn at
   random (``numpy.random.default_rng([seed, crc32('<object>|<design key>')])``, ids sorted
   first, so the draw is reproducible and independent of the store's row order).
3. The ten GQMs of each drawn grasp (``app.quality.gqm.compute_gqms``), in a process pool, in
   jobs of ``GQM_CHUNK`` grasps. Each finished job's values go to the store's ``gqms`` table at once
   (keyed by design, object, simulation settings, ``GQMSettings.key()`` and GH id), so a
   rerun computes only the GQMs it lacks and an interrupted run loses only the jobs in
   flight.
4. The winners: per object and GQM, the design with the highest best-grasp value (ties: the
   first design in the order given); win counts per design; and whether each winning grasp
   meets the correctness criteria of the object's grasp type (``check_pp``/``check_cg``
   re-run on the stored contacts).
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Generator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import closing
from dataclasses import dataclass
from multiprocessing import get_context

import numpy as np

from app.model.design import ThumbDesign
from app.model.objects import load_object
from app.quality.gqm import GQM_NAMES, GQMSettings, compute_gqms
from app.quality.grasp_type import check_cg, check_pp
from app.quality.outcome import GraspOutcome
from app.quality.settings import SimSettings
from app.runs.executors import Executor
from app.runs.keys import design_key, set_object_key
from app.runs.progress import Progress
from app.runs.store import ResultStore
from app.runs.sweep import execute_tasks
from app.runs.tasks import plan_tasks
from app.sim.hypothesis_sets import hypotheses_of
from app.sim.simulate import cached_kit

BF_SET = "brute_force"
#: Grasps per GQM job (the unit stored at once): a few seconds of cylindrical grips.
GQM_CHUNK = 10


# ----------------------------------------------------------------------------- simulation
def simulate_bf(
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    store: ResultStore,
    settings: SimSettings,
    executor: Executor | None = None,
    hypothesis_set: str = BF_SET,
    progress: bool = True,
) -> int:
    """Simulate the missing brute-force outcomes into ``store``; returns how many."""
    skey = settings.key()
    store.put_settings_meta(skey, settings.as_dict())
    for d in designs:
        store.put_design_meta(design_key(d), d.as_dict())
    for name in object_names:
        meta = {"key": name, "hypothesis_set": hypothesis_set}
        store.put_object_meta(set_object_key(name, hypothesis_set), meta)
    tasks = plan_tasks(store, designs, object_names, settings, hypothesis_set=hypothesis_set)
    return execute_tasks(
        tasks,
        store,
        skey,
        lambda name: set_object_key(name, hypothesis_set),
        executor,
        progress,
        label="brute-force grasps",
    )


# ----------------------------------------------------------------------------- GQMs
@dataclass(frozen=True)
class Scored:
    """One drawn FC grasp and its GQMs."""

    object_name: str
    """Object key."""
    design: ThumbDesign
    """The design."""
    gh_id: str
    """Hypothesis id."""
    outcome: GraspOutcome
    """The stored outcome (q, contacts, ``extra['T_object_palm']``)."""
    values: dict[str, float]
    """The ten GQMs."""


#: A GQM job: object key, design (cmc_deg, mcp_deg, cmc_tilt), (GH id, outcome) pairs, settings.
_Job = tuple[str, tuple[float, float, str], list[tuple[str, GraspOutcome]], GQMSettings]


@dataclass(frozen=True)
class _Pose:
    q: np.ndarray
    T_object_palm: np.ndarray
    contacts: object


def _gqm_job(job: _Job) -> list[dict[str, float]]:
    name, design, items, settings = job
    obj = load_object(name)
    hand = cached_kit(*design).hand
    out = []
    for _, o in items:
        pose = _Pose(o.q_final_rad, np.asarray(o.extra["T_object_palm"], float), o.contacts)
        out.append(compute_gqms(pose, obj, hand, settings))  # type: ignore[arg-type]
    return out


def draw_fc(
    store: ResultStore,
    name: str,
    design: ThumbDesign,
    settings: SimSettings,
    max_grasps: int,
    seed: int,
    hypothesis_set: str = BF_SET,
) -> list[tuple[str, GraspOutcome]]:
    """Up to ``max_grasps`` FC outcomes of (object, design), drawn reproducibly."""
    dkey = design_key(design)
    ids = hypotheses_of(name, hypothesis_set).ids
    got = store.get_many(dkey, set_object_key(name, hypothesis_set), settings.key(), ids)
    fc = sorted(k for k, o in got.items() if o.is_fc)
    rng = np.random.default_rng([seed, zlib.crc32(f"{name}|{dkey}".encode())])
    pick = sorted(rng.choice(len(fc), size=min(max_grasps, len(fc)), replace=False).tolist())
    return [(fc[i], got[fc[i]]) for i in pick]


@dataclass
class ScoreRun:
    """What ``score_grasps`` did."""

    scored: list[Scored]
    """Every drawn grasp with its GQMs, in the order drawn."""
    computed: int
    """Grasps whose GQMs were computed in this run (the others came from the store)."""


def _run_jobs(
    jobs: Sequence[_Job], workers: int
) -> Generator[tuple[int, list[dict[str, float]]], None, None]:
    """(job index, values) of every job as it finishes, over ``workers`` processes.

    At most ``2 · workers`` jobs are queued; on an exception (Ctrl-C included) the queued
    ones are cancelled and the pool is not waited for.
    """
    if workers <= 1 or len(jobs) <= 1:
        for i, job in enumerate(jobs):
            yield i, _gqm_job(job)
        return
    pool = ProcessPoolExecutor(min(workers, len(jobs)), mp_context=get_context("spawn"))
    try:
        pending: dict[Future, int] = {}
        queue = list(range(len(jobs)))[::-1]
        while queue or pending:
            while queue and len(pending) < 2 * workers:
                i = queue.pop()
                pending[pool.submit(_gqm_job, jobs[i])] = i
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for f in done:
                yield pending.pop(f), f.result()
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def score_grasps(
    drawn: dict[tuple[str, ThumbDesign], list[tuple[str, GraspOutcome]]],
    settings: GQMSettings | None = None,
    workers: int = 1,
    on_done: Callable[[int], None] | None = None,
    store: ResultStore | None = None,
    sim: SimSettings | None = None,
    hypothesis_set: str = BF_SET,
) -> ScoreRun:
    """GQMs of every drawn grasp, in jobs of ``GQM_CHUNK`` grasps over ``workers`` processes.

    With a ``store`` (and the ``sim`` settings the outcomes were simulated with), GQMs
    already stored for (design, object set key, ``sim.key()``, ``settings.key()``, GH id)
    are read instead of computed, and every finished job is stored in one transaction.
    ``on_done(n)`` is called after each job with its number of grasps.
    """
    s = settings or GQMSettings()
    if store is not None and sim is None:
        raise ValueError("score_grasps: a store needs the simulation settings (sim)")
    gkey = s.key()
    skey = sim.key() if sim is not None else ""
    keys = [k for k, v in drawn.items() if v]
    store_keys = {
        (name, d): (design_key(d), set_object_key(name, hypothesis_set)) for name, d in keys
    }
    values: dict[tuple[str, ThumbDesign], dict[str, dict[str, float]]] = {}
    jobs: list[_Job] = []
    job_key: list[tuple[str, ThumbDesign]] = []
    for name, d in keys:
        items = drawn[(name, d)]
        have: dict[str, dict[str, float]] = {}
        if store is not None:
            dkey, okey = store_keys[(name, d)]
            have = store.get_gqms(dkey, okey, skey, gkey, [gh for gh, _ in items])
        values[(name, d)] = have
        missing = [(gh, o) for gh, o in items if gh not in have]
        for start in range(0, len(missing), GQM_CHUNK):
            jobs.append(
                (name, (d.cmc_deg, d.mcp_deg, d.cmc_tilt), missing[start : start + GQM_CHUNK], s)
            )
            job_key.append((name, d))
    computed = 0
    with closing(_run_jobs(jobs, workers)) as finished:  # closed early: the pool is stopped
        for i, vals in finished:
            got = {gh: v for (gh, _), v in zip(jobs[i][2], vals, strict=True)}
            if store is not None:
                dkey, okey = store_keys[job_key[i]]
                store.put_gqms(dkey, okey, skey, gkey, got)
            values[job_key[i]].update(got)
            computed += len(got)
            if on_done:
                on_done(len(got))
    scored = [
        Scored(name, d, gh, o, values[(name, d)][gh])
        for name, d in keys
        for gh, o in drawn[(name, d)]
    ]
    return ScoreRun(scored, computed)


# ----------------------------------------------------------------------------- Table 3
@dataclass(frozen=True)
class Winner:
    """The best grasp of one (object, GQM) over all designs."""

    object_name: str
    gqm: str
    best: Scored
    """The winning grasp (its design is the winning design)."""
    correct: bool
    """The grasp meets the object's PP/CG correctness criteria (re-checked)."""
    reasons: tuple[str, ...]
    """Why not, when not correct."""


def recheck_type(sc: Scored, sim: SimSettings) -> tuple[bool, tuple[str, ...]]:
    """PP/CG correctness of a grasp from its stored contacts (``check_pp``/``check_cg``)."""
    spec = load_object(sc.object_name).spec
    c = sc.outcome.contacts
    if spec.grasp_type == "PP":
        v = check_pp(c)
    elif spec.grip_axis_object is None:
        return False, (f"{sc.object_name} is CG but has no grip axis",)
    else:
        hand = cached_kit(sc.design.cmc_deg, sc.design.mcp_deg, sc.design.cmc_tilt).hand
        R = np.asarray(sc.outcome.extra["T_object_palm"], float)[:3, :3]
        n_main = R @ hand.thumb_n_main_palm(sc.outcome.q_final_rad)
        v = check_cg(c, n_main, spec.grip_axis_object, sim.grasp_type)
    return bool(v.correct), tuple(v.reasons)


def find_winners(
    scored: Sequence[Scored], designs: Sequence[ThumbDesign], sim: SimSettings
) -> list[Winner]:
    """Per object and GQM, the highest-scoring grasp (ties: the earlier design, then id)."""
    order = {d: i for i, d in enumerate(designs)}
    winners: list[Winner] = []
    names = list(dict.fromkeys(s.object_name for s in scored))
    for name in names:
        mine = [s for s in scored if s.object_name == name]
        for g in GQM_NAMES:
            best = max(mine, key=lambda s, g=g: (s.values[g], -order[s.design], s.gh_id))
            ok, why = recheck_type(best, sim)
            winners.append(Winner(name, g, best, ok, why))
    return winners


def win_counts(winners: Sequence[Winner], designs: Sequence[ThumbDesign]) -> list[dict]:
    """Rows (cmc_deg, mcp_deg, wins, correct_wins), one per design, in the given order."""
    rows = []
    for d in designs:
        mine = [w for w in winners if w.best.design == d]
        rows.append(
            {
                "cmc_deg": d.cmc_deg,
                "mcp_deg": d.mcp_deg,
                "wins": len(mine),
                "correct_wins": sum(w.correct for w in mine),
            }
        )
    return rows


# ----------------------------------------------------------------------------- all of it
@dataclass
class ComparisonResult:
    """What ``run_comparison`` did."""

    n_gh: dict[str, int]
    """Brute-force hypotheses per object."""
    simulated: int
    """Outcomes simulated in this run (the rest came from the store)."""
    scored: list[Scored]
    """Every drawn FC grasp with its GQMs."""
    winners: list[Winner]
    """Per object and GQM, the winning grasp."""
    seconds: dict[str, float]
    """Wall time of each stage: 'simulate', 'gqm', 'winners'."""
    gqm_computed: int = 0
    """Grasps whose GQMs were computed in this run (the rest came from the store)."""


def _count_missing(
    store: ResultStore,
    drawn: dict[tuple[str, ThumbDesign], list[tuple[str, GraspOutcome]]],
    sim: SimSettings,
    gqm: GQMSettings,
    hypothesis_set: str,
) -> int:
    """Drawn grasps whose GQMs are not in the store yet (for the progress bar)."""
    skey, gkey = sim.key(), gqm.key()
    n = 0
    for (name, d), items in drawn.items():
        ids = [gh for gh, _ in items]
        okey = set_object_key(name, hypothesis_set)
        n += len(ids) - len(store.get_gqms(design_key(d), okey, skey, gkey, ids))
    return n


def run_comparison(
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    store: ResultStore,
    *,
    sim: SimSettings | None = None,
    gqm: GQMSettings | None = None,
    executor: Executor | None = None,
    max_grasps: int = 100,
    seed: int = 0,
    workers: int = 1,
    hypothesis_set: str = BF_SET,
    progress: bool = True,
) -> ComparisonResult:
    """Simulate and score the brute-force comparison and find the winners (module docstring);
    ``app.reports.table3.write_comparison`` writes its tables and picture."""
    import time

    sim = sim or SimSettings()
    t0 = time.perf_counter()
    n_gh = {n: len(hypotheses_of(n, hypothesis_set)) for n in object_names}
    simulated = simulate_bf(designs, object_names, store, sim, executor, hypothesis_set, progress)
    t1 = time.perf_counter()
    drawn = {
        (n, d): draw_fc(store, n, d, sim, max_grasps, seed, hypothesis_set)
        for n in object_names
        for d in designs
    }
    gqm = gqm or GQMSettings()
    total = _count_missing(store, drawn, sim, gqm, hypothesis_set) if progress else 0
    bar = Progress(total, "GQM grasps") if total else None
    run = score_grasps(drawn, gqm, workers, bar.update if bar else None, store, sim, hypothesis_set)
    scored = run.scored
    if bar:
        bar.close()
    t2 = time.perf_counter()
    winners = find_winners(scored, designs, sim) if scored else []
    return ComparisonResult(
        n_gh,
        simulated,
        scored,
        winners,
        {"simulate": t1 - t0, "gqm": t2 - t1, "winners": time.perf_counter() - t2},
        run.computed,
    )
