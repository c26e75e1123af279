"""Does a fresh S_GAS computation match the shipped reference table (docs/results)?

Usage: PYTHONPATH=. .venv/bin/python benchmarks/check_reference_match.py \
    [--executor inline|local] [--cmc 0] [--mcp 45] [--object plastic_pear]

Computes one design on one object into a fresh store under build/ and prints its counts
beside the shipped table's.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from app.explorer.reference import reference_score
from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.executors import Executor, InlineExecutor, LocalExecutor
from app.runs.store import ResultStore
from app.runs.sweep import run_sweep

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--executor", choices=("inline", "local"), default="inline")
    ap.add_argument("--cmc", type=float, default=0.0)
    ap.add_argument("--mcp", type=float, default=45.0)
    ap.add_argument("--object", default="plastic_pear")
    a = ap.parse_args()
    path = ROOT / "build" / f"check_reference_{a.executor}.sqlite"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.unlink(missing_ok=True)
    store = ResultStore(path)
    ex: Executor = InlineExecutor() if a.executor == "inline" else LocalExecutor(2)
    t = time.perf_counter()
    res = run_sweep([ThumbDesign(a.cmc, a.mcp)], [a.object], settings=SimSettings(),
                    store=store, executor=ex, progress=False)  # fmt: skip
    ex.close()
    assert res is not None
    ref = reference_score(a.cmc, a.mcp, [a.object], SimSettings())
    print(f"{a.executor}: {time.perf_counter() - t:.1f} s")
    print(
        "fresh  ",
        res.scores[0].objects[a.object],
        f"{res.scores[0].objects[a.object].sgas_pct:.2f}",
    )
    if ref is None:
        print("shipped: no row (not a shipped design, or other settings)")
    else:
        print("shipped", ref.objects[a.object], f"{ref.objects[a.object].sgas_pct:.2f}")


if __name__ == "__main__":
    main()
