"""The design map: the 1° grid, spline interpolation (exact at the computed designs, smooth
between them), its fallbacks for partial sweeps, and the best computed design."""

from __future__ import annotations

import numpy as np
import pytest

from app.model.design import CMC_GRID_DEG, MCP_GRID_DEG
from app.reports.design_map import best_design, design_grid, interpolate_map
from tests.test_report import quadratic


def _grid_data() -> tuple[np.ndarray, np.ndarray]:
    C, M = np.meshgrid(CMC_GRID_DEG, MCP_GRID_DEG, indexing="ij")
    return C.ravel().astype(float), M.ravel().astype(float)


def test_design_grid_shape() -> None:
    cg, mg = design_grid(1.0)
    assert cg.shape == (46,) and mg.shape == (91,)
    assert cg[0] == 0 and cg[-1] == 45 and mg[-1] == 90
    c, m = _grid_data()
    cg, mg, Z = interpolate_map(c, m, quadratic(c, m))
    assert Z.shape == (91, 46) and cg.shape == (46,) and mg.shape == (91,)


def test_interpolate_grid_exact_and_smooth() -> None:
    c, m = _grid_data()
    cg, mg, Z = interpolate_map(c, m, quadratic(c, m))
    truth = quadratic(cg[None, :], mg[:, None])
    nodes = np.ix_(np.isin(mg, MCP_GRID_DEG), np.isin(cg, CMC_GRID_DEG))
    assert np.abs(Z[nodes] - truth[nodes]).max() < 1e-6
    assert np.abs(Z - truth).max() < 0.5  # a cubic spline reproduces a quadratic
    assert np.all(np.isfinite(Z)) and Z.min() >= 0 and Z.max() <= 100
    # a non-polynomial function: exact at nodes, close between them
    f = lambda c, m: 50 + 20 * np.sin(np.radians(2 * m)) * np.cos(np.radians(c))  # noqa: E731
    _, _, Z2 = interpolate_map(c, m, f(c, m))
    truth2 = f(cg[None, :], mg[:, None])
    assert np.abs(Z2[nodes] - truth2[nodes]).max() < 1e-6
    assert np.abs(Z2 - truth2).max() < 1.0
    # clipping and smoothing
    _, _, Z3 = interpolate_map(c, m, quadratic(c, m) + 40)
    assert Z3.max() == 100.0
    _, _, Zs = interpolate_map(c, m, quadratic(c, m), smoothing=5.0)
    assert np.abs(Zs - truth).max() < 5.0


def test_interpolate_fallbacks() -> None:
    rng = np.random.default_rng(3)
    # scattered designs: thin-plate spline, exact at the data, close inside their box
    cs = np.concatenate([[0, 45, 0, 45], rng.uniform(0, 45, 36)])
    ms = np.concatenate([[0, 0, 90, 90], rng.uniform(0, 90, 36)])
    cg, mg, Z = interpolate_map(cs, ms, quadratic(cs, ms))
    assert Z.shape == (91, 46) and np.all(np.isfinite(Z))
    assert np.abs(Z - quadratic(cg[None, :], mg[:, None])).max() < 3.0
    i, j = np.searchsorted(cg, 45.0), np.searchsorted(mg, 90.0)
    assert abs(Z[j, i] - quadratic(45, 90)) < 1e-6
    # a sub-range sweep: NaN outside the computed box, or only the box with extent="data"
    c, m = _grid_data()
    sub = c <= 15
    _, _, Zd = interpolate_map(c[sub], m[sub], quadratic(c[sub], m[sub]))
    assert np.all(np.isfinite(Zd[:, :16])) and np.all(np.isnan(Zd[:, 16:]))
    cg2, mg2, Z2 = interpolate_map(c[sub], m[sub], quadratic(c[sub], m[sub]), extent="data")
    assert cg2[-1] == 15 and Z2.shape == (91, 16) and np.all(np.isfinite(Z2))
    # two or three values on an axis: lower spline degree; one axis constant: 1-D spline
    sub3 = c <= 30
    _, _, Z3 = interpolate_map(c[sub3], m[sub3], quadratic(c[sub3], m[sub3]))
    assert np.abs(Z3[:, :31] - quadratic(cg[None, :31], mg[:, None])).max() < 1e-6
    one = c == 15
    _, _, Z1 = interpolate_map(c[one], m[one], quadratic(c[one], m[one]))
    assert np.isfinite(Z1).sum() == 91
    assert np.abs(Z1[:, 15] - quadratic(15.0, mg)).max() < 1e-6
    # a single design, duplicates averaged, NaN values ignored
    _, _, Zp = interpolate_map([15, 15, 30], [60, 60, 0], [40, 50, np.nan])
    assert np.nanmax(Zp) == 45 and np.isfinite(Zp).sum() == 1
    with pytest.raises(ValueError):
        interpolate_map([1.0], [2.0], [np.nan])


def test_best_design_is_the_highest_finite_value_first_on_ties() -> None:
    c, m = _grid_data()
    v = quadratic(c, m)
    bc, bm, bv = best_design(c, m, v)
    i = int(np.argmax(v))
    assert (bc, bm, bv) == (c[i], m[i], v[i])
    # NaN is skipped, ties go to the first in input order
    assert best_design([0, 15, 30], [0, 0, 0], [np.nan, 5.0, 5.0]) == (15.0, 0.0, 5.0)
    with pytest.raises(ValueError, match="finite"):
        best_design([0], [0], [np.nan])


def test_map_maximum_near_a_known_optimum() -> None:
    """A peak placed between the grid designs is found by the 1° map within a grid step."""
    c, m = _grid_data()
    peak = lambda c, m: 60 - 0.03 * (c - 22.0) ** 2 - 0.01 * (m - 52.0) ** 2  # noqa: E731
    cg, mg, Z = interpolate_map(c, m, peak(c, m))
    j, i = np.unravel_index(int(np.nanargmax(Z)), Z.shape)
    assert abs(cg[i] - 22.0) <= 2.0 and abs(mg[j] - 52.0) <= 3.0
