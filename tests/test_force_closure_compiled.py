"""The compiled force-closure decision (app.quality.force_closure_compiled) gives scipy's
verdict: its wrenches are numpy's, its NNLS residuals are scipy's, and its FC verdict equals
``positively_spans`` on random, boundary-bisected and simulated contact sets."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from scipy.optimize import nnls

from app.model.contact_set import ContactSet
from app.model.objects import load_object
from app.quality import force_closure as fcm
from app.quality import force_closure_compiled as fcc
from app.quality.force_closure import (
    RANK_REL_TOL,
    SPAN_REL_TOL,
    evaluate_fc,
    positively_spans,
    positively_spans_compiled,
    primitive_wrenches,
)
from app.quality.judge import judge
from app.quality.settings import SimSettings
from app.sim.hypothesis_sets import cached_hypotheses
from app.sim.simulate import cached_kit, simulate_base, simulate_thumb

Contacts = tuple[np.ndarray, np.ndarray, np.ndarray, float]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frame(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.eye(3)[np.argmin(np.abs(d))]
    t1 = _unit(np.cross(a, d))
    return t1, np.cross(d, t1)


def _kernel(p: np.ndarray, n: np.ndarray, c: np.ndarray, r: float, mu: float = 0.4) -> int:
    p, n = np.ascontiguousarray(p, float), np.ascontiguousarray(n, float)
    c = np.ascontiguousarray(c, float)
    return fcc.fc_kernel(p, n, c, float(r), mu, 8, RANK_REL_TOL, SPAN_REL_TOL)


def _reference(p: np.ndarray, n: np.ndarray, c: np.ndarray, r: float, mu: float = 0.4) -> bool:
    return positively_spans(primitive_wrenches(p, n, c, r, mu, 8))


# ---------------------------------------------------------------- wrenches


def test_wrenches_equal_numpy() -> None:
    rng = np.random.default_rng(0)
    # normals with ties in |n| (the argmin picks the first), axis-aligned, and random
    special = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0], [0.6, 0.8, 0], [0, 0.6, -0.8]])
    special = np.vstack([special, _unit(np.array([[1.0, 1, 1], [-1.0, 1, 0], [1.0, -1, -1]]))])
    worst = 0.0
    for i in range(300):
        k = int(rng.integers(1, 30))
        n = _unit(rng.normal(size=(k, 3)))
        if i % 3 == 0:
            n[: min(k, len(special))] = special[: min(k, len(special))]
        p = rng.uniform(-80, 80, (k, 3))
        c, r = rng.uniform(-20, 20, 3), float(rng.uniform(5, 100))
        mu, n_edges = float(rng.uniform(0.05, 1.2)), int(rng.integers(3, 17))
        W = primitive_wrenches(p, n, c, r, mu, n_edges)
        Wc = fcc.primitive_wrenches_nb(p, n, c, r, mu, n_edges)
        assert Wc.shape == W.shape
        worst = max(worst, float(np.max(np.abs(W - Wc))))
    assert worst <= 1e-12, worst


# ---------------------------------------------------------------- NNLS against scipy


def _nnls_problem(rng: np.random.Generator, i: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """(W (M, 6), b, well_conditioned): M from 7 to 300; kinds 1, 3, 5 are degenerate."""
    M = int(rng.integers(7, 301))
    kind = i % 6
    if kind == 0:  # generic: b mostly in the cone
        W = rng.normal(size=(M, 6))
    elif kind == 1:  # rank deficient (rank 1..5)
        rk = int(rng.integers(1, 6))
        W = rng.normal(size=(M, rk)) @ rng.normal(size=(rk, 6))
    elif kind == 2:  # pointed cone (x_0 > 0): b often outside
        W = rng.normal(size=(M, 6))
        W[:, 0] = np.abs(W[:, 0]) + 0.1
    elif kind == 3:  # repeated rows, some perturbed by 1e-9
        W0 = rng.normal(size=(max(3, M // 10), 6))
        W = W0[rng.integers(0, len(W0), M)]
        W = W + rng.normal(0, 1e-9, (M, 6)) * rng.integers(0, 2, (M, 1))
    elif kind == 4:  # row norms spread over six decades
        W = rng.normal(size=(M, 6)) * 10.0 ** rng.uniform(-3, 3, (M, 1))
    else:  # nearly pointed: x_0 ≥ about −1e-7, some rows with x_0 ~ 1e-6
        W = rng.normal(size=(M, 6))
        W[:, 0] = np.abs(W[:, 0]) * rng.choice([1.0, 1e-6], M) - 1e-7 * rng.random(M)
    b = rng.normal(size=6) * 10.0 ** rng.uniform(-2, 2)
    return np.ascontiguousarray(W), b, kind in (0, 2, 4)


def test_nnls_residual_equals_scipy() -> None:
    rng = np.random.default_rng(1)
    n_ok = n_zero = n_pos = 0
    worst = 0.0
    for i in range(1800):
        W, b, well = _nnls_problem(rng, i)
        bn = float(np.linalg.norm(b))
        xs, rs = nnls(W.T, b, maxiter=50 * len(W))
        x, rc, status = fcc.nnls_nb(W, b, 3 * len(W) + 60, 0.0)
        # a feasible λ, and the residual is its residual
        assert np.all(x >= 0)
        assert rc == pytest.approx(float(np.linalg.norm(W.T @ x - b)), abs=1e-12 * bn)
        # never below the optimum (which scipy's λ bounds from above)
        assert rc >= rs - 1e-9 * bn
        if well:
            assert status == fcc.NNLS_OK, (i, status)
        if status == fcc.NNLS_OK:
            n_ok += 1
            # converged: scipy's residual, and no worse than scipy's own λ
            worst = max(worst, abs(rc - rs) / bn)
            assert rc <= float(np.linalg.norm(W.T @ xs - b)) + 1e-9 * bn
            n_zero += rs < 1e-9 * bn
            n_pos += rs > 1e-3 * bn
    assert worst < 1e-10, worst
    assert n_ok >= 1500 and n_zero >= 300 and n_pos >= 300, (n_ok, n_zero, n_pos)


# ---------------------------------------------------------------- crafted thresholds


def test_rank_band_defers_to_scipy() -> None:
    """σ_6 / σ_1 near RANK_REL_TOL: decided outside [tol / 2, 2 tol], undecided inside."""

    def squashed(s: float) -> np.ndarray:
        W = np.vstack([np.eye(6), -np.eye(6)])
        W[:, 5] *= s
        return W

    assert fcc.fc_kernel_w(squashed(4e-10), RANK_REL_TOL, SPAN_REL_TOL) == fcc.NOT_FC
    assert fcc.fc_kernel_w(squashed(3e-9), RANK_REL_TOL, SPAN_REL_TOL) == fcc.FC
    for s in (6e-10, 1.5e-9):
        assert fcc.fc_kernel_w(squashed(s), RANK_REL_TOL, SPAN_REL_TOL) == fcc.UNDECIDED_RANK
    assert not positively_spans(squashed(4e-10)) and positively_spans(squashed(3e-9))


def test_ill_conditioned_cone_defers_to_scipy() -> None:
    """e_1..e_6 and (−1, …, −1, −η): FC, but −Σe_j needs λ = 1/η. Decided while the
    residual's rounding bound is far below the threshold, undecided when it is not."""

    def cone(eta: float) -> np.ndarray:
        return np.vstack([np.eye(6), np.r_[-np.ones(5), -eta]])

    assert positively_spans(cone(1e-3)) and positively_spans(cone(1e-6))
    assert fcc.fc_kernel_w(cone(1e-3), RANK_REL_TOL, SPAN_REL_TOL) == fcc.FC
    assert fcc.fc_kernel_w(cone(1e-5), RANK_REL_TOL, SPAN_REL_TOL) == fcc.UNDECIDED_NNLS_BAND
    assert fcc.fc_kernel_w(cone(1e-6), RANK_REL_TOL, SPAN_REL_TOL) < 0


