"""The cached distance field of imported meshes against trimesh's exact (slow) signed distance."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from app.model.objects.distance_field import EXACT_WITHIN_MM, build_field, cached_field
from app.model.objects.shapes import MeshSdf, mesh_sdf


def _meshes() -> dict[str, trimesh.Trimesh]:
    return {
        "sphere": trimesh.creation.icosphere(3, radius=25.0),
        "box": trimesh.creation.box((50.0, 40.0, 30.0)),
        # thin (3 mm) with a hole: an inside medial surface and sharp rims
        "annulus": trimesh.creation.annulus(5.0, 20.0, 3.0, sections=48),
    }


@pytest.fixture(scope="module", params=list(_meshes()))
def case(request: pytest.FixtureRequest) -> tuple[str, trimesh.Trimesh, object]:
    m = _meshes()[request.param]
    return request.param, m, build_field(m)


def _near_points(m: trimesh.Trimesh, n: int, sigma: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    s = np.asarray(trimesh.sample.sample_surface(m, n, seed=seed)[0])
    return s + rng.normal(size=s.shape) * sigma


def test_exact_near_the_surface(case: tuple[str, trimesh.Trimesh, object]) -> None:
    """Within the band the field answers with the exact distance of the nearest triangle
    (trimesh's closest point), sign included; the plain interpolation would not be exact."""
    name, m, f = case
    p = _near_points(m, 1500, 1.5, 1)
    exact = mesh_sdf(m)(p)
    got = f(p)  # type: ignore[operator]
    band = f.band_mm - f.spacing_mm * math.sqrt(3)  # type: ignore[attr-defined]
    near = np.abs(exact) < band
    assert near.sum() > 1000
    np.testing.assert_allclose(got[near], exact[near], atol=1e-9)
    if name != "box":  # the box's flat faces interpolate exactly; the curved/thin ones do not
        assert np.abs(f.interpolated(p)[near] - exact[near]).max() > 1e-3  # type: ignore[attr-defined]


def test_sign_everywhere_and_far_values_close(case: tuple[str, trimesh.Trimesh, object]) -> None:
    """Anywhere in and around the grid: the sign is trimesh's inside test; within 8 mm of
    the surface the value is exact, farther within about h of the true distance."""
    _, m, f = case
    rng = np.random.default_rng(2)
    q = rng.uniform(m.bounds[0] - 35.0, m.bounds[1] + 35.0, size=(2500, 3))
    exact = mesh_sdf(m)(q)
    got = f(q)  # type: ignore[operator]
    clear = np.abs(exact) > 1e-6
    assert np.all(np.sign(got[clear]) == np.sign(exact[clear]))
    h = f.spacing_mm  # type: ignore[attr-defined]
    lo = f.origin_mm  # type: ignore[attr-defined]
    hi = lo + h * (np.array(f.values_mm.shape) - 1)  # type: ignore[attr-defined]
    in_grid = np.all((q >= lo) & (q <= hi), axis=1)
    assert 0 < in_grid.sum() < len(q)
    assert np.abs(got - exact)[in_grid].max() <= 1.25 * h  # h·√3/2 plus interpolation
    # within EXACT_WITHIN_MM of the surface (less the bound's slack) the answer is exact
    close = in_grid & (np.abs(exact) < EXACT_WITHIN_MM - 2 * h)
    assert close.sum() > 50
    np.testing.assert_allclose(got[close], exact[close], atol=1e-9)
    # outside the grid: the distance to the mesh's box, a lower bound beyond the band
    out = ~in_grid
    assert np.all(got[out] <= exact[out] + 1e-9)
    assert np.all(got[out] >= f.band_mm)  # type: ignore[attr-defined]


def test_rigid_motion_moves_the_field_with_the_mesh() -> None:
    """The field of a moved mesh, queried at moved points, gives the same distances."""
    m = trimesh.creation.capsule(height=30.0, radius=10.0, count=[24, 24])
    T = trimesh.transformations.rotation_matrix(0.7, [1.0, 2.0, 0.5])
    T[:3, 3] = [13.0, -7.0, 40.0]
    m2 = m.copy()
    m2.apply_transform(T)
    p = _near_points(m, 800, 1.0, 3)
    p2 = p @ T[:3, :3].T + T[:3, 3]
    np.testing.assert_allclose(build_field(m)(p), build_field(m2)(p2), atol=1e-9)


def test_cached_on_disk(tmp_path: object, monkeypatch: pytest.MonkeyPatch) -> None:
    """The first call builds and saves, the second loads identical values; an unwritable
    cache folder only costs the rebuild."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    m = trimesh.creation.box((20.0, 30.0, 10.0))
    f1, built1 = cached_field(m)
    f2, built2 = cached_field(m)
    assert built1 and not built2
    np.testing.assert_array_equal(f1.values_mm, f2.values_mm)
    p = _near_points(m, 200, 2.0, 4)
    np.testing.assert_array_equal(f1(p), f2(p))
    monkeypatch.setenv("XDG_CACHE_HOME", "/proc/no-such-cache")
    f3, built3 = cached_field(m)
    assert built3
    np.testing.assert_array_equal(f3(p), f1(p))


def test_mesh_objects_use_the_field(tmp_path: object, monkeypatch: pytest.MonkeyPatch) -> None:
    """An imported-mesh geometry's SDF is the field (exact near the surface)."""
    from app.model.objects.shapes import from_mesh

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    m = trimesh.creation.cylinder(radius=20.0, height=60.0, sections=64)
    g = from_mesh(m)
    assert isinstance(g.sdf, MeshSdf)
    p = _near_points(m, 300, 1.0, 5)
    np.testing.assert_allclose(g.sdf(p), mesh_sdf(m)(p), atol=1e-9)
    assert g.sdf.built_s is not None


def test_signed_bounds_bracket_the_exact_distance(
    case: tuple[str, trimesh.Trimesh, object],
) -> None:
    """The node bounds the compiled contact screening reads (``signed_bounds``) hold the exact
    signed distance (trimesh's) near the surface, deep inside and far away, and they are
    tight: a couple of spacings wide, and signed wherever the point is over 2 h deep or
    away."""
    from app.model.objects.distance_field import signed_bounds

    name, m, f = case
    pk = f.pack()  # type: ignore[attr-defined]
    h = f.spacing_mm  # type: ignore[attr-defined]
    p = np.vstack([_near_points(m, 400, s, 3) for s in (0.5, 2.0, 6.0, 20.0)])
    exact = mesh_sdf(m)(p)
    lo, hi = np.array([signed_bounds(pk, *x) for x in p]).T
    assert np.all(lo <= exact) and np.all(exact <= hi), name
    near = np.abs(exact) < f.band_mm  # type: ignore[attr-defined]
    assert (hi - lo)[near].max() <= 2 * h * math.sqrt(3) + 1e-3
    signed = np.abs(exact) > 2 * h
    assert np.all(np.sign(lo[signed]) == np.sign(hi[signed]))
