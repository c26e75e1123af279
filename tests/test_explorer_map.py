"""The in-scene design map's picking (viser-free geometry) and its picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from app.explorer.map_pick import MAP_WXYZ, MapPlacement, nearest_design

P = MapPlacement(centre=(0.1, 2.0, 0.3), width=0.40, height=0.44)
SIZE = (800, 880)


def _quat_matrix(wxyz: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = wxyz
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def test_image_orientation_is_upright_facing_the_map_camera() -> None:
    R = _quat_matrix(MAP_WXYZ)
    assert np.allclose(R[:, 0], (1, 0, 0))  # image columns along +x (screen right)
    assert np.allclose(R[:, 1], (0, 0, -1))  # image rows downward
    assert np.allclose(R[:, 2], (0, 1, 0))  # seen by a camera looking along +y
    top = P.world_of_pixel(400, 0, SIZE)
    left = P.world_of_pixel(0, 440, SIZE)
    assert top[2] == pytest.approx(0.3 + 0.22) and left[0] == pytest.approx(0.1 - 0.2)


@pytest.mark.parametrize("px", [(0.5, 0.5), (400.0, 440.0), (799.0, 13.0), (123.4, 870.0)])
def test_ray_through_a_pixel_hits_that_pixel(px: tuple[float, float]) -> None:
    target = np.array(P.world_of_pixel(*px, SIZE))
    for origin in ((0.0, 1.2, 0.3), (0.4, 1.5, -0.2)):
        d = target - origin
        got = P.pixel_of_ray(origin, d / np.linalg.norm(d), SIZE)
        assert got is not None and np.allclose(got, px, atol=1e-6)


def test_ray_missing_the_map() -> None:
    assert P.pixel_of_ray((0.1, 1.0, 0.3), (0.0, -1.0, 0.0), SIZE) is None  # looking away
    assert P.pixel_of_ray((0.1, 1.0, 0.3), (1.0, 0.0, 0.0), SIZE) is None  # parallel
    d = np.array([0.5, 1.0, 0.0])
    assert P.pixel_of_ray((0.1, 1.0, 0.3), d / np.linalg.norm(d), SIZE) is None  # beside it


def test_nearest_design_within_radius() -> None:
    designs = [(0.0, 45.0), (15.0, 60.0), (30.0, 75.0)]
    assert nearest_design(designs, 28.0, 77.0, 10.0) == 2
    assert nearest_design(designs, 5.0, 49.0, 10.0) == 0
    assert nearest_design(designs, 45.0, 0.0, 10.0) is None
    assert nearest_design([], 0.0, 0.0, 10.0) is None


def test_scene_picture_pixels_map_back_to_degrees() -> None:
    from app.explorer.map_data import TOTAL, MapPoint
    from app.explorer.panel_map import render_base, with_star
    from app.quality.scores import DesignScore, ObjectScore

    pts = [
        MapPoint(c, m, DesignScore({"a": ObjectScore(10, 3 + int(c + m) % 5, 2)}, {"a": "PP"}))
        for c in (0.0, 15.0, 30.0, 45.0)
        for m in (0.0, 45.0, 90.0)
    ]
    small, big = render_base(pts, TOTAL), render_base(pts, TOTAL, scale=2.0)
    assert big.image.shape[:2] == (2 * small.image.shape[0], 2 * small.image.shape[1])
    for c, m in ((0.0, 0.0), (30.0, 45.0), (45.0, 90.0)):
        assert np.allclose(big.pixel(c, m), 2 * np.array(small.pixel(c, m)), atol=1.0)
        assert np.allclose(big.degrees(*big.pixel(c, m)), (c, m))
    starred = with_star(big, 30.0, 45.0)
    x, y = (int(round(v)) for v in big.pixel(30.0, 45.0))
    assert tuple(starred[y, x]) == (230, 20, 20)  # the star's red fill, at twice the size
    changed_big = int((starred != big.image).any(-1).sum())
    changed_small = int((with_star(small, 30.0, 45.0) != small.image).any(-1).sum())
    assert 3 * changed_small < changed_big < 5 * changed_small  # about 4x the pixels


@pytest.mark.subprocess
def test_server_initialises_image_encoders_before_any_tab(tmp_path: Path) -> None:
    """Tabs opening at once encode their first images in parallel threads; PIL's plugin
    imports racing there deadlocked sessions (never finished, never freed). The server
    imports them up front, in a fresh process as in ``handbench serve``."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    code = (
        "import PIL.Image as I; from app.explorer.server import ExplorerServer; "
        "assert I._initialized == 0, I._initialized; "
        "s = ExplorerServer('127.0.0.1', 0, sys.argv[1], objects=['chips_can'], workers=0); "
        "n = I._initialized; s.stop(); print(n)"
    )
    cmd = [sys.executable, "-c", "import sys; " + code, str(tmp_path / "s.sqlite")]
    out = subprocess.run(
        cmd, cwd=root, capture_output=True, text=True, timeout=120,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "2"  # every plugin imported


def test_last_tab_closing_empties_the_simulation_caches() -> None:
    """The contact caches hold every hand's link shapes (one hand per design change of any
    tab); the server empties them, and the kits, when no tab is left."""
    from app.explorer.server import drop_simulation_caches
    from app.model.hand.model import build_hand
    from app.sim import contacts
    from app.sim.simulate import cached_kit

    hand = build_hand(15.0, 60.0)
    for lk in hand.links[:3]:
        contacts._samples(lk.shape, 2.0)  # noqa: SLF001
        contacts._coarse(lk.shape, 2.0)  # noqa: SLF001
    cached_kit(15.0, 60.0, "ulnar")
    assert contacts._samples.cache_info().currsize >= 1  # noqa: SLF001
    drop_simulation_caches()
    assert contacts._samples.cache_info().currsize == 0  # noqa: SLF001
    assert contacts._coarse.cache_info().currsize == 0  # noqa: SLF001
    assert cached_kit.cache_info().currsize == 0


def test_last_tab_closing_empties_the_compiled_engine_caches() -> None:
    """The compiled contacts keep link tables per hand (one per design change): emptied too."""
    from app.explorer.server import drop_simulation_caches
    from app.model.hand.model import build_hand
    from app.sim.contacts_compiled import link_tables

    hand = build_hand(15.0, 60.0)
    link_tables(tuple(lk.shape for lk in hand.links[:3]), 1.0)
    assert link_tables.cache_info().currsize >= 1
    drop_simulation_caches()
    assert link_tables.cache_info().currsize == 0


def _warm_set_held(key: str) -> bool:
    """The compiled engine's per-object caches hold ``key``'s arrays, packed signed distance
    and piece spheres."""
    from app.model.objects import load_object
    from app.sim import closing_compiled, contacts_compiled, sdf_compiled

    obj = load_object(key)
    arr = closing_compiled._CACHE.get(id(obj))  # noqa: SLF001
    prog = sdf_compiled._CACHE.get(id(obj))  # noqa: SLF001
    if arr is None or prog is None or arr[0] is not obj or prog[0] is not obj:
        return False
    return id(arr[1]) in contacts_compiled._SPHERES  # noqa: SLF001


def _hand_caches_empty() -> bool:
    from app.model.hand import model as hand_model
    from app.sim import closing_compiled, contacts
    from app.sim.contacts_compiled import link_tables
    from app.sim.simulate import cached_kit

    return (
        cached_kit.cache_info().currsize == 0
        and link_tables.cache_info().currsize == 0
        and contacts._samples.cache_info().currsize == 0  # noqa: SLF001
        and not closing_compiled._CHAIN_CACHE  # noqa: SLF001
        and hand_model._visual_meshes.cache_info().currsize == 0  # noqa: SLF001
    )


def test_last_tab_closing_keeps_the_warm_engine() -> None:
    """What the server loads at start (``load_engine``: the objects' arrays, signed distances
    and piece spheres) is what the release keeps: the hands' caches go, and the arrays of an
    object outside the kept set."""
    from app.explorer.server import drop_simulation_caches
    from app.sim.resident import load_engine

    load_engine(["chips_can", "washer"])
    assert _warm_set_held("chips_can") and _warm_set_held("washer")
    assert not _hand_caches_empty()  # the warm-up simulation built one hand
    drop_simulation_caches(["chips_can"])
    assert _warm_set_held("chips_can")
    assert not _warm_set_held("washer")
    assert _hand_caches_empty()


def test_maps_are_drawn_on_one_thread() -> None:
    """Matplotlib caches fonts per thread (open files and FreeType faces): maps drawn from
    many threads (one per tab) draw on the one map thread, so the font cache does not grow."""
    import threading

    from matplotlib import font_manager

    from app.explorer.map_data import TOTAL, MapPoint
    from app.explorer.panel_map import render_base
    from app.quality.scores import DesignScore, ObjectScore

    score = DesignScore({"chips_can": ObjectScore(10, 5, 4)}, {"chips_can": "PP"})
    pts = [MapPoint(c, m, score, "store") for c, m in ((0.0, 45.0), (30.0, 60.0), (15.0, 90.0))]
    fonts = font_manager._get_font  # pyright: ignore[reportAttributeAccessIssue]  # noqa: SLF001
    render_base(pts, TOTAL)
    before = fonts.cache_info().currsize
    threads = [threading.Thread(target=lambda: render_base(pts, TOTAL)) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert fonts.cache_info().currsize == before


def test_icon_list_covers_the_explorer() -> None:
    """``server.ICONS`` (read once at start) lists every icon the explorer's panels use."""
    import re

    import viser

    from app.explorer.server import ICONS

    src = Path(__file__).resolve().parents[1] / "app" / "explorer"
    used = {m for p in src.glob("*.py") for m in re.findall(r"Icon\.([A-Z_0-9]+)", p.read_text())}
    assert {getattr(viser.Icon, n) for n in used} == set(ICONS)


def test_server_loads_the_engine_at_start(tmp_path: Path) -> None:
    """The server loads the warm engine in a thread once it listens, says so, and then holds
    the warm set and no hand: the level the last tab closing returns to."""
    from app.explorer.server import ExplorerServer

    lines: list[str] = []
    srv = ExplorerServer(
        "127.0.0.1", 0, tmp_path / "s.sqlite", objects=["chips_can"], workers=0,
        log=lines.append,
    )  # fmt: skip
    try:
        assert srv._preload is not None and srv._preload.name == "engine-preload"  # noqa: SLF001
        assert srv.engine_ready.wait(120)
        assert srv.engine_load_s is not None
        assert lines and lines[-1].startswith("engine ready in ")
        assert _warm_set_held("chips_can")
        assert _hand_caches_empty()
    finally:
        srv.stop()