def test_face_with_columns_off_its_span_defers_to_scipy() -> None:
    """e_1..e_6 and (−1, …, −1, 0): the cone is the half-space x_6 ≥ 0; −Σe_j's face holds
    e_1..e_5 outside the span of its passive column: a solver that adds them (scipy adds
    nearly dependent columns) decides by rounding, so the kernel leaves it to scipy; tilted
    clearly behind the face, it decides."""
    W = np.vstack([np.eye(6), np.r_[-np.ones(5), 0.0]])
    assert fcc.fc_kernel_w(W, RANK_REL_TOL, SPAN_REL_TOL) == fcc.UNDECIDED_NEAR_FACE
    assert not positively_spans(W)
    W[-1, 5] = 0.5
    assert fcc.fc_kernel_w(W, RANK_REL_TOL, SPAN_REL_TOL) == fcc.NOT_FC
    assert not positively_spans(W)


def test_fallback_runs_the_scipy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """An undecided kernel call returns scipy's verdict and is counted."""
    p = 20.0 * _unit(np.array([[1.0, 0, 0], [-1, 0.1, 0], [0, 1, 0.2], [0, -1, 0]]))
    n = -p / 20.0
    truth = _reference(p, n, np.zeros(3), 20.0)
    seen: list[bool] = []

    def spy(W: np.ndarray) -> bool:
        seen.append(True)
        return positively_spans(W)

    monkeypatch.setattr(fcm, "positively_spans", spy)
    before = dict(fcm.COMPILED_STATS)
    assert positively_spans_compiled(p, n, np.zeros(3), 20.0) == truth
    assert seen == []  # decided by the kernel
    monkeypatch.setattr(fcc, "fc_kernel", lambda *a: fcc.UNDECIDED_NNLS_BAND)
    assert positively_spans_compiled(p, n, np.zeros(3), 20.0) == truth
    assert seen == [True]
    assert fcm.COMPILED_STATS["calls"] == before["calls"] + 2
    assert fcm.COMPILED_STATS["fallbacks"] == before["fallbacks"] + 1


