"""Explorer logic that needs no browser: state links, S_GAS table, map data."""

from __future__ import annotations

import pytest

from app.explorer.url_state import UrlState, UrlStateError, parse_query, probe_html


def test_link_round_trip() -> None:
    s = UrlState(30.0, 75.0, "chips_can", "17")
    assert s.query() == "?cmc=30&mcp=75&object=chips_can&gh=17"
    assert parse_query(s.query()) == s


def test_link_partial_and_ids() -> None:
    assert parse_query("") == UrlState()
    assert parse_query("?mcp=12.5") == UrlState(mcp_deg=12.5)
    s = parse_query("?gh=chips_can/r07/d0/t03&other=1")
    assert s.gh == "chips_can/r07/d0/t03"


def test_link_bad_number() -> None:
    with pytest.raises(UrlStateError, match="cmc"):
        parse_query("?cmc=abc")


def test_probe_writes_under_viser_prefix() -> None:
    html = probe_html("k1")
    assert "viser-user:k1" in html and "location.search" in html
    assert "viser-user:k1-webgl" in html and "UNMASKED_RENDERER_WEBGL" in html
    assert '"' not in html.split('onerror="', 1)[1].rstrip('">')  # the attribute stays whole


def test_software_renderers_are_told_from_gpus() -> None:
    from app.explorer.url_state import is_software_renderer

    software = [
        "ANGLE (Google, Vulkan 1.3.0 (SwiftShader Device (Subzero) (0x0000C0DE)), "
        "SwiftShader driver)",
        "llvmpipe (LLVM 15.0.6, 256 bits)",
        "Microsoft Basic Render Driver",
        "Software Rasterizer",
    ]
    gpus = [
        "ANGLE (NVIDIA, NVIDIA GeForce RTX 3060 (0x00002503) Direct3D11 vs_5_0 ps_5_0, D3D11)",
        "Apple M2",
        "Mesa Intel(R) UHD Graphics 620 (KBL GT2)",
        "AMD Radeon Pro 5500M OpenGL Engine",
    ]
    assert all(is_software_renderer(r) for r in software)
    assert not any(is_software_renderer(r) for r in gpus)


def test_map_image_and_table() -> None:
    import numpy as np

    from app.explorer.map_data import TOTAL, MapPoint, metric_value
    from app.explorer.panel_map import render_map, table_markdown
    from app.quality.scores import DesignScore, ObjectScore

    pts = [
        MapPoint(c, m, DesignScore({"a": ObjectScore(100, int(c + m), 10)}, {"a": "CG"}))
        for c in (0.0, 15.0, 45.0)
        for m in (0.0, 45.0, 90.0)
    ]
    assert metric_value(pts[0].score, TOTAL) == metric_value(pts[0].score, "a")
    img = render_map(pts, TOTAL, (20.0, 60.0), size=(400, 440))
    assert img.shape == (440, 400, 3) and img.dtype == np.uint8
    assert img.std() > 10
    md = table_markdown(pts)
    assert md.count("\n") == len(pts) + 1 and "| 45 | 90 |" in md


def test_score_table_partial() -> None:
    from app.explorer.live_score import ScoreSnapshot, snapshot_markdown
    from app.model.design import ThumbDesign

    s = ScoreSnapshot(
        ThumbDesign(15, 60),
        {"chips_can": (420, 300, 200), "washer": (30, 3, 1)},
        {"chips_can": 420, "washer": 1026},
        running="washer",
        state="computing",
    )
    md = snapshot_markdown(s)
    assert "CMC 15°, MCP 60°" in md and "computing 30/1026" in md
    assert "59.5" in md  # chips_can S_GAS = (200 + 50) / 420
    # no mean over the finished objects: the totals wait for every object
    assert "(partial)" not in md and "total **" not in md
    assert "once every object has a first sample (1 done" in md
    # the running object's estimate so far: (1 + 1) / 30 = 6.7 %, with its intervals
    assert "≈6.7 (95 % CI" in md and "certain 0–97" in md


