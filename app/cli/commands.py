"""The ``handbench`` subcommands: each reads its parsed flags and returns an exit code."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.model.design import ThumbDesign
    from app.quality.settings import SimSettings

from app.cli.flags import (
    check_out_dir,
    check_out_file,
    designs_from_args,
    objects_from_args,
    open_executor,
    open_store,
    settings_from_args,
)
from app.errors import SettingsError
from app.model.design import ThumbDesign

#: Picture formats ``render`` writes (matplotlib's, limited to the common ones).
PICTURE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".pdf", ".svg")


def cmd_serve(args: argparse.Namespace) -> int:
    from app.explorer.server import serve

    serve(host=args.host, port=args.port, store_path=args.store)
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    from app.reports.pictures import render_hand, render_object

    design = ThumbDesign(args.cmc, args.mcp, args.cmc_tilt)
    if args.object:
        objects_from_args([args.object])
    if args.gh is not None and not args.object:
        raise SettingsError("--gh needs --object")
    settings = settings_from_args(args)
    out = check_out_file(args.out, "--out", PICTURE_EXTENSIONS)
    if args.gh is not None:
        from app.reports.grasp_view import PICKS, pick_hypothesis, render_grasp

        gh: str | int = args.gh
        if args.gh in PICKS:
            with open_store(args) as store:
                gh = pick_hypothesis(store, design, args.object, settings, args.gh)
        elif args.gh.isdigit():
            gh = int(args.gh)
        print(render_grasp(out, design, args.object, gh, settings))
    elif args.object:
        render_object(out, args.object, cmc_deg=design.cmc_deg, mcp_deg=design.mcp_deg)
    else:
        render_hand(out, design.cmc_deg, design.mcp_deg)
    print(f"wrote {out}")
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from app.runs.sweep import run_sweep

    design = ThumbDesign(args.cmc, args.mcp, args.cmc_tilt)
    names = objects_from_args(args.object)
    settings = settings_from_args(args)
    with open_store(args) as store:
        with open_executor(args) as ex:
            res = run_sweep(
                [design],
                names,
                settings=settings,
                store=store,
                executor=ex,
                progress=not args.json and sys.stderr.isatty(),
                gh_stride=args.gh_stride,
            )
    assert res is not None
    score = res.scores[0]
    doc = score.to_json_dict(design.cmc_deg, design.mcp_deg, settings.as_dict())
    if args.json:
        print(json.dumps(doc, indent=2))
        return 0
    print(
        f"design CMC {design.cmc_deg:g}°, MCP {design.mcp_deg:g}°"
        f"  ({res.computed} grasps simulated, {res.seconds:.1f} s)"
    )
    print(f"{'object':<14}{'N_GH':>6}{'FC %':>8}{'C %':>8}{'S_GAS %':>9}")
    for key, o in doc["objects"].items():
        print(f"{key:<14}{o['n_gh']:>6}{o['fc_pct']:>8.1f}{o['c_pct']:>8.1f}{o['sgas_pct']:>9.1f}")
    for k in ("pp_sgas_pct", "cg_sgas_pct", "total_sgas_pct"):
        v = doc[k]
        print(f"{k:<28}{'-' if v is None else f'{v:.1f}':>8}")
    return 0


def _write_sweep_meta(
    path: Path,
    settings: SimSettings,
    designs: list[ThumbDesign],
    names: list[str],
    n_gh: dict[str, int],
    args: argparse.Namespace,
    elapsed_s: float,
    res: object,
) -> None:
    """meta.json beside a sweep's table: what made it (the explorer's reference layer uses a
    shipped table only when its settings key, hand model and tilt match the session's)."""
    from app.model.hand.data import load_hand_dims
    from app.quality.settings import ENGINE_VERSION

    tilts = sorted({d.cmc_tilt for d in designs})
    meta = {
        "settings_key": settings.key(),
        "hand_hash": load_hand_dims().content_hash,
        "engine_version": ENGINE_VERSION,
        "cmc_tilt": tilts[0] if len(tilts) == 1 else tilts,
        "objects": names,
        "n_gh": n_gh,
        "gh_stride": args.gh_stride,
        "executor": args.executor,
        "grasps_simulated": getattr(res, "computed", None),
        "elapsed_s": round(elapsed_s, 1),
        "produced_by": "handbench " + " ".join(sys.argv[1:]),
    }
    path.write_text(json.dumps(meta, indent=2))


