"""Off-screen pictures: size, content, design differences, contact legend, hand placement."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from app.model.contact_set import ContactSet
from app.model.hand.model import build_hand
from app.model.objects import load_object
from app.reports.pictures import (
    grid_pose,
    render_design_grid,
    render_hand,
    render_object,
    roll0_pose,
)
from app.reports.scene import CONTACT_RGB, render_scene

SIZE = (360, 280)


def _rgb(path: Path) -> np.ndarray:
    img = mpimg.imread(str(path))
    assert img.dtype == np.float32 and img.ndim == 3
    return np.asarray(img[..., :3], float)


def _has_colour(img: np.ndarray, hex_colour: str, tol: float = 0.06) -> bool:
    c = np.array([int(hex_colour[i : i + 2], 16) / 255 for i in (1, 3, 5)])
    return bool((np.abs(img - c).max(axis=-1) < tol).any())


def test_render_hand_writes_png_of_requested_size(tmp_path: Path) -> None:
    out = tmp_path / "hand.png"
    info = render_hand(out, 0, 45, size=SIZE)
    assert out.is_file() and info.path == out
    img = _rgb(out)
    assert img.shape[:2] == (SIZE[1], SIZE[0])
    assert img.std() > 0.05  # not a uniform picture
    # skin-toned pixels (the hand) and white background both present
    skin = (img[..., 0] > img[..., 2] + 0.15) & (img[..., 0] > 0.4)
    assert skin.mean() > 0.03
    assert (img.min(axis=-1) > 0.99).mean() > 0.2
    assert info.n_polygons > 1000
    assert info.seconds < 5


def test_different_designs_give_different_pictures(tmp_path: Path) -> None:
    hand = build_hand(0, 0)
    q = grid_pose(hand)  # the thumb partly closed: its path depends on the design
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    render_hand(a, 0, 0, q=q, size=SIZE, title="same title", show_axes=False)
    render_hand(b, 45, 90, q=q, size=SIZE, title="same title", show_axes=False)
    diff = np.abs(_rgb(a) - _rgb(b)).max(axis=-1)
    assert (diff > 0.1).mean() > 0.01
    # ...and the same design twice gives the same picture
    c = tmp_path / "c.png"
    render_hand(c, 0, 0, q=q, size=SIZE, title="same title", show_axes=False)
    assert np.abs(_rgb(a) - _rgb(c)).max() < 1e-6


def test_contacts_are_drawn_with_a_legend(tmp_path: Path) -> None:
    obj = load_object("coffee_can")
    hand = build_hand(0, 45)
    T = roll0_pose(hand, obj)
    p = np.array([[50.0, 0.0, 60.0], [50.0, 5.0, 70.0], [35.4, 35.4, 80.0], [0.0, 50.0, 60.0]])
    n = -p * np.array([1.0, 1.0, 0.0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    contacts = ContactSet(
        p_object=p,
        n_object=n,
        link=np.array(["palm", "palm", "index_distal", "thumb_distal"], dtype=object),
        palmar=np.array([True, True, True, False]),
    )
    out = tmp_path / "contacts.png"
    info = render_scene(
        out, hand=hand, T_object_palm=T, obj=obj, contacts=contacts, size=(500, 400)
    )
    assert len(info.legend_labels) == 3
    assert any("palm" in s for s in info.legend_labels)
    img = _rgb(out)
    for colour in CONTACT_RGB.values():
        assert _has_colour(img, colour), colour


def test_roll0_pose_puts_the_hand_at_first_contact() -> None:
    obj = load_object("chips_can")
    hand = build_hand(0, 45)
    T = roll0_pose(hand, obj, standoff_mm=0.0)
    # P lies on the axis ray through the target
    P = T[:3, :3] @ hand.approach_point_palm + T[:3, 3]
    v = P - obj.spec.target_object
    assert np.linalg.norm(np.cross(v, obj.spec.normal_object)) < 1e-6
    assert v @ obj.spec.normal_object > 0
    # the hand surface just touches the object
    poses = hand.link_poses(hand.q_open)
    pts = []
    for i, lk in enumerate(hand.links):
        p_link, _ = lk.shape.surface_points(1.5)
        pts.append(p_link @ poses[i, :3, :3].T + poses[i, :3, 3])
    p_obj = np.concatenate(pts) @ T[:3, :3].T + T[:3, 3]
    assert -1.5 < obj.sdf(p_obj).min() < 1.5
    # a standoff moves it back along the normal
    T2 = roll0_pose(hand, obj, standoff_mm=20.0)
    assert np.allclose(T2[:3, 3] - T[:3, 3], 20.0 * obj.spec.normal_object, atol=1e-6)


@pytest.mark.parametrize("key", ["washer"])
def test_render_object(tmp_path: Path, key: str) -> None:
    out = tmp_path / f"{key}.png"
    info = render_object(out, key, size=SIZE)
    img = _rgb(out)
    assert img.shape[:2] == (SIZE[1], SIZE[0])
    # the object's grey-blue and the hand's skin tone are both visible
    blue = (img[..., 2] > img[..., 0] + 0.08) & (img[..., 2] > 0.4)
    skin = (img[..., 0] > img[..., 2] + 0.15) & (img[..., 0] > 0.4)
    assert blue.mean() > 0.002 and skin.mean() > 0.02
    assert info.legend_labels == ()


def test_design_grid(tmp_path: Path) -> None:
    out = tmp_path / "grid.png"
    info = render_design_grid(out, designs=[(0, 0), (45, 90)], size=(600, 320))
    assert _rgb(out).shape[:2] == (320, 600)
    assert info.n_polygons > 2000
