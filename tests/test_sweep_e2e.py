"""End to end through the CLI: a small sweep, kill -9 mid-run, resume, same table."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from app.cli import main
from app.model.design import ThumbDesign
from app.quality.settings import SimSettings
from app.runs.keys import design_key, object_key
from app.runs.store import ResultStore
from app.sim.hypothesis_sets import cached_hypotheses

ARGS = [
    "--cmc",
    "0,45",
    "--mcp",
    "45",
    "--object",
    "small_marker",
    "chips_can",
    "--gh-stride",
    "23",
    "--chunk",
    "4",
]


def run_cli(tmp: Path, out: str, store: str, workers: str = "2") -> None:
    assert (
        main(
            [
                "sweep",
                *ARGS,
                "--workers",
                workers,
                "--out",
                str(tmp / out),
                "--store",
                str(tmp / store),
            ]
        )
        == 0
    )


@pytest.mark.slow
def test_small_sweep_writes_tables_and_plots(tmp_path: Path, capsys) -> None:
    run_cli(tmp_path, "a", "a.sqlite", workers="1")
    out = tmp_path / "a"
    for f in ("table.csv", "table.md", "lines.png", "contour.png", "bars.png"):
        assert (out / f).stat().st_size > 0, f
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert [(float(r["cmc_deg"]), float(r["mcp_deg"])) for r in rows] == [(0, 45), (45, 45)]
    for r in rows:
        for k in ("small_marker_sgas_pct", "chips_can_sgas_pct", "total_sgas_pct"):
            assert 0.0 <= float(r[k]) <= 100.0
    # a can wrap is force closure for some design (the c = 45 open thumb blocks it, see docs)
    assert max(float(r["chips_can_fc_pct"]) for r in rows) > 0
    assert "best design" in capsys.readouterr().out
    # a rerun computes nothing and prints the same table
    before = (out / "table.csv").read_text()
    run_cli(tmp_path, "a", "a.sqlite", workers="1")
    assert (out / "table.csv").read_text() == before
    assert "0 grasps simulated" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.pool
def test_kill_minus_nine_then_resume_gives_the_same_table(tmp_path: Path) -> None:
    run_cli(tmp_path, "ref", "ref.sqlite")
    store = tmp_path / "killed.sqlite"
    cmd = [
        sys.executable,
        "-m",
        "app.cli",
        "sweep",
        *ARGS,
        "--workers",
        "2",
        "--out",
        str(tmp_path / "killed"),
        "--store",
        str(store),
        "--chunk",  # one hypothesis a task: stored a few at a time, so a poll sees it mid-way
        "1",
    ]
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True
    )
    deadline = time.time() + 300  # generous: a loaded machine starts the workers slowly
    # wait until some, but not all, outcomes are stored, then kill the whole process group
    stored = 0
    while time.time() < deadline:
        time.sleep(0.02)  # the whole sweep takes well under a second once the workers run
        if store.exists():
            try:
                with ResultStore(store, readonly=True) as st:
                    stored = sum(
                        st.count(design_key(ThumbDesign(c, 45)), object_key(k), SimSettings().key())
                        for c in (0, 45)
                        for k in ("small_marker", "chips_can")
                    )
            except Exception:  # noqa: BLE001 - the db may be mid-creation
                stored = 0
        if stored > 0 or proc.poll() is not None:
            break
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    total = 2 * sum(len(cached_hypotheses(k).ids[::23]) for k in ("small_marker", "chips_can"))
    assert 0 < stored < total, (stored, total)  # really interrupted mid-sweep
    run_cli(tmp_path, "killed", "killed.sqlite")
    ref = (tmp_path / "ref" / "table.csv").read_text()
    assert (tmp_path / "killed" / "table.csv").read_text() == ref
    with ResultStore(store, readonly=True) as st:
        for c in (0, 45):
            for k in ("small_marker", "chips_can"):
                n = st.count(design_key(ThumbDesign(c, 45)), object_key(k), SimSettings().key())
                assert n == len(cached_hypotheses(k).ids[::23])  # none missing, none twice
