"""The ``handbench`` command line. Every flag for a design or a setting is generated from
the typed dataclasses (``ThumbDesign``, ``SimSettings``) and their field docstrings."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.design import ThumbDesign
    from app.settings import SimSettings
from typing import Any, get_args, get_origin, get_type_hints

from app.config_docs import field_docs
from app.design import CMC_GRID_DEG, MCP_GRID_DEG, ThumbDesign
from app.errors import HandbenchError, SettingsError


# ----------------------------------------------------------------------------- flag builders
def _add_dataclass_flags(parser: argparse.ArgumentParser, cls: type, group: str) -> None:
    docs = field_docs(cls)
    hints = get_type_hints(cls)
    g = parser.add_argument_group(group)
    for f in dataclasses.fields(cls):
        t = hints[f.name]
        flag = "--" + f.name.replace("_", "-")
        default = f.default if f.default is not dataclasses.MISSING else None
        helptext = f"{docs.get(f.name, '')} (default: {default})"
        if get_origin(t) is tuple:
            g.add_argument(
                flag,
                dest=f"{group}.{f.name}",
                type=float,
                nargs=len(get_args(t)),
                default=None,
                help=helptext,
            )
        elif get_args(t) and all(isinstance(a, str) for a in get_args(t)):  # Literal
            g.add_argument(
                flag, dest=f"{group}.{f.name}", choices=get_args(t), default=None, help=helptext
            )
        else:
            g.add_argument(
                flag,
                dest=f"{group}.{f.name}",
                type=t if t in (int, float) else str,
                default=None,
                help=helptext,
            )


def add_settings_flags(parser: argparse.ArgumentParser) -> None:
    """Flags for every field of ``SimSettings`` (closing, contact, fc, grasp_type)."""
    from app.settings import SimSettings

    for f in dataclasses.fields(SimSettings):
        _add_dataclass_flags(parser, get_type_hints(SimSettings)[f.name], f.name)


def settings_from_args(args: argparse.Namespace) -> Any:
    """Build ``SimSettings`` from parsed flags (unset flags keep their defaults)."""
    from app.settings import SimSettings

    parts: dict[str, Any] = {}
    for f in dataclasses.fields(SimSettings):
        cls = get_type_hints(SimSettings)[f.name]
        kw = {}
        for sf in dataclasses.fields(cls):
            v = getattr(args, f"{f.name}.{sf.name}", None)
            if v is not None:
                kw[sf.name] = tuple(v) if isinstance(v, list) else v
        parts[f.name] = cls(**kw)
    return SimSettings(**parts)


def add_design_flags(parser: argparse.ArgumentParser, required: bool = True) -> None:
    """--cmc, --mcp (degrees) and --cmc-tilt from ``ThumbDesign``."""
    docs = field_docs(ThumbDesign)
    parser.add_argument(
        "--cmc", type=float, required=required, metavar="DEG", help=docs["cmc_deg"] + " Range 0-45."
    )
    parser.add_argument(
        "--mcp", type=float, required=required, metavar="DEG", help=docs["mcp_deg"] + " Range 0-90."
    )
    parser.add_argument(
        "--cmc-tilt", choices=("ulnar", "radial"), default="ulnar", help=docs["cmc_tilt"]
    )


def parse_angle_list(text: str, name: str) -> list[float]:
    """'0,15,30' or a range with a step 'start:stop:step' (stop included) -> degrees.

    Range values are rounded to 1e-9° so that '0:0.3:0.1' gives exactly 0.3 (the same design
    key as a typed 0.3)."""
    forms = f"--{name} takes a comma list ('0,15,30') or start:stop:step ('0:45:5')"
    try:
        if ":" in text:
            a, b, s = (float(x) for x in text.split(":"))
            if not all(math.isfinite(x) for x in (a, b, s)) or s <= 0 or b < a:
                raise ValueError
            n = int(math.floor((b - a) / s + 1e-9))
            vals = [round(a + k * s, 9) for k in range(n + 1)]
        else:
            vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise SettingsError(f"{forms}, got {text!r}") from None
    if not vals:
        raise SettingsError(f"--{name} is empty; {forms}")
    return vals


def _designs_arg(args: argparse.Namespace) -> list[ThumbDesign]:
    """Designs of --cmc × --mcp (default: the 28 published ones), CMC-major."""
    cmcs = parse_angle_list(args.cmc, "cmc") if args.cmc else list(CMC_GRID_DEG)
    mcps = parse_angle_list(args.mcp, "mcp") if args.mcp else list(MCP_GRID_DEG)
    return [ThumbDesign(c, m) for c in cmcs for m in mcps]


@contextlib.contextmanager
def _executor(args: argparse.Namespace) -> Iterator[Any]:
    """The executor of --executor/--workers/--address, closed on exit."""
    from app.sweep import make_executor

    ex = make_executor(args.executor, args.workers, args.address)
    try:
        yield ex
    finally:
        ex.close()


def _objects_arg(names: list[str] | None) -> list[str]:
    from app.objects import OBJECT_KEYS, load_object

    if not names:
        return list(OBJECT_KEYS)
    for n in names:
        load_object(n)  # UnknownObjectError lists the valid keys
    return names


def _store(args: argparse.Namespace):  # noqa: ANN202
    from app.store import ResultStore, default_store_path

    return ResultStore(Path(args.store) if args.store else default_store_path())


# ----------------------------------------------------------------------------- commands
def cmd_serve(args: argparse.Namespace) -> int:
    from app.explorer.server import serve

    serve(host=args.host, port=args.port, store_path=args.store)
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    from app.render import render_hand, render_object

    design = ThumbDesign(args.cmc, args.mcp, args.cmc_tilt)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    if args.gh is not None:
        from app.grasp_view import PICKS, pick_hypothesis, render_grasp

        if not args.object:
            raise SettingsError("--gh needs --object")
        _objects_arg([args.object])
        settings = settings_from_args(args)
        gh: str | int = args.gh
        if args.gh in PICKS:
            with _store(args) as store:
                gh = pick_hypothesis(store, design, args.object, settings, args.gh)
        elif args.gh.isdigit():
            gh = int(args.gh)
        print(render_grasp(out, design, args.object, gh, settings))
    elif args.object:
        _objects_arg([args.object])
        render_object(out, args.object, cmc_deg=design.cmc_deg, mcp_deg=design.mcp_deg)
    else:
        render_hand(out, design.cmc_deg, design.mcp_deg)
    print(f"wrote {out}")
    return 0


def cmd_evaluate(args: argparse.Namespace) -> int:
    from app.sweep import run_sweep

    design = ThumbDesign(args.cmc, args.mcp, args.cmc_tilt)
    names = _objects_arg(args.object)
    settings = settings_from_args(args)
    with _store(args) as store:
        with _executor(args) as ex:
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
    from app.hand.data import load_hand_dims
    from app.settings import ENGINE_VERSION

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


def _add_run_flags(s: argparse.ArgumentParser, workers_help: str) -> None:
    """Flags of every command that simulates: workers, executor, store, and the settings."""
    s.add_argument("--workers", type=int, default=None, help=workers_help)
    s.add_argument(
        "--executor",
        choices=("local", "inline", "ray"),
        default="local",
        help="local process pool (default), inline, or a Ray cluster",
    )
    s.add_argument("--address", help="Ray cluster address (with --executor ray)")
    s.add_argument("--store", help="results database (default ~/.cache/handbench/results.sqlite)")
    add_settings_flags(s)


def cmd_sweep(args: argparse.Namespace) -> int:
    from app.objects import load_object
    from app.plots import plot_bars, plot_contour, plot_lines
    from app.report import write_table_csv, write_table_md
    from app.sweep import cached_hypotheses, run_sweep

    designs = _designs_arg(args)
    names = _objects_arg(args.object)
    settings = settings_from_args(args)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with _store(args) as store:
        with _executor(args) as ex:
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

    from app.gqm import GQMSettings
    from app.gqm.compare import run_comparison

    designs = _designs_arg(args)
    names = _objects_arg(args.object)
    settings = settings_from_args(args)
    if args.max_grasps < 1:
        raise SettingsError(f"--max-grasps must be >= 1, got {args.max_grasps}")
    hset = "brute_force_nodup" if args.drop_duplicate_roll else "brute_force"
    gqm = GQMSettings(
        mu=settings.fc.mu, n_edges=settings.fc.n_edges, wrench_contacts=args.wrench_contacts
    )
    out = Path(args.out)
    t0 = time.perf_counter()
    with _store(args) as store:
        with _executor(args) as ex:
            res = run_comparison(
                designs,
                names,
                store,
                out,
                sim=settings,
                gqm=gqm,
                executor=ex,
                max_grasps=args.max_grasps,
                seed=args.seed,
                workers=args.workers or os.cpu_count() or 1,
                hypothesis_set=hset,
                progress=sys.stderr.isatty(),
                picture=not args.no_picture,
            )
    print(
        f"{len(designs)} designs x {len(names)} objects, brute-force GHs per object: "
        + ", ".join(f"{k} {v}" for k, v in res.n_gh.items())
    )
    sec = res.seconds
    print(
        f"{res.simulated} grasps simulated ({sec['simulate']:.1f} s), {len(res.scored)} FC "
        f"grasps scored, GQMs of {res.gqm_computed} computed, the rest from the store "
        f"({sec['gqm']:.1f} s), tables ({sec['write']:.1f} s); "
        f"total {time.perf_counter() - t0:.1f} s"
    )
    md = next((q for q in res.paths if q.suffix == ".md"), None)
    if md is not None:
        print(md.read_text())
    print("wrote " + ", ".join(str(q) for q in res.paths))
    return 0


def cmd_objects(args: argparse.Namespace) -> int:
    from app.objects import OBJECT_KEYS, import_object, load_object

    if args.objects_cmd == "import":
        obj = import_object(
            args.path, like=args.like, units=args.units, key=args.key, save_to=args.save_to
        )
        b = obj.mesh.bounds
        print(
            f"imported {obj.spec.key} ({args.path}) like {args.like}: "
            f"{len(obj.mesh.faces)} faces, size {(b[1] - b[0]).round(1).tolist()} mm"
        )
        return 0
    for k in OBJECT_KEYS:
        o = load_object(k)
        b = o.mesh.bounds
        print(
            f"{k:<14} {o.spec.grasp_type}  N_GH {o.spec.setup.n_gh:>5}  "
            f"size {(b[1] - b[0]).round(1).tolist()} mm  {o.spec.name}"
        )
    return 0


def cmd_screenshot(args: argparse.Namespace) -> int:
    from app.explorer.screenshot import screenshot_cli

    return screenshot_cli(args)


# ----------------------------------------------------------------------------- parser
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="handbench",
        description="Design explorer and simulation benchmark for anthropomorphic hands.",
    )
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND")

    s = sub.add_parser("serve", help="run the design explorer (web UI)")
    s.add_argument("--host", default="127.0.0.1", help="interface to listen on (0.0.0.0: LAN)")
    s.add_argument("--port", type=int, default=8080, help="port (0: any free port)")
    s.add_argument("--store", help="results database (default ~/.cache/handbench/results.sqlite)")
    s.set_defaults(func=cmd_serve)

    s = sub.add_parser("render", help="off-screen picture of the hand (and an object)")
    add_design_flags(s)
    s.add_argument("--object", help="object key: show it with the hand at roll 0")
    s.add_argument(
        "--gh",
        help="simulate this hypothesis (id, index, or first-correct / "
        "first-fc / first-failed from the store) and draw the final grasp",
    )
    s.add_argument("--store", help="results database for --gh first-correct etc.")
    s.add_argument("--out", required=True, help="PNG file to write")
    add_settings_flags(s)
    s.set_defaults(func=cmd_render)

    for name, helptext, func in (
        ("evaluate", "FC %, C %, S_GAS % of one design", cmd_evaluate),
        ("sweep", "run many designs; write table.csv/md and plots", cmd_sweep),
    ):
        s = sub.add_parser(name, help=helptext)
        if name == "evaluate":
            add_design_flags(s)
            s.add_argument("--json", action="store_true", help="print JSON")
        else:
            s.add_argument("--cmc", help="CMC angles: '0,15,30,45' or '0:45:5' (default grid)")
            s.add_argument("--mcp", help="MCP angles: '0,15,...,90' or '0:90:5' (default grid)")
            s.add_argument("--out", default="out/sweep", help="output folder")
            s.add_argument("--chunk", type=int, default=60, help="hypotheses per task")
        s.add_argument("--object", nargs="+", help="object keys (default: all six)")
        s.add_argument(
            "--gh-stride",
            type=int,
            default=1,
            metavar="K",
            help="preview: only every K-th hypothesis of each object (default 1: "
            "all, as published)",
        )
        _add_run_flags(s, "processes (default: cores)")
        s.set_defaults(func=func)

    s = sub.add_parser("bruteforce", help="brute-force grasps: the ten GQMs, best design per GQM")
    s.add_argument("--cmc", help="CMC angles: '0,15,30,45' or '0:45:5' (default grid)")
    s.add_argument("--mcp", help="MCP angles: '0,15,...,90' or '0:90:5' (default grid)")
    s.add_argument("--out", default="out/bruteforce", help="output folder")
    s.add_argument("--object", nargs="+", help="object keys (default: all six)")
    s.add_argument(
        "--max-grasps",
        type=int,
        default=100,
        help="FC grasps drawn per object and design for the GQMs (default 100)",
    )
    s.add_argument("--seed", type=int, default=0, help="seed of the random draw")
    s.add_argument(
        "--drop-duplicate-roll",
        action="store_true",
        help="drop the roll 2π (a duplicate of 0) from the published roll list",
    )
    s.add_argument(
        "--wrench-contacts",
        choices=("patch", "link"),
        default="patch",
        help="Q_C1 contact points: every patch point (FC model, default) or one per "
        "link; Q_C2 always uses one per link (docs/bruteforce.md)",
    )
    s.add_argument("--no-picture", action="store_true", help="skip bruteforce_winners.png")
    _add_run_flags(s, "processes of both stages, simulation and GQMs (default: cores)")
    s.set_defaults(func=cmd_bruteforce)

    s = sub.add_parser("objects", help="list objects or import a mesh")
    osub = s.add_subparsers(dest="objects_cmd", required=True, metavar="ACTION")
    osub.add_parser("list", help="the shipped objects")
    imp = osub.add_parser("import", help="import an STL/OBJ/PLY mesh")
    imp.add_argument("path")
    imp.add_argument("--like", required=True, help="take the grasp set-up of this object")
    imp.add_argument("--units", choices=("mm", "m"), default="mm", help="units of the file")
    imp.add_argument("--key", help="key for the imported object (default: file name)")
    imp.add_argument("--save-to", help="folder to save it in (use with HANDBENCH_USER_OBJECTS)")
    s.set_defaults(func=cmd_objects)

    s = sub.add_parser("screenshot", help="headless browser screenshot of the explorer")
    add_design_flags(s)
    s.add_argument("--object", default="chips_can")
    s.add_argument("--gh", help="grasp hypothesis id or index to replay")
    s.add_argument("--out", required=True)
    s.add_argument("--size", default="1400x900", help="WxH pixels")
    s.add_argument(
        "--view",
        default="scene",
        choices=("scene", "map"),
        help="what to capture: the 3-D scene or the design map tab",
    )
    s.add_argument("--store", help="results database")
    s.set_defaults(func=cmd_screenshot)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except HandbenchError as e:
        print(f"handbench: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("handbench: interrupted (finished results are kept in the store)", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