# ---------------------------------------------------------------- verdicts near the boundary


def _near_boundary(rng: np.random.Generator, i: int, mu: float) -> Contacts:
    """2-4 contacts (some as small patches) on a sphere or a cylinder, placed near the FC
    boundary of their family, with perturbed normals."""
    R = 20.0
    kind = i % 4
    if kind == 0:  # two small patches, the axis tilted by about the friction angle
        tilt = np.arctan(mu) * (1 + rng.normal(0, 0.02))
        d = _unit(rng.normal(size=3))
        t1, _ = _frame(d)
        e = np.cos(tilt) * d + np.sin(tilt) * t1
        pts = []
        for dd in (d, -e):
            k = int(rng.integers(1, 4))
            u1, u2 = _frame(dd)
            rad = 10 ** rng.uniform(-3, 0.5)
            ang = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(k) / k
            pts.append(R * _unit(R * dd + rad * (np.cos(ang)[:, None] * u1
                                                 + np.sin(ang)[:, None] * u2)))  # fmt: skip
        p = np.vstack(pts)
        n = _unit(-p / R + rng.normal(0, 0.02, p.shape))
        return p, n, np.zeros(3), R
    if kind == 1:  # 3-4 contacts about an equator, the largest gap near 180° + 2 atan μ
        k = int(rng.integers(3, 5))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))
        gap = np.max(np.diff(np.r_[ang, ang[0] + 2 * np.pi]))
        target = np.pi + 2 * np.arctan(mu) * (1 + rng.normal(0, 0.03))
        ang = ang * (2 * np.pi - target) / (2 * np.pi - gap)
        p = R * _unit(np.c_[R * np.cos(ang), R * np.sin(ang), rng.normal(0, 0.5, k)])
        return p, -p / R, np.zeros(3), R
    if kind == 2:  # cylinder side, 2-4 contacts, short patches along the axis
        Rc, H = 25.0, 100.0
        k = int(rng.integers(2, 5))
        th, z = rng.uniform(0, 2 * np.pi, k), rng.uniform(0, H, k)
        n = _unit(-np.c_[np.cos(th), np.sin(th), np.zeros(k)] + rng.normal(0, 0.3, (k, 3)))
        reps = rng.integers(1, 4, k)
        p = np.repeat(np.c_[Rc * np.cos(th), Rc * np.sin(th), z], reps, axis=0)
        p[:, 2] += rng.normal(0, 1.0, len(p))
        return p, np.repeat(n, reps, axis=0), np.array([0, 0, H / 2]), float(np.hypot(Rc, H / 2))
    # 3-4 contacts on a sphere near the polar angle atan(1/μ) (a cap's FC limit)
    k = int(rng.integers(3, 5))
    th, ph = np.arctan(1 / mu) + rng.normal(0, 0.02, k), rng.uniform(0, 2 * np.pi, k)
    d = np.c_[np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)]
    return R * d, -d, np.zeros(3), R


