"""The brute-force comparison of METHOD §6: simulate the brute-force set, score FC grasps with
the ten GQMs, and find, per object and GQM, the design whose best grasp scores highest.

Pipeline (``run_comparison``):

1. Simulate the brute-force hypotheses (``app.bruteforce``) of every object under every
   design with the sweep machinery (``app.sweep.Task``/``run_task`` and an executor). Results
   go to the same results store under the object key ``object_key(name) + ':bf'``; a rerun
   computes only what is missing.
2. Per object and design: the stored FC grasps, of which up to ``max_grasps`` are drawn at
   random (``numpy.random.default_rng([seed, crc32('<object>|<design key>')])``, ids sorted
   first, so the draw is reproducible and independent of the store's row order).
3. The ten GQMs of each drawn grasp (``app.gqm.compute_gqms``), in a process pool.
4. Table 3: per object and GQM, the design with the highest best-grasp value (ties: the
   first design in the order given); win counts per design; and whether each winning grasp
   meets the correctness criteria of the object's grasp type (``check_pp``/``check_cg``
   re-run on the stored contacts).
"""

from __future__ import annotations

import csv
import math
import zlib
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from app.design import ThumbDesign
from app.gqm import GQM_NAMES, GQMSettings, compute_gqms
from app.grasp_type import check_cg, check_pp
from app.objects import load_object
from app.settings import SimSettings
from app.store import GraspOutcome, ResultStore
from app.sweep import (
    Executor,
    Progress,
    Task,
    _kit,
    design_key,
    execute_tasks,
    hypotheses_of,
    set_object_key,
)

BF_SET = "brute_force"


# ----------------------------------------------------------------------------- simulation
def plan_bf_tasks(
    store: ResultStore,
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    settings: SimSettings,
    chunk: int = 60,
    hypothesis_set: str = BF_SET,
) -> list[Task]:
    """Tasks for every (design, object, brute-force GH) not yet in the store."""
    skey = settings.key()
    tasks: list[Task] = []
    for name in object_names:
        hyps = hypotheses_of(name, hypothesis_set)
        okey = set_object_key(name, hypothesis_set)
        present = [store.present_ids(design_key(d), okey, skey) for d in designs]
        for start in range(0, len(hyps), chunk):
            idx = range(start, min(start + chunk, len(hyps)))
            groups: dict[tuple[int, ...], list[ThumbDesign]] = {}
            for d, have in zip(designs, present, strict=True):
                missing = tuple(i for i in idx if hyps.ids[i] not in have)
                if missing:
                    groups.setdefault(missing, []).append(d)
            for missing, ds in groups.items():
                tasks.append(Task(name, missing, tuple(ds), settings, hypothesis_set))
    return tasks


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
    tasks = plan_bf_tasks(store, designs, object_names, settings, hypothesis_set=hypothesis_set)
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


@dataclass(frozen=True)
class _Pose:
    q: np.ndarray
    T_object_palm: np.ndarray
    contacts: object


def _gqm_job(
    job: tuple[str, tuple[float, float, str], list[tuple[str, GraspOutcome]], GQMSettings],
) -> list[dict[str, float]]:
    name, design, items, settings = job
    obj = load_object(name)
    hand = _kit(*design).hand
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


def score_grasps(
    drawn: dict[tuple[str, ThumbDesign], list[tuple[str, GraspOutcome]]],
    settings: GQMSettings | None = None,
    workers: int = 1,
    on_done: Callable[[int], None] | None = None,
) -> list[Scored]:
    """GQMs of every drawn grasp, one job per (object, design), over ``workers`` processes."""
    s = settings or GQMSettings()
    keys = [k for k, v in drawn.items() if v]
    jobs = [(name, (d.cmc_deg, d.mcp_deg, d.cmc_tilt), drawn[(name, d)], s) for name, d in keys]
    if workers > 1 and len(jobs) > 1:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            results = []
            for r in pool.map(_gqm_job, jobs):
                results.append(r)
                if on_done:
                    on_done(len(r))
    else:
        results = []
        for j in jobs:
            results.append(_gqm_job(j))
            if on_done:
                on_done(len(results[-1]))
    out: list[Scored] = []
    for (name, d), vals in zip(keys, results, strict=True):
        for (gh, o), v in zip(drawn[(name, d)], vals, strict=True):
            out.append(Scored(name, d, gh, o, v))
    return out


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
        hand = _kit(sc.design.cmc_deg, sc.design.mcp_deg, sc.design.cmc_tilt).hand
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


def _fmt(x: float) -> str:
    return f"{x:.4g}" if math.isfinite(x) else "nan"