def test_first_sample_gives_estimated_totals() -> None:
    """Once every object has a value or a random sample, PP, CG and total are shown as
    estimates whose bounds are the means of the objects' bounds (not the final bold total)."""
    from app.explorer.live_score import ObjectProgress, ScoreSnapshot, snapshot_markdown
    from app.model.design import ThumbDesign

    s = ScoreSnapshot(
        ThumbDesign(15, 60),
        {"chips_can": (420, 300, 200), "washer": (24, 12, 6)},
        {"chips_can": 420, "washer": 1026},
        state="computing",
    )
    p = ObjectProgress("washer", 1026, 24, 12, 6, computed=24, elapsed_s=0.5,
                       source="random sample")  # fmt: skip
    s.progress["washer"] = p
    est = s.estimates()
    assert est is not None and set(est) == {"pp", "cg", "total"}
    v, lo, hi = est["total"]
    w_lo, w_hi = p.interval_pct
    assert v == pytest.approx((59.52380952 + p.estimate_pct) / 2)
    assert lo == pytest.approx((59.52380952 + w_lo) / 2) and hi == pytest.approx(
        (59.52380952 + w_hi) / 2
    )
    assert lo < v < hi
    assert est["cg"] == pytest.approx((59.52380952,) * 3)
    md = snapshot_markdown(s)
    assert f"total ≈{v:.1f} ({lo:.1f}–{hi:.1f})" in md and "total **" not in md
    # a run-order (not random) sample gives the certain range instead of the interval
    s.progress["washer"] = ObjectProgress("washer", 1026, 24, 12, 6)
    est2 = s.estimates()
    assert est2 is not None
    assert est2["total"][1] == pytest.approx(
        (59.52380952 + s.progress["washer"].certain_pct[0]) / 2
    )


def test_link_tilt() -> None:
    s = UrlState(30.0, 75.0, "chips_can", "17", tilt="radial")
    assert s.query() == "?cmc=30&mcp=75&object=chips_can&gh=17&tilt=radial"
    assert parse_query(s.query()) == s
    assert parse_query("?cmc=10").tilt is None  # keep the current tilt (ulnar by default)
    assert parse_query("?tilt=ulnar").tilt == "ulnar"
    with pytest.raises(UrlStateError, match="tilt"):
        parse_query("?tilt=sideways")


def test_screenshot_passes_tilt(monkeypatch: pytest.MonkeyPatch) -> None:
    import argparse

    from app.explorer import screenshot

    seen: list[UrlState] = []

    def fake(out, state, *a, **k):  # noqa: ANN001, ANN002, ANN003, ANN202
        seen.append(state)
        return out

    monkeypatch.setattr(screenshot, "take_screenshot", fake)
    ns = argparse.Namespace(cmc=15.0, mcp=60.0, object="chips_can", gh=None, out="x.png",
                            size="400x300", view="map", store=None, cmc_tilt="radial")  # fmt: skip
    assert screenshot.screenshot_cli(ns) == 0
    assert seen[0].tilt == "radial" and "tilt=radial" in seen[0].query()


class _FakeStore:
    """The two store reads of the design map: described designs and their summaries."""

    def __init__(self, designs: dict[str, tuple[dict, dict]]) -> None:
        self._d = designs

    def designs(self) -> list[tuple[str, dict]]:
        return [(k, meta) for k, (meta, _) in self._d.items()]

    def summary(self, design_key: str, settings_key: str) -> dict:
        return self._d.get(design_key, ({}, {}))[1]


def _write_reference(path, objects, settings_key: str, rows) -> None:  # noqa: ANN001
    import json

    from app.model.hand.data import load_hand_dims
    from app.reports.report import write_table_csv
    from app.sim.hypothesis_sets import cached_hypotheses

    write_table_csv(rows, path / "table.csv", objects)
    meta = {
        "settings_key": settings_key,
        "hand_hash": load_hand_dims().content_hash,
        "engine_version": 3,
        "objects": list(objects),
        "n_gh": {k: len(cached_hypotheses(k)) for k in objects},
    }
    (path / "meta.json").write_text(json.dumps(meta))