def test_verdict_equals_scipy_near_the_boundary() -> None:
    rng = np.random.default_rng(2)
    n_fc = n_not = n_undecided = 0
    for i in range(2000):
        p, n, c, r = _near_boundary(rng, i, 0.4)
        truth = _reference(p, n, c, r)
        code = _kernel(p, n, c, r)
        if code >= 0:
            assert (code == fcc.FC) == truth, i
        else:
            n_undecided += 1
        assert positively_spans_compiled(p, n, c, r) == truth, i
        n_fc += truth
        n_not += not truth
    assert n_fc >= 400 and n_not >= 400, (n_fc, n_not)
    assert n_undecided <= 20, n_undecided


def _family(rng: np.random.Generator, i: int) -> tuple[Callable[[float], Contacts], float, float]:
    """A one-parameter family of contact sets whose verdict flips between t = lo and hi."""
    R = 20.0
    kind = i % 3
    if kind == 0:  # 3-4 contacts on a cap, lowered toward the equator by t
        k = int(rng.integers(3, 5))
        th0, ph = rng.uniform(0.6, 1.0, k), rng.uniform(0, 2 * np.pi, k)

        def cap(t: float) -> Contacts:
            th = th0 + t
            d = np.c_[np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)]
            return R * d, -d, np.zeros(3), R

        return cap, 0.0, 1.5
    if kind == 1:  # 3-4 contacts about an equator, spread by t
        k = int(rng.integers(3, 5))
        ang, z = np.sort(rng.uniform(0, 1.5 * np.pi, k)), rng.normal(0, 2.0, k)
        ang -= ang[0]

        def ring(t: float) -> Contacts:
            a = ang * (1 + t)
            p = R * _unit(np.c_[np.cos(a), np.sin(a), z / R])
            return p, -p / R, np.zeros(3), R

        return ring, 0.0, 0.99 * (2 * np.pi / ang[-1] - 1)
    # two small patches, the second tilted away from antipodal by t
    d = _unit(rng.normal(size=3))
    t1, _ = _frame(d)
    rad = 10 ** rng.uniform(-1, 0.5)
    k1, k2 = int(rng.integers(1, 4)), int(rng.integers(2, 4))
    a0 = rng.uniform(0, 2 * np.pi, 2)

    def patch(dd: np.ndarray, k: int, start: float) -> np.ndarray:
        u1, u2 = _frame(dd)
        a = start + 2 * np.pi * np.arange(k) / k
        return R * _unit(R * dd + rad * (np.cos(a)[:, None] * u1 + np.sin(a)[:, None] * u2))

    def pinch(t: float) -> Contacts:
        q = np.vstack([patch(d, k1, a0[0]), patch(-(np.cos(t) * d + np.sin(t) * t1), k2, a0[1])])
        return q, -q / R, np.zeros(3), R

    return pinch, 0.0, 1.2


def test_verdict_equals_scipy_at_scipys_own_flip() -> None:
    """Families bisected (on ``positively_spans`` itself) to where scipy's verdict flips,
    then sampled at 1e-15 … 1e-1 from it: every verdict is scipy's; the kernel defers the
    ill-conditioned ones and decides the rest."""
    rng = np.random.default_rng(3)
    codes: dict[int, int] = {}
    decided_far = far = 0
    for i in range(45):
        f, lo, hi = _family(rng, i)
        v_lo = _reference(*f(lo))
        if v_lo == _reference(*f(hi)):
            continue
        for _ in range(52):
            mid = 0.5 * (lo + hi)
            if _reference(*f(mid)) == v_lo:
                lo = mid
            else:
                hi = mid
        for e in range(-15, 0):
            for t in (lo - 10.0**e, hi + 10.0**e):
                p, n, c, r = f(t)
                truth = _reference(p, n, c, r)
                code = _kernel(p, n, c, r)
                codes[code] = codes.get(code, 0) + 1
                if code >= 0:
                    assert (code == fcc.FC) == truth, (i, e, code)
                assert positively_spans_compiled(p, n, c, r) == truth, (i, e)
                if e >= -2:
                    far += 1
                    decided_far += code >= 0
    assert codes.get(fcc.FC, 0) >= 20 and codes.get(fcc.NOT_FC, 0) >= 20, codes
    assert sum(v for k, v in codes.items() if k < 0) >= 200, codes  # the fallback is exercised
    assert far >= 60 and decided_far == far, (decided_far, far)