def write_outputs(
    out: Path,
    scored: Sequence[Scored],
    winners: Sequence[Winner],
    designs: Sequence[ThumbDesign],
    n_gh: dict[str, int],
) -> list[Path]:
    """bruteforce_table.csv/.md, bruteforce_wins.csv and bruteforce_gqms.csv in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [
        out / n
        for n in (
            "bruteforce_table.csv",
            "bruteforce_table.md",
            "bruteforce_wins.csv",
            "bruteforce_gqms.csv",
        )
    ]
    with paths[0].open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["object", "gqm", "cmc_deg", "mcp_deg", "gh_id", "value", "correct", "reasons"])
        for x in winners:
            d = x.best.design
            w.writerow(
                [
                    x.object_name,
                    x.gqm,
                    d.cmc_deg,
                    d.mcp_deg,
                    x.best.gh_id,
                    _fmt(x.best.values[x.gqm]),
                    int(x.correct),
                    "; ".join(x.reasons),
                ]
            )
    names = list(dict.fromkeys(x.object_name for x in winners))
    cell = {(x.object_name, x.gqm): x for x in winners}
    lines = [
        "# Brute-force grasps: best design per GQM (METHOD §6, published Table 3 form)",
        "",
        "Cell: winning design `CMC/MCP` in degrees, its best value, and ✓ when that grasp "
        "meets the object's PP/CG correctness criteria (✗ otherwise).",
        "",
        "| GQM | " + " | ".join(f"{n} (N_GH {n_gh.get(n, 0)})" for n in names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for g in GQM_NAMES:
        cells = []
        for n in names:
            x = cell[(n, g)]
            d = x.best.design
            mark = "✓" if x.correct else "✗"
            cells.append(f"{d.cmc_deg:g}/{d.mcp_deg:g} ({_fmt(x.best.values[g])}) {mark}")
        lines.append(f"| {g} | " + " | ".join(cells) + " |")
    wins = win_counts(winners, designs)
    lines += [
        "",
        "## Wins per design",
        "",
        "| CMC (°) | MCP (°) | wins | correct wins |",
        "|---|---|---|---|",
    ]
    for r in sorted(wins, key=lambda r: -r["wins"]):
        if r["wins"]:
            lines.append(
                f"| {r['cmc_deg']:g} | {r['mcp_deg']:g} | {r['wins']} | {r['correct_wins']} |"
            )
    paths[1].write_text("\n".join(lines) + "\n")
    with paths[2].open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["cmc_deg", "mcp_deg", "wins", "correct_wins"])
        w.writeheader()
        w.writerows(wins)
    with paths[3].open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["object", "cmc_deg", "mcp_deg", "gh_id", "is_correct", *GQM_NAMES])
        for s in scored:
            w.writerow(
                [
                    s.object_name,
                    s.design.cmc_deg,
                    s.design.mcp_deg,
                    s.gh_id,
                    int(s.outcome.is_correct),
                    *(_fmt(s.values[g]) for g in GQM_NAMES),
                ]
            )
    return paths


def render_winners(path: Path, winners: Sequence[Winner], designs: Sequence[ThumbDesign]) -> Path:
    """One picture, a panel per object, of the most frequent winner's winning grasps."""
    import matplotlib.pyplot as plt

    from app.render import render_scene

    wins = win_counts(winners, designs)
    top = max(wins, key=lambda r: r["wins"])
    design = next(d for d in designs if (d.cmc_deg, d.mcp_deg) == (top["cmc_deg"], top["mcp_deg"]))
    mine: dict[str, Winner] = {}
    for w in winners:
        if w.best.design == design and w.object_name not in mine:
            mine[w.object_name] = w
    hand = _kit(design.cmc_deg, design.mcp_deg, design.cmc_tilt).hand
    tiles = []
    for name, w in mine.items():
        gqms = ", ".join(x.gqm for x in winners if x.best is w.best)
        tile = path.with_name(f"{path.stem}_{name}.png")
        render_scene(
            tile,
            hand=hand,
            q=w.best.outcome.q_final_rad,
            T_object_palm=np.asarray(w.best.outcome.extra["T_object_palm"], float),
            obj=load_object(name),
            contacts=w.best.outcome.contacts,
            show_axes=False,
            title=f"{name}: {w.best.gh_id.split('/', 1)[1]} — best {gqms}",
            size=(700, 560),
        )
        tiles.append(tile)
    cols = min(3, len(tiles))
    rows = math.ceil(len(tiles) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(7 * cols, 5.6 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, tile in zip(axes.ravel(), tiles, strict=False):
        ax.imshow(plt.imread(tile))
    fig.suptitle(
        f"Winning brute-force grasps of the most frequent winner, "
        f"CMC {design.cmc_deg:g}°, MCP {design.mcp_deg:g}° ({top['wins']} wins)",
        fontsize=16,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    for tile in tiles:
        tile.unlink()
    return path


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
    paths: list[Path]
    """Files written."""
    seconds: dict[str, float]
    """Wall time of each stage: 'simulate', 'gqm', 'write'."""


def run_comparison(
    designs: Sequence[ThumbDesign],
    object_names: Sequence[str],
    store: ResultStore,
    out: Path,
    *,
    sim: SimSettings | None = None,
    gqm: GQMSettings | None = None,
    executor: Executor | None = None,
    max_grasps: int = 100,
    seed: int = 0,
    workers: int = 1,
    hypothesis_set: str = BF_SET,
    progress: bool = True,
    picture: bool = True,
) -> ComparisonResult:
    """Simulate, score and tabulate the brute-force comparison (module docstring)."""
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
    total = sum(len(v) for v in drawn.values())
    bar = Progress(total, "GQM grasps") if progress and total else None
    scored = score_grasps(drawn, gqm, workers, bar.update if bar else None)
    if bar:
        bar.close()
    t2 = time.perf_counter()
    winners = find_winners(scored, designs, sim) if scored else []
    paths = write_outputs(out, scored, winners, designs, n_gh)
    if picture and winners:
        paths.append(render_winners(out / "bruteforce_winners.png", winners, designs))
    t3 = time.perf_counter()
    return ComparisonResult(
        n_gh,
        simulated,
        scored,
        winners,
        paths,
        {"simulate": t1 - t0, "gqm": t2 - t1, "write": t3 - t2},
    )
