"""The layer rule (docs/architecture.md), read from the source of every module of ``app``.

Layers, bottom to top: base (``errors``, ``hashing``, ``config_docs``) ← model ← sim ←
quality ← runs ← {reports, explorer, cli}. A module may import its own layer and the layers
below; of the three top packages, explorer may use reports, and cli may use both. Only the
explorer imports viser; only reports and the explorer import matplotlib. Imports inside
functions and under ``TYPE_CHECKING`` count too: a lazy import hides a cycle, it does not
remove it.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
APP = ROOT / "app"

#: Rank of each layer; a module may import ranks <= its own (top peers: see ALLOWED_PEERS).
RANK = {"base": 0, "model": 1, "sim": 2, "quality": 3, "runs": 4}
TOP = ("reports", "explorer", "cli")
#: Which top packages may import which other top packages.
ALLOWED_PEERS = {"reports": set(), "explorer": {"reports"}, "cli": {"reports", "explorer"}}
#: Third-party packages only some layers may import.
RESTRICTED = {"viser": {"explorer"}, "matplotlib": {"reports", "explorer"}}
RESTRICTED["mpl_toolkits"] = RESTRICTED["matplotlib"]


def layer_of(module: str) -> str:
    """'base', a layer name, or a top package name, of a dotted module name under ``app``."""
    parts = module.split(".")
    if len(parts) >= 2 and parts[1] in (*RANK, *TOP):
        return parts[1]
    return "base"


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imports_of(source: str, module: str, is_package: bool = False) -> set[str]:
    """Every module that ``source`` imports, at any depth (relative imports resolved)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base if is_package else base[:-1]
                base = base[: len(base) - (node.level - 1)]
                name = ".".join([*base, node.module] if node.module else base)
            else:
                name = node.module or ""
            out.add(name)
            # `from app.runs import gqm_compare` imports the submodule
            out.update(f"{name}.{a.name}" for a in node.names)
    return out


def app_modules() -> dict[str, set[str]]:
    """Module name -> imported names, for every module of ``app``."""
    mods: dict[str, set[str]] = {}
    for path in sorted(APP.rglob("*.py")):
        name = module_name(path)
        mods[name] = imports_of(path.read_text(), name, path.name == "__init__.py")
    return mods


def violations(mods: dict[str, set[str]]) -> list[str]:
    """Every import that breaks the layer rule, as readable lines."""
    known = set(mods)
    bad: list[str] = []
    for mod, imported in mods.items():
        mine = layer_of(mod)
        for imp in sorted(imported):
            top = imp.split(".")[0]
            if top in RESTRICTED and mine not in RESTRICTED[top]:
                bad.append(f"{mod} imports {imp} (only {sorted(RESTRICTED[top])} may)")
            if top != "app" or imp not in known:
                continue
            theirs = layer_of(imp)
            if theirs == mine:
                continue
            if mine in TOP:
                ok = theirs in RANK or theirs == "base" or theirs in ALLOWED_PEERS[mine]
            elif theirs in TOP:
                ok = False
            else:
                ok = RANK.get(theirs, 0) <= RANK.get(mine, 0)
            if not ok:
                bad.append(f"{mod} ({mine}) imports {imp} ({theirs}), a layer above")
    return bad


def cycles(mods: dict[str, set[str]]) -> list[list[str]]:
    """Import cycles among ``app`` modules (each as the list of its modules)."""
    graph = {m: sorted(i for i in imps if i in mods and i != m) for m, imps in mods.items()}
    # a package's own __init__ importing its submodules is not a cycle of ours
    for m in graph:
        graph[m] = [i for i in graph[m] if not m.startswith(i + ".")]
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return found


# ----------------------------------------------------------------------------- the checker
def test_checker_flags_an_upward_import() -> None:
    mods = {
        "app.sim.closing": {"app.runs.store", "numpy"},
        "app.runs.store": {"app.quality.outcome"},
        "app.quality.outcome": set(),
    }
    assert violations(mods) == [
        "app.sim.closing (sim) imports app.runs.store (runs), a layer above"
    ]


def test_checker_flags_ui_imports_and_top_peers() -> None:
    mods = {
        "app.quality.scores": {"matplotlib.pyplot"},
        "app.runs.sweep": {"viser"},
        "app.reports.plots": {"matplotlib", "app.explorer.session"},
        "app.explorer.session": {"viser", "app.reports.design_map", "app.cli.flags"},
        "app.reports.design_map": set(),
        "app.cli.flags": set(),
    }
    got = violations(mods)
    assert any("app.quality.scores imports matplotlib" in b for b in got)
    assert any("app.runs.sweep imports viser" in b for b in got)
    assert any("app.reports.plots (reports) imports app.explorer.session" in b for b in got)
    assert any("app.explorer.session (explorer) imports app.cli.flags" in b for b in got)
    assert len(got) == 4


def test_checker_finds_a_lazy_cycle() -> None:
    src_a = "def f():\n    from app.runs.b import x\n"
    mods = {
        "app.runs.a": imports_of(src_a, "app.runs.a"),
        "app.runs.b": imports_of("from app.runs.a import f\n", "app.runs.b"),
    }
    assert cycles(mods) == [["app.runs.a", "app.runs.b"]]


def test_relative_imports_resolve() -> None:
    assert "app.sim.closing" in imports_of("from .closing import x\n", "app.sim.simulate")
    assert "app.sim.closing" in imports_of("from .closing import x\n", "app.sim", True)


# ----------------------------------------------------------------------------- the code
def test_layers_import_downward_only() -> None:
    mods = app_modules()
    assert {layer_of(m) for m in mods} == {"base", *RANK, *TOP}
    assert violations(mods) == []


def test_no_import_cycles() -> None:
    assert cycles(app_modules()) == []


@pytest.mark.parametrize(
    "entry", ["app.runs.sweep", "app.runs.gqm_compare", "app.cli.flags", "app.runs.ray_executor"]
)
@pytest.mark.subprocess
def test_core_loads_without_ui(entry: str) -> None:
    """Importing the core (and the CLI's flag module) loads neither viser nor matplotlib."""
    code = (
        f"import sys, {entry};"
        "bad = [m for m in ('viser', 'matplotlib') if m in sys.modules];"
        "print(*bad);"
        "sys.exit(1 if bad else 0)"
    )
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr or r.stdout