# ---------------------------------------------------------------- simulated grasps


@pytest.fixture(scope="module")
def simulated() -> list[tuple[str, ContactSet, bool]]:
    """Every 20th hypothesis of four objects at design 0/45 (thumb and base contacts), with
    the compiled judge's FC verdict for the thumb grasp."""
    s = SimSettings()
    kit = cached_kit(0.0, 45.0, "ulnar")
    out = []
    for key in ("washer", "small_marker", "chips_can", "power_drill"):
        obj, hy = load_object(key), cached_hypotheses(key)
        for i in range(0, len(hy), 20):
            base = simulate_base(kit, obj, hy, i, s)
            g = simulate_thumb(kit, obj, base, s)
            if not g.approached:
                continue
            out.append((key, g.contacts, judge(g, obj, s, 0).is_fc))
            out.append((key, base.contacts, evaluate_fc(base.contacts, obj.centroid_object,
                                                        obj.max_radius, s.fc).is_fc))  # fmt: skip
    return out


def test_verdict_equals_scipy_on_simulated_grasps(simulated) -> None:
    s = SimSettings()
    n_fc = n_decided = 0
    for key, cs, is_fc in simulated:
        obj = load_object(key)
        c, r = obj.centroid_object, obj.max_radius
        ref = evaluate_fc(cs, c, r, s.fc, compiled=False)
        assert is_fc == ref.is_fc, key
        got = evaluate_fc(cs, c, r, s.fc)
        assert got.is_fc == ref.is_fc and got.n_points == ref.n_points
        n_fc += ref.is_fc
        if len(cs):
            n_decided += _kernel(cs.p_object, cs.n_object, c, r, s.fc.mu) >= 0
    assert len(simulated) >= 150
    assert 30 <= n_fc <= len(simulated) - 30, n_fc
    # the scipy fallback is rare on real grasps
    assert n_decided >= 0.98 * sum(len(cs) > 0 for _, cs, _ in simulated)


def test_evaluate_fc_uses_the_compiled_path_by_default() -> None:
    p = 20.0 * _unit(np.array([[1.0, 0, 0], [-1, 0.1, 0], [0, 1, 0.2], [0, -1, 0]]))
    cs = ContactSet(p, -p / 20.0, np.array(["index_distal"] * 4, dtype=object), np.ones(4, bool))
    before = fcm.COMPILED_STATS["calls"]
    res = evaluate_fc(cs, np.zeros(3), 20.0)
    assert fcm.COMPILED_STATS["calls"] == before + 1
    ref = evaluate_fc(cs, np.zeros(3), 20.0, compiled=False)
    assert (res.is_fc, res.n_points) == (ref.is_fc, ref.n_points) and np.isnan(res.epsilon)
    assert evaluate_fc(cs, np.zeros(3), 20.0, with_epsilon=True).is_fc == res.is_fc
    assert fcm.COMPILED_STATS["calls"] == before + 1


def test_warm_leaves_nothing_to_compile_at_run_time() -> None:
    """After ``python -m app.quality.warm`` (``make setup``), the judge's calls, whatever
    the input arrays' dtype or layout, use the warmed signature: no compile at run time."""
    from app.quality.warm import warm_force_closure

    assert warm_force_closure() >= 0
    sigs = list(fcc.fc_kernel.signatures)
    assert len(sigs) >= 1
    rng = np.random.default_rng(4)
    p = rng.normal(size=(5, 6))[:, ::2] * 20  # a strided view
    n = _unit(-p).astype(np.float32)
    positively_spans_compiled(p, n, [0, 0, 0], 20, np.float64(0.4), np.int64(8))  # type: ignore[arg-type]
    positively_spans_compiled(p.tolist(), n, np.zeros(3, np.float32), 20.0, 0.4, 8)
    assert list(fcc.fc_kernel.signatures) == sigs