def test_reference_layer(tmp_path) -> None:  # noqa: ANN001
    from typing import cast

    from app.explorer.live_score import read_snapshot, snapshot_markdown
    from app.explorer.map_data import TOTAL, map_points
    from app.explorer.panel_map import render_map, table_markdown
    from app.model.design import ThumbDesign
    from app.model.objects import load_object
    from app.quality.scores import DesignScore, ObjectScore
    from app.quality.settings import SimSettings
    from app.runs.keys import design_key, object_key
    from app.runs.store import ResultStore
    from app.sim.hypothesis_sets import cached_hypotheses

    objs = ("chips_can",)
    n = len(cached_hypotheses("chips_can"))
    types = {"chips_can": load_object("chips_can").spec.grasp_type}

    def score(n_fc: int, n_c: int) -> DesignScore:
        return DesignScore({"chips_can": ObjectScore(n, n_fc, n_c)}, types)

    ref_rows = [score(n // 2, n // 4).to_row(0, 0), score(n, n // 3).to_row(15, 60)]
    settings = SimSettings()
    good, bad = tmp_path / "good", tmp_path / "bad"
    good.mkdir()
    bad.mkdir()
    _write_reference(good, objs, settings.key(), ref_rows)
    _write_reference(bad, objs, "0123456789abcdef", ref_rows)

    # the user's store has (15, 60) complete: its score wins over the shipped row
    d = ThumbDesign(15, 60)
    store = cast(
        ResultStore,
        _FakeStore({design_key(d): (d.as_dict(), {object_key("chips_can"): (n, 7, 3)})}),
    )
    pts = map_points(store, objs, settings, ref_dir=good)
    assert [(p.cmc_deg, p.mcp_deg, p.source) for p in pts] == [
        (0.0, 0.0, "shipped"),
        (15.0, 60.0, "store"),
    ]
    assert pts[0].score.objects["chips_can"] == ObjectScore(n, n // 2, n // 4)  # counts exact
    assert pts[1].score.objects["chips_can"] == ObjectScore(n, 7, 3)
    md = table_markdown(pts)
    assert "| shipped |" in md and "| store |" in md and "docs/results" in md
    assert pts[0].label.endswith("(shipped)")
    assert render_map(pts, TOTAL, (0.0, 45.0), size=(300, 330)).shape == (330, 300, 3)

    # a mismatching settings key, another tilt or other settings: the table is ignored
    assert [p.source for p in map_points(store, objs, settings, ref_dir=bad)] == ["store"]
    assert [p.source for p in map_points(store, objs, settings, "radial", good)] == []

    # the Live S_GAS panel shows a shipped design's row at once, marked as such
    empty = cast(ResultStore, _FakeStore({}))
    snap = read_snapshot(empty, ThumbDesign(0, 0), objs, settings, ref_dir=good)
    assert snap.reference is not None and "shipped reference sweep" in snapshot_markdown(snap)
    assert read_snapshot(empty, ThumbDesign(0, 0), objs, settings, ref_dir=bad).reference is None
    assert read_snapshot(empty, ThumbDesign(5, 5), objs, settings, ref_dir=good).reference is None


def test_wilson_interval_known_values() -> None:
    from app.explorer.live_score import wilson_interval

    lo, hi = wilson_interval(5, 10)  # textbook: 0.2366 .. 0.7634
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)
    lo, hi = wilson_interval(0, 20)  # never below 0, upper 0.1611
    assert lo == 0.0 and hi == pytest.approx(0.1611, abs=1e-4)
    assert wilson_interval(0, 0) == (0.0, 1.0)


def test_object_progress_interval_and_time_left() -> None:
    from app.explorer.live_score import ObjectProgress

    # 100 of 400 done: 40 FC of which 30 correct -> credit 35 -> 35 %
    p = ObjectProgress("x", 400, 100, 40, 30, computed=50, elapsed_s=10.0)
    assert p.estimate_pct == pytest.approx(35.0)
    lo, hi = p.interval_pct
    assert lo < 35.0 < hi
    c_lo, c_hi = p.certain_pct
    assert (c_lo, c_hi) == (pytest.approx(8.75), pytest.approx(83.75))
    # the finite-population correction narrows the plain Wilson interval
    w = ObjectProgress("x", 10**9, 100, 40, 30)
    assert hi - lo < w.interval_pct[1] - w.interval_pct[0]
    assert p.rate_per_s == pytest.approx(5.0) and p.remaining_s == pytest.approx(60.0)
    # complete: the interval is the value itself
    done = ObjectProgress("x", 400, 400, 160, 120)
    assert done.interval_pct == (pytest.approx(35.0), pytest.approx(35.0))
    assert done.remaining_s is None  # nothing computed in this run: no rate
    # a subsample estimate feeds the same display, marked as such
    from app.explorer.live_score import progress_cell

    sgas, prog = progress_cell(ObjectProgress("x", 400, 40, 20, 10, source="random sample"), True)
    assert sgas.startswith("≈37.5 (95 % CI") and "(random sample)" in prog


def test_complete_store_differing_from_reference_says_which_is_used() -> None:
    from app.explorer.live_score import reference_diff_markdown
    from app.quality.scores import DesignScore, ObjectScore

    types = {"plastic_pear": "PP"}
    mine = DesignScore({"plastic_pear": ObjectScore(648, 300, 199)}, types)
    ref = DesignScore({"plastic_pear": ObjectScore(648, 300, 197)}, types)
    md = reference_diff_markdown(mine, ref)
    assert "plastic_pear 38.3 shipped vs 38.5 yours" in md and "used here" in md
    assert reference_diff_markdown(mine, mine) == "Same as the shipped reference sweep."


def test_screenshot_waits_for_complete_sgas() -> None:
    import threading
    import time
    from types import SimpleNamespace
    from typing import Any, cast

    from app.explorer.screenshot import wait_sgas_complete

    panel = SimpleNamespace(last=SimpleNamespace(state="computing"))
    session = cast(Any, SimpleNamespace(score_panel=panel))
    with pytest.raises(TimeoutError, match="--no-wait"):
        wait_sgas_complete(session, 0.3)
    t = threading.Timer(0.3, lambda: setattr(panel, "last", SimpleNamespace(state="complete")))
    t.start()
    t0 = time.monotonic()
    wait_sgas_complete(session, 5.0)
    assert 0.25 < time.monotonic() - t0 < 2.0
