"""The ``handbench`` command line: the parser of every subcommand, and ``main``."""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path
from typing import NoReturn

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
from app.cli.flags import add_design_flags, add_run_flags, add_settings_flags, int_at_least
from app.errors import HandbenchError

#: The published rows shipped with the repository (``handbench validate``'s default).
DEFAULT_REFERENCE = (
    Path(__file__).resolve().parents[2] / "docs" / "reference" / "published_sgas_cmc0_cmc30.csv"
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``handbench: error: <command>: <message>``, exit 2."""

    def error(self, message: str) -> NoReturn:
        where = self.prog.removeprefix("handbench").strip()
        hint = f"see 'handbench {where + ' ' if where else ''}--help'"
        print(
            f"handbench: error: {where + ': ' if where else ''}{message} ({hint})", file=sys.stderr
        )
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="handbench",
        description="Design explorer and simulation benchmark for anthropomorphic hands.",
    )
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND")

    s = sub.add_parser("serve", help="run the design explorer (web UI)")
    s.add_argument("--host", default="127.0.0.1", help="interface to listen on (0.0.0.0: LAN)")
    s.add_argument(
        "--port", type=int_at_least(0, 65535), default=8080, help="port 0-65535 (0: any free port)"
    )
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
    s.add_argument("--out", required=True, help="picture file to write (.png, .jpg, .pdf, .svg)")
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
            s.add_argument(
                "--chunk", type=int_at_least(1), default=60, help="hypotheses per task (>= 1)"
            )
        s.add_argument("--object", nargs="+", help="object keys (default: all six)")
        s.add_argument(
            "--gh-stride",
            type=int_at_least(1),
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
        type=int_at_least(1),
        default=100,
        help="FC grasps drawn per object and design for the GQMs (>= 1, default 100)",
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
    osub.add_parser("list", help="the shipped objects and the saved imports")
    imp = osub.add_parser("import", help="import an STL/OBJ/PLY mesh (a scan, a CAD model)")
    imp.add_argument("path")
    imp.add_argument("--like", required=True, help="take the grasp set-up of this object")
    imp.add_argument(
        "--units",
        choices=("mm", "cm", "m"),
        default=None,
        help="units of the file (default: guessed from the size, mm or m, and said)",
    )
    imp.add_argument("--key", help="key for the imported object (default: file name)")
    imp.add_argument(
        "--up",
        choices=("+x", "-x", "+y", "-y", "+z", "-z", "x", "y", "z"),
        help="the file axis that points up (e.g. y for a scan lying on its side)",
    )
    imp.add_argument(
        "--rotate",
        metavar="RX,RY,RZ",
        help="rotate the file first by these angles about x, y, z (degrees, in that order)",
    )
    imp.add_argument(
        "--allow-open",
        action="store_true",
        help="accept a surface with large holes (a scan open at the bottom): they are closed "
        "with flat caps, and volume, inside tests and signed distance use the capped surface",
    )
    imp.add_argument(
        "--save-to",
        help="folder to save it in (default: $HANDBENCH_USER_OBJECTS or "
        "~/.local/share/handbench/objects, where every command finds it)",
    )
    imp.add_argument(
        "--no-palm-stages",
        action="store_true",
        help="do not compute and cache the palm stages now (every design's shared part, "
        "seconds for a scan): the first runs on the object then compute them",
    )
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


def _one_line_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """Warnings reach the user as one line of words, without source paths."""
    text = " ".join(str(message).split())
    print(f"handbench: warning: {text}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = _one_line_warning
            return int(args.func(args) or 0)
    except HandbenchError as e:
        print(f"handbench: error: {' '.join(str(e).split())}", file=sys.stderr)
        return 2
    except OSError as e:  # a file or folder the user named (permissions, disk full...)
        if isinstance(e, BrokenPipeError):  # e.g. `handbench objects list | head`
            sys.stderr.close()
            return 0
        print(f"handbench: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("handbench: interrupted (finished results are kept in the store)", file=sys.stderr)
        return 130
    except Exception as e:
        if os.environ.get("HANDBENCH_DEBUG"):
            raise
        print(
            f"handbench: internal error: {type(e).__name__}: {' '.join(str(e).split())} "
            "(a bug: please report it; HANDBENCH_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 1