def cmd_sweep(args: argparse.Namespace) -> int:
    from app.model.objects import load_object
    from app.reports.plots import plot_bars, plot_contour, plot_lines
    from app.reports.report import write_table_csv, write_table_md
    from app.runs.sweep import run_sweep
    from app.sim.hypothesis_sets import cached_hypotheses

    designs = designs_from_args(args)
    names = objects_from_args(args.object)
    settings = settings_from_args(args)
    out = check_out_dir(args.out, "--out")
    t0 = time.perf_counter()
    with open_store(args) as store:
        with open_executor(args) as ex:
            res = run_sweep(
                designs,
                names,
                settings=settings,
                store=store,
                executor=ex,
                chunk=args.chunk,
                gh_stride=args.gh_stride,
            )
    assert res is not None
    rows = [s.to_row(d.cmc_deg, d.mcp_deg) for d, s in zip(res.designs, res.scores, strict=True)]
    names_disp = {k: load_object(k).spec.name for k in names}
    types = {k: load_object(k).spec.grasp_type for k in names}
    n_gh = {k: len(cached_hypotheses(k).ids[:: args.gh_stride]) for k in names}
    write_table_csv(rows, out / "table.csv", object_keys=names)
    write_table_md(rows, out / "table.md", names_disp, types, n_gh)
    plot_lines(rows, out / "lines.png")
    plot_contour(rows, out / "contour.png")
    plot_bars(rows, out / "bars.png", names_disp, n_gh)
    (out / "settings.json").write_text(json.dumps(settings.as_dict(), indent=2))
    elapsed = time.perf_counter() - t0
    _write_sweep_meta(out / "meta.json", settings, designs, names, n_gh, args, elapsed, res)
    best = max(rows, key=lambda r: -1.0 if r["total_sgas_pct"] is None else r["total_sgas_pct"])
    print(
        f"{len(designs)} designs x {len(names)} objects: {res.computed} grasps simulated in "
        f"{elapsed:.1f} s"
    )
    total = best["total_sgas_pct"]
    print(
        f"best design: CMC {best['cmc_deg']:g}°, MCP {best['mcp_deg']:g}° "
        f"(total S_GAS {'-' if total is None else f'{total:.1f}'} %)"
    )
    print(f"wrote {out}/table.csv, table.md, lines.png, contour.png, bars.png")
    return 0


def cmd_bruteforce(args: argparse.Namespace) -> int:
    import os

    from app.quality.gqm import GQMSettings
    from app.reports.table3 import write_comparison
    from app.runs.gqm_compare import run_comparison

    designs = designs_from_args(args)
    names = objects_from_args(args.object)
    settings = settings_from_args(args)
    out = check_out_dir(args.out, "--out")
    hset = "brute_force_nodup" if args.drop_duplicate_roll else "brute_force"
    gqm = GQMSettings(
        mu=settings.fc.mu, n_edges=settings.fc.n_edges, wrench_contacts=args.wrench_contacts
    )
    t0 = time.perf_counter()
    with open_store(args) as store:
        with open_executor(args) as ex:
            res = run_comparison(
                designs,
                names,
                store,
                sim=settings,
                gqm=gqm,
                executor=ex,
                max_grasps=args.max_grasps,
                seed=args.seed,
                workers=args.workers or os.cpu_count() or 1,
                hypothesis_set=hset,
                progress=sys.stderr.isatty(),
            )
    t_write = time.perf_counter()
    paths = write_comparison(res, designs, out, picture=not args.no_picture)
    sec = {**res.seconds, "write": time.perf_counter() - t_write}
    print(
        f"{len(designs)} designs x {len(names)} objects, brute-force GHs per object: "
        + ", ".join(f"{k} {v}" for k, v in res.n_gh.items())
    )
    print(
        f"{res.simulated} grasps simulated ({sec['simulate']:.1f} s), {len(res.scored)} FC "
        f"grasps scored, GQMs of {res.gqm_computed} computed, the rest from the store "
        f"({sec['gqm']:.1f} s), tables ({sec['write']:.1f} s); "
        f"total {time.perf_counter() - t0:.1f} s"
    )
    md = next((q for q in paths if q.suffix == ".md"), None)
    if md is not None:
        print(md.read_text())
    print("wrote " + ", ".join(str(q) for q in paths))
    return 0


