"""Flags built from the typed dataclasses (``ThumbDesign``, ``SimSettings``) and their field
docstrings, and the readers that turn parsed flags into designs, objects, stores, executors.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from app.model.design import ThumbDesign
from typing import Any, get_args, get_origin, get_type_hints

from app.config_docs import field_docs
from app.errors import SettingsError
from app.model.design import CMC_GRID_DEG, MCP_GRID_DEG, ThumbDesign


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
    from app.quality.settings import SimSettings

    for f in dataclasses.fields(SimSettings):
        _add_dataclass_flags(parser, get_type_hints(SimSettings)[f.name], f.name)


def settings_from_args(args: argparse.Namespace) -> Any:
    """Build ``SimSettings`` from parsed flags (unset flags keep their defaults)."""
    from app.quality.settings import SimSettings

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


#: Most values an angle list or range may give (a typo such as a step of 1e-9 would
#: otherwise allocate billions of designs before anything starts).
MAX_LIST_VALUES = 100_000


def parse_angle_list(text: str, name: str) -> list[float]:
    """'0,15,30' or a range with a step 'start:stop:step' (stop included) -> degrees.

    Range values are rounded to 1e-9° so that '0:0.3:0.1' gives exactly 0.3 (the same design
    key as a typed 0.3). Empty list items ('0,,15', '0,15,') and ranges of more than
    ``MAX_LIST_VALUES`` values raise ``SettingsError``."""
    forms = f"--{name} takes a comma list ('0,15,30') or start:stop:step ('0:45:5')"
    if ":" not in text:
        items = [x.strip() for x in text.split(",")]
        if not any(items):
            raise SettingsError(f"--{name} is empty; {forms}")
        if not all(items):
            k = items.index("") + 1
            raise SettingsError(f"--{name} {text!r}: item {k} is empty; {forms}")
    try:
        if ":" in text:
            a, b, s = (float(x) for x in text.split(":"))
            if not all(math.isfinite(x) for x in (a, b, s)) or s <= 0 or b < a:
                raise ValueError
            n = int(math.floor((b - a) / s + 1e-9)) + 1
        else:
            vals = [float(x) for x in text.split(",")]
            if not all(math.isfinite(v) for v in vals):
                raise ValueError
            return vals
    except ValueError:
        raise SettingsError(f"{forms}, got {text!r}") from None
    if n > MAX_LIST_VALUES:
        raise SettingsError(
            f"--{name} {text!r} gives {n:.3g} values; at most {MAX_LIST_VALUES} are "
            f"allowed: use a step of at least {(b - a) / (MAX_LIST_VALUES - 1):.3g}"
        )
    vals = [round(a + k * s, 9) for k in range(n)]
    return vals


def int_at_least(low: int, high: int | None = None):  # noqa: ANN201
    """An argparse ``type`` accepting integers in [low, high] (high None: no upper bound)."""

    def parse(text: str) -> int:
        rng = f">= {low}" if high is None else f"in [{low}, {high}]"
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer {rng}, got {text!r}") from None
        if v < low or (high is not None and v > high):
            raise argparse.ArgumentTypeError(f"must be an integer {rng}, got {v}")
        return v

    parse.__name__ = "int"
    return parse


def _probe_writable(folder: Path, flag: str) -> None:
    """Create ``folder`` (and parents) and check a file can be written in it."""
    import tempfile

    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".handbench-probe-"):
            pass
    except OSError as e:
        raise SettingsError(
            f"{flag} {str(folder)!r}: cannot write there ({e.strerror or e}); "
            "give a folder you can write to"
        ) from None


def check_out_dir(text: str, flag: str) -> Path:
    """An output folder: an existing or creatable, writable folder (created here)."""
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise SettingsError(f"{flag} {text!r} is a file, not a folder; give a folder name")
    _probe_writable(p, flag)
    return p


def check_out_file(text: str, flag: str, extensions: tuple[str, ...]) -> Path:
    """An output file: a known extension, not a folder, in a writable (created) folder."""
    p = Path(text)
    known = ", ".join(extensions)
    if not text or p.is_dir():
        raise SettingsError(
            f"{flag} {text!r} is a folder; give a file name ending in one of {known}"
        )
    if p.suffix.lower() not in extensions:
        raise SettingsError(
            f"{flag} {text!r}: unknown picture extension {p.suffix or '(none)'!r}; valid: {known}"
        )
    _probe_writable(p.parent, flag)
    return p


def designs_from_args(args: argparse.Namespace) -> list[ThumbDesign]:
    """Designs of --cmc × --mcp (default: the 28 published ones), CMC-major."""
    cmcs = parse_angle_list(args.cmc, "cmc") if args.cmc else list(CMC_GRID_DEG)
    mcps = parse_angle_list(args.mcp, "mcp") if args.mcp else list(MCP_GRID_DEG)
    return [ThumbDesign(c, m) for c in cmcs for m in mcps]


@contextlib.contextmanager
def open_executor(args: argparse.Namespace) -> Iterator[Any]:
    """The executor of --executor/--workers/--address, closed on exit."""
    from app.runs.sweep import make_executor

    ex = make_executor(args.executor, args.workers, args.address)
    try:
        yield ex
    finally:
        ex.close()


def objects_from_args(names: list[str] | None) -> list[str]:
    from app.model.objects import OBJECT_KEYS, load_object

    if not names:
        return list(OBJECT_KEYS)
    for n in names:
        load_object(n)  # UnknownObjectError lists the valid keys
    return names


def open_store(args: argparse.Namespace):  # noqa: ANN202
    from app.errors import StoreError
    from app.runs.store import ResultStore, default_store_path

    path = Path(args.store) if args.store else default_store_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise StoreError(
            f"--store {str(path)!r}: cannot create its folder ({e.strerror or e})"
        ) from None
    return ResultStore(path)


def add_run_flags(s: argparse.ArgumentParser, workers_help: str) -> None:
    """Flags of every command that simulates: workers, executor, store, and the settings."""
    s.add_argument("--workers", type=int_at_least(1), default=None, help=workers_help + ", >= 1")
    s.add_argument(
        "--executor",
        choices=("local", "inline", "ray"),
        default="local",
        help="local process pool (default; a crashing worker fails only its task), inline "
        "(this process: no crash containment, for debugging and profiling), or a Ray cluster",
    )
    s.add_argument("--address", help="Ray cluster address (with --executor ray)")
    s.add_argument("--store", help="results database (default ~/.cache/handbench/results.sqlite)")
    add_settings_flags(s)
