"""The design map: a score known at computed designs, interpolated over (CMC, MCP).

Pure numpy/scipy (no matplotlib): the sweep's contour plot and the browser explorer both use
:func:`interpolate_map`.

Which interpolant (METHOD §7 asks for a smoothing/cubic spline on a 1° grid):

- **Full rectangular grid** (every combination of the distinct CMC values × the distinct MCP
  values computed once, e.g. the 28 published DAs): ``scipy.interpolate.RectBivariateSpline``
  of degree 3 along each axis with ≥ 4 values; an axis with 2 or 3 values gets degree 1 or 2
  (a cubic needs 4 points). ``smoothing = 0`` interpolates (passes through every computed
  value); ``smoothing > 0`` is FITPACK's ``s``: an upper bound on the sum of squared residuals
  at the computed designs, in (score unit)².
- **One axis constant** (a sweep of one CMC angle, or one MCP angle): a 1-D interpolating
  spline (``make_interp_spline``, degree ≤ 3) along the other axis.
- **Scattered designs** (anything else, ≥ 3 points not on one line):
  ``scipy.interpolate.RBFInterpolator`` with a thin-plate-spline kernel and a linear
  polynomial term; ``smoothing`` is its regularisation (0 interpolates). Collinear scattered
  designs use a linear RBF kernel with a constant term.

Repeated designs are averaged first. Values are clipped to [0, 100] (scores are %).
Grid points outside the bounding box of the computed designs are NaN: the map never invents
scores by extrapolation (with the 28 published DAs the box is the whole design range).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import RBFInterpolator, RectBivariateSpline, make_interp_spline

from app.model.design import CMC_RANGE_DEG, MCP_RANGE_DEG

_TOL_DEG = 1e-9


def design_grid(
    step_deg: float = 1.0,
    cmc_range: tuple[float, float] = CMC_RANGE_DEG,
    mcp_range: tuple[float, float] = MCP_RANGE_DEG,
) -> tuple[np.ndarray, np.ndarray]:
    """Regular grid axes ``(cmc_grid (A,), mcp_grid (B,))`` in degrees, ends included.

    The last value is the range end even when ``step_deg`` does not divide the range.
    """
    if not step_deg > 0:
        raise ValueError(f"step_deg must be > 0, got {step_deg}")

    def axis(lo: float, hi: float) -> np.ndarray:
        n = int(np.floor((hi - lo) / step_deg + 1e-9))
        a = lo + step_deg * np.arange(n + 1, dtype=float)
        if hi - a[-1] > 1e-9:
            a = np.append(a, hi)
        return a

    return axis(*cmc_range), axis(*mcp_range)


def _unique_mean(
    c: np.ndarray, m: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Average values of repeated (c, m) designs; returns (N',) arrays."""
    pts = np.stack([c, m], axis=1)
    uniq, inv = np.unique(np.round(pts, 9), axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    sums = np.zeros(len(uniq))
    np.add.at(sums, inv, v)
    counts = np.bincount(inv, minlength=len(uniq))
    return uniq[:, 0], uniq[:, 1], sums / counts


def _full_grid(
    c: np.ndarray, m: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(cu (P,), mu (Q,), V (P, Q))`` when the designs fill a rectangular grid, else None."""
    cu, mu = np.unique(c), np.unique(m)
    if len(cu) * len(mu) != len(v):
        return None
    V = np.full((len(cu), len(mu)), np.nan)
    V[np.searchsorted(cu, c), np.searchsorted(mu, m)] = v
    return (cu, mu, V) if not np.isnan(V).any() else None


def _collinear(pts: np.ndarray) -> bool:
    """(N, 2) points all on one line (or fewer than 3)."""
    if len(pts) < 3:
        return True
    d = pts - pts.mean(axis=0)
    s = np.linalg.svd(d, compute_uv=False)
    return bool(s[1] <= 1e-9 * max(s[0], 1.0))


def interpolate_map(
    cmc_deg: ArrayLike,
    mcp_deg: ArrayLike,
    values: ArrayLike,
    step_deg: float = 1.0,
    *,
    smoothing: float = 0.0,
    extent: Literal["design", "data"] = "design",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interpolate scores known at computed designs onto a regular (CMC, MCP) grid.

    Args:
        cmc_deg: (N,) CMC angle of each computed design, degrees.
        mcp_deg: (N,) MCP angle of each computed design, degrees.
        values: (N,) the score there (%, e.g. total S_GAS); NaN entries are ignored.
        step_deg: grid spacing, degrees.
        smoothing: 0 interpolates; > 0 smooths (see the module docstring per method).
        extent: "design" — the grid spans the whole design range (``app.model.design``);
            "data" — only the bounding box of the computed designs.

    Returns:
        ``(cmc_grid (A,), mcp_grid (B,), Z (B, A))``: ``Z[j, i]`` is the value at
        ``(cmc_grid[i], mcp_grid[j])``, clipped to [0, 100], NaN outside the bounding box of
        the computed designs. The full design range at 1° gives A = 46, B = 91.

    Raises:
        ValueError: shapes differ or no finite value is given.
    """
    c = np.asarray(cmc_deg, dtype=float).reshape(-1)
    m = np.asarray(mcp_deg, dtype=float).reshape(-1)
    v = np.asarray(values, dtype=float).reshape(-1)
    if not c.shape == m.shape == v.shape:
        raise ValueError(f"cmc_deg {c.shape}, mcp_deg {m.shape}, values {v.shape} differ")
    ok = np.isfinite(c) & np.isfinite(m) & np.isfinite(v)
    if not ok.any():
        raise ValueError("interpolate_map needs at least one design with a finite value")
    c, m, v = _unique_mean(c[ok], m[ok], v[ok])

    lo_c, hi_c, lo_m, hi_m = c.min(), c.max(), m.min(), m.max()
    if extent == "data":
        cg, mg = design_grid(step_deg, (lo_c, hi_c), (lo_m, hi_m))
    elif extent == "design":
        cg, mg = design_grid(step_deg)
    else:
        raise ValueError(f"extent must be 'design' or 'data', got {extent!r}")
    Z = np.full((len(mg), len(cg)), np.nan)
    ci = np.flatnonzero((cg >= lo_c - _TOL_DEG) & (cg <= hi_c + _TOL_DEG))
    mi = np.flatnonzero((mg >= lo_m - _TOL_DEG) & (mg <= hi_m + _TOL_DEG))
    if len(ci) == 0 or len(mi) == 0:  # the data fall between grid lines
        return cg, mg, Z
    cq, mq = np.clip(cg[ci], lo_c, hi_c), np.clip(mg[mi], lo_m, hi_m)

    cu, mu = np.unique(c), np.unique(m)
    if len(v) == 1:
        inner = np.full((len(mi), len(ci)), v[0])
    elif len(cu) == 1 or len(mu) == 1:
        # one axis constant: 1-D spline along the other
        along_c = len(mu) == 1
        x, q = (c, cq) if along_c else (m, mq)
        order = np.argsort(x)
        spl = make_interp_spline(x[order], v[order], k=min(3, len(x) - 1))
        line = spl(q)
        inner = np.broadcast_to(line[None, :] if along_c else line[:, None], (len(mi), len(ci)))
    elif (grid := _full_grid(c, m, v)) is not None:
        gc, gm, V = grid
        kx, ky = min(3, len(gc) - 1), min(3, len(gm) - 1)
        # scipy's stub types ``s`` as int; FITPACK takes any float >= 0
        spline = RectBivariateSpline(gc, gm, V, kx=kx, ky=ky, s=smoothing)  # pyright: ignore[reportArgumentType]
        inner = spline(cq, mq).T  # (len(cq), len(mq)) -> (B', A')
    else:
        pts = np.stack([c, m], axis=1)
        if _collinear(pts):
            rbf = RBFInterpolator(pts, v, kernel="linear", degree=0, smoothing=smoothing)
        else:
            rbf = RBFInterpolator(pts, v, kernel="thin_plate_spline", degree=1, smoothing=smoothing)
        Cq, Mq = np.meshgrid(cq, mq)  # (B', A')
        inner = rbf(np.stack([Cq.ravel(), Mq.ravel()], axis=1)).reshape(Cq.shape)
    Z[np.ix_(mi, ci)] = inner
    return cg, mg, np.clip(Z, 0.0, 100.0)


def best_design(
    cmc_deg: ArrayLike, mcp_deg: ArrayLike, values: ArrayLike
) -> tuple[float, float, float]:
    """``(cmc_deg, mcp_deg, value)`` of the computed design with the highest finite value.

    Ties go to the first in input order. Inputs are (N,) arrays.
    """
    v = np.asarray(values, dtype=float)
    if not np.isfinite(v).any():
        raise ValueError("no design has a finite value")
    i = int(np.nanargmax(np.where(np.isfinite(v), v, -np.inf)))
    return float(np.asarray(cmc_deg)[i]), float(np.asarray(mcp_deg)[i]), float(v[i])
