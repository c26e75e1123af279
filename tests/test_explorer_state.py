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


def test_map_image_and_table() -> None:
    import numpy as np

    from app.explorer.map_data import TOTAL, MapPoint, metric_value
    from app.explorer.panel_map import render_map, table_markdown
    from app.scores import DesignScore, ObjectScore

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
    from app.design import ThumbDesign
    from app.explorer.panel_score import ScoreSnapshot, snapshot_markdown

    s = ScoreSnapshot(
        ThumbDesign(15, 60),
        {"chips_can": (420, 300, 200), "washer": (30, 3, 1)},
        {"chips_can": 420, "washer": 1026},
        running="washer",
        state="computing",
    )
    md = snapshot_markdown(s)
    assert "CMC 15°, MCP 60°" in md and "computing 30/1026" in md
    assert "(partial)" in md and "59.5" in md  # chips_can S_GAS = (200 + 50) / 420