def _parse_rotate(text: str | None) -> tuple[float, float, float] | None:
    if text is None:
        return None
    try:
        a = tuple(float(x) for x in text.split(","))
    except ValueError:
        a = ()
    if len(a) != 3 or not all(math.isfinite(x) for x in a):
        raise SettingsError(f"--rotate takes three angles 'rx,ry,rz' in degrees, got {text!r}")
    return a  # type: ignore[return-value]


def cmd_objects(args: argparse.Namespace) -> int:
    from app.model.objects import OBJECT_KEYS, available_keys, import_object, load_object
    from app.model.objects.importer import user_objects_dir

    if args.objects_cmd == "import":
        rotate = _parse_rotate(args.rotate)
        folder = check_out_dir(args.save_to or str(user_objects_dir()), "--save-to")
        obj = import_object(
            args.path,
            like=args.like,
            units=args.units,
            key=args.key,
            allow_open=args.allow_open,
            save_to=folder,
            up=args.up,
            rotate_deg=rotate,
        )
        b = obj.mesh.bounds
        print(
            f"imported {obj.spec.key} ({args.path}) like {args.like}: "
            f"{len(obj.mesh.faces)} faces, size {(b[1] - b[0]).round(1).tolist()} mm, "
            f"saved in {folder}"
        )
        # the distance field of the saved file (what every later process loads), built now
        # so that the first evaluation does not pay for it
        from app.model.objects.model import object_from_file

        saved = object_from_file(Path(folder) / f"{obj.spec.key}.toml", obj.spec.key)
        built_s, where = saved.prepare_distance_field()
        if built_s is not None:
            print(f"distance field built in {built_s:.1f} s, cached in {where}")
        elif where is not None:
            print(f"distance field found in the cache ({where})")
        # and its palm stages (every design's shared part, docs/cost-model.md) for the
        # default settings, so that a design on the scan costs what it does on a built-in
        if args.no_palm_stages:
            return 0
        from app.model.objects.model import register_object
        from app.runs.palm_cache import build_tables, cache_dir

        register_object(saved)  # the saved file's object: what every later process loads
        for name, n, dt, cached in build_tables((saved.spec.key,)):
            state = "found in the cache" if cached else f"built in {dt:.1f} s"
            print(f"palm stages of {name}: {n} hypotheses {state} ({cache_dir()})")
        return 0
    for k in available_keys():
        o = load_object(k)
        b = o.mesh.bounds
        src = (
            ""
            if k in OBJECT_KEYS
            else f"  (from {o.spec.shape.get('imported_from', o.spec.source)})"
        )
        print(
            f"{k:<14} {o.spec.grasp_type}  N_GH {o.spec.setup.n_gh:>5}  "
            f"size {(b[1] - b[0]).round(1).tolist()} mm  {o.spec.name}{src}"
        )
    return 0


def cmd_screenshot(args: argparse.Namespace) -> int:
    from app.explorer.screenshot import parse_size, screenshot_cli

    parse_size(args.size)
    check_out_file(args.out, "--out", (".png", ".jpg", ".jpeg"))
    return screenshot_cli(args)


def cmd_validate(args: argparse.Namespace) -> int:
    from app.reports.validate import (
        agreement,
        agreement_markdown,
        read_score_table,
        write_agreement_csv,
    )

    ours = read_score_table(args.table)
    ref = read_score_table(args.reference)
    ag = agreement(ours, ref)
    text = agreement_markdown(ag)
    print(text)
    if args.out:
        from app.reports.validate_plots import plot_contour_pair, plot_lines_overlay

        out = Path(args.out)
        if out.exists() and not out.is_dir():
            raise SettingsError(f"--out {out} is a file; give a folder")
        out.mkdir(parents=True, exist_ok=True)
        (out / "agreement.md").write_text(text + "\n")
        paths = [out / "agreement.md", write_agreement_csv(ag, out / "agreement.csv")]
        if "total_sgas" in [m.measure for m in ag.measures]:
            paths += [
                plot_contour_pair(ag, out / "contour_pair.png"),
                plot_lines_overlay(ag, out / "lines_overlay.png"),
            ]
        print("wrote " + ", ".join(str(q) for q in paths))
    return 0
