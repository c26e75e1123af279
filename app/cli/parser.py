"""The ``handbench`` command line: the parser of every subcommand, and ``main``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    pass

from app.cli.commands import (
    cmd_bruteforce,
    cmd_evaluate,
    cmd_objects,
    cmd_render,
    cmd_screenshot,
    cmd_serve,
    cmd_sweep,
    cmd_validate,
)
from app.cli.flags import add_design_flags, add_run_flags, add_settings_flags
from app.errors import HandbenchError

#: The published rows shipped with the repository (``handbench validate``'s default).
DEFAULT_REFERENCE = (
    Path(__file__).resolve().parents[2] / "docs" / "reference" / "published_sgas_cmc0_cmc30.csv"
)


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
        ("evaluate", "FC %%, C %%, S_GAS %% of one design", cmd_evaluate),
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
        add_run_flags(s, "processes (default: cores)")
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
    add_run_flags(s, "processes of both stages, simulation and GQMs (default: cores)")
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

    s = sub.add_parser(
        "validate", help="rank agreement of a score table with a reference (published) table"
    )
    s.add_argument("table", help="our table.csv (from handbench sweep)")
    s.add_argument(
        "--reference",
        default=str(DEFAULT_REFERENCE),
        help="reference table in the published form: cmc, mcp, per object fc/c/sgas "
        "(default: the published CMC 0/30 rows, docs/reference/)",
    )
    s.add_argument("--out", help="folder for agreement.md/.csv and the side-by-side pictures")
    s.set_defaults(func=cmd_validate)

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
    s.add_argument(
        "--no-wait",
        action="store_true",
        help="take the picture at once, without waiting for the Live S_GAS numbers",
    )
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
    except BrokenPipeError:  # e.g. `handbench objects list | head`
        sys.stderr.close()
        return 0
