"""Force closure and the Ferrari–Canny ε of a grasp (METHOD §5, Q_C1 of §6).

Model: hard-finger contacts with Coulomb friction μ, each friction cone linearised by
``n_edges`` edges. Every edge ``f`` at a contact point ``p`` gives a primitive wrench

    w = [f, (p − c) × f / r]                                                  (6,)

with ``c`` the object's centroid and ``r`` its largest radius (mm; ``r`` makes the torque
rows commensurate with the force rows: it does not change force closure, it does change ε).

The grasp is force closure (FC) when the origin lies strictly inside the convex hull of the
primitive wrenches ``W`` (M, 6). That needs rank(W) = 6, checked first by SVD; the hull is
then computed by qhull (``scipy.spatial.ConvexHull`` with scipy's default options for 6-D
input: ``"Qx"`` exact pre-merges plus the always-on ``"Qt"`` triangulated output; no ``QJ``
joggle, so the input points are used exactly; never ``Qbb``/``QbB``, which rescale the input
array IN PLACE and report facets in the rescaled coordinates). Each facet ``k`` comes as
``a_k · x + b_k ≤ 0`` inside, ``|a_k| = 1``, so the signed distance from the origin to the
facet hyperplane is ``−b_k`` and

    ε = min_k (−b_k)                                                     (Ferrari–Canny)

in its L1 form: conv(W) holds the wrenches the contacts can apply with a total normal force
of 1 (the cone edges have unit normal component), and ε is the radius of the largest
origin-centred ball inside conv(W); ``ε > 0`` iff FC.
FC is decided as ``ε > FC_REL_TOL · max_i |W_i|`` (a relative tolerance, so the decision is
the same for any length unit).

Units: lengths mm; forces per unit normal force (dimensionless).

Speed (measured, ``benchmarks/bench_force_closure.py``): a 6-D hull of ~300 wrenches has
~30,000 facets and takes ~0.2 s, which would make one design (4,260 grasps) cost minutes.
So the benchmark DECIDES FC with ``positively_spans`` (below), which is the same predicate
— origin strictly inside conv(W) ⇔ W positively spans R^6 — by 7 non-negative least-squares
solves (~0.8 ms), and builds the qhull hull only where ε is wanted (Q_C1, ≤ 100 grasps per
object and design). ``tests/test_force_closure.py`` checks the two against each other and
against an LP on random and analytic contact sets. ``evaluate_fc`` decides with
``positively_spans_compiled``: the same tests in one numba call
(``force_closure_compiled``, ~0.1 ms per grasp), with this scipy path as its fallback where a
number lies too close to its threshold (``tests/test_force_closure_compiled.py``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import nnls
from scipy.spatial import ConvexHull, QhullError

from app.errors import SettingsError
from app.model.contact_set import ContactSet
from app.quality import force_closure_compiled as fcc

#: rank(W) = 6 needs σ_6 > RANK_REL_TOL · σ_1 (singular values of the (M, 6) wrench matrix).
RANK_REL_TOL = 1e-9
#: FC needs every facet hyperplane farther than FC_REL_TOL · max_i |W_i| from the origin.
FC_REL_TOL = 1e-9


def friction_cone_edges(n: np.ndarray, mu: float, n_edges: int) -> np.ndarray:
    """Edges of the linearised Coulomb cones at K contacts.

    ``e_kj = n_k + μ (cos θ_j t1_k + sin θ_j t2_k)``, ``θ_j = 2π j / n_edges``, where
    ``(t1_k, t2_k, n_k)`` is a right-handed orthonormal frame: ``t1 = a × n / |a × n|`` with
    ``a`` the coordinate axis least aligned with ``n``, ``t2 = n × t1``.

    Edges are NOT normalised: each has unit normal component (a unit normal force), and norm
    ``sqrt(1 + μ²)``; the polygon of edge tips is inscribed in the circle of radius μ.

    The cone's orientation about ``n`` (the choice of ``t1``) depends on the frame. It is
    equivariant (the edge set maps onto itself) under translations and under the 24 rotations
    that permute the coordinate axes, when ``n_edges`` is even; under other rotations the
    polygon turns about ``n``, which changes ε by at most the linearisation error.

    Args:
        n: (K, 3) unit contact normals (into the object).
        mu: friction coefficient, > 0.
        n_edges: edges per cone, ≥ 3.

    Returns:
        (K, n_edges, 3) edge directions.
    """
    n = np.asarray(n, dtype=float).reshape(-1, 3)
    axis = np.argmin(np.abs(n), axis=1)  # (K,)
    a = np.eye(3)[axis]  # (K, 3)
    t1 = np.cross(a, n)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    theta = 2.0 * np.pi * np.arange(n_edges) / n_edges  # (E,)
    c, s = np.cos(theta), np.sin(theta)
    return (
        n[:, None, :]
        + mu * c[None, :, None] * t1[:, None, :]
        + mu * s[None, :, None] * t2[:, None, :]
    )


def primitive_wrenches(
    p: np.ndarray,
    n: np.ndarray,
    centroid: np.ndarray,
    r: float,
    mu: float = 0.4,
    n_edges: int = 8,
) -> np.ndarray:
    """Primitive wrenches ``[f, (p − c) × f / r]`` of the linearised friction cones.

    Args:
        p: (K, 3) contact points, mm.
        n: (K, 3) unit normals pointing from the finger INTO the object: the finger pushes the
            object along +n.
        centroid: (3,) the object's centroid c, same frame, mm.
        r: the object's largest radius, mm (> 0); the torque scale.
        mu: friction coefficient.
        n_edges: edges per cone.

    Returns:
        (K * n_edges, 6) wrenches, contact-major (rows ``k * n_edges + j``).
    """
    p = np.asarray(p, dtype=float).reshape(-1, 3)
    f = friction_cone_edges(n, mu, n_edges)  # (K, E, 3)
    arm = (p - np.asarray(centroid, dtype=float).reshape(3))[:, None, :]  # (K, 1, 3)
    tau = np.cross(arm, f) / float(r)
    return np.concatenate([f, tau], axis=2).reshape(-1, 6)


def _has_full_rank(W: np.ndarray) -> bool:
    """rank(W) = 6 by SVD: σ_6 > RANK_REL_TOL · σ_1. W (M, 6)."""
    if W.ndim != 2 or W.shape[1] != 6 or W.shape[0] < 7 or not np.all(np.isfinite(W)):
        return False
    s = np.linalg.svd(W, compute_uv=False)
    return bool(s[0] > 0 and s[5] > RANK_REL_TOL * s[0])


def fc_and_epsilon(W: np.ndarray) -> tuple[bool, float]:
    """Force closure and ε of a wrench set in one hull computation.

    Args:
        W: (M, 6) primitive wrenches.

    Returns:
        (is_fc, ε): ε = min over hull facets of the signed distance from the origin to the
        facet hyperplane (> 0 inside; ≤ 0 when the origin is on or outside the hull), 0.0
        for degenerate input (fewer than 7 points, rank < 6, qhull failure).
        is_fc = ε > FC_REL_TOL · max_i |W_i|.
    """
    W = np.asarray(W, dtype=float)
    if not _has_full_rank(W):
        return False, 0.0
    try:
        hull = ConvexHull(W)
    except (QhullError, ValueError):
        return False, 0.0
    eps = float(np.min(-hull.equations[:, -1]))
    tol = FC_REL_TOL * float(np.max(np.linalg.norm(W, axis=1)))
    return eps > tol, eps


#: A positive basis of R^6: every vector is a non-negative combination of these seven.
_POSITIVE_BASIS = np.vstack([np.eye(6), -np.ones((1, 6))])
#: b lies in cone(W) when the NNLS residual is below this fraction of max_i |W_i|.
SPAN_REL_TOL = 1e-7


def positively_spans(W: np.ndarray) -> bool:
    """True iff the origin is strictly inside conv(W), decided without a hull.

    The origin is interior to conv(W) iff the cone of W is all of R^6 (a strictly positive
    combination of W is then zero), iff each vector of a positive basis (e_1..e_6 and
    -Σe_j) is a non-negative combination of the rows of W: seven NNLS problems
    ``min ||Wᵀλ - b||, λ ≥ 0`` with zero residual (relative ``SPAN_REL_TOL``). A quick
    rank test (SVD) and a half-space test on the forces reject most non-FC sets first.

    Args:
        W: (M, 6) primitive wrenches.
    """
    W = np.asarray(W, dtype=float)
    if not _has_full_rank(W):
        return False
    f = W[:, :3]
    mean = f.mean(axis=0)
    if np.linalg.norm(mean) > 0 and (f @ mean > 0).all():
        return False  # all forces in an open half-space: they cannot balance
    scale = float(np.max(np.linalg.norm(W, axis=1)))
    A = W.T
    for b in _POSITIVE_BASIS:
        _, residual = nnls(A, b * scale, maxiter=50 * A.shape[1])
        if residual > SPAN_REL_TOL * scale:
            return False
    return True


#: Calls of ``positively_spans_compiled`` in this process, and how many ran the scipy path
#: (in all and by the kernel's UNDECIDED code).
COMPILED_STATS: dict[str, int] = {"calls": 0, "fallbacks": 0}


def positively_spans_compiled(
    p: np.ndarray,
    n: np.ndarray,
    centroid: np.ndarray,
    r: float,
    mu: float = 0.4,
    n_edges: int = 8,
) -> bool:
    """``positively_spans(primitive_wrenches(p, n, centroid, r, mu, n_edges))``, the same
    verdict from one numba call (``force_closure_compiled.fc_kernel``, ~9× faster); that
    scipy path itself runs only where the kernel is too close to a threshold to be sure
    (counted in ``COMPILED_STATS``).

    Args:
        p: (K, 3) contact points, mm.
        n: (K, 3) unit normals into the object.
        centroid: (3,) the object's centroid, mm.
        r: the object's largest radius, mm.
        mu: friction coefficient.
        n_edges: edges per cone.
    """
    p = np.ascontiguousarray(p, dtype=np.float64).reshape(-1, 3)
    n = np.ascontiguousarray(n, dtype=np.float64).reshape(-1, 3)
    c = np.ascontiguousarray(centroid, dtype=np.float64).reshape(3)
    code = fcc.fc_kernel(p, n, c, float(r), float(mu), int(n_edges), RANK_REL_TOL, SPAN_REL_TOL)
    COMPILED_STATS["calls"] += 1
    if code >= 0:
        return code == fcc.FC
    COMPILED_STATS["fallbacks"] += 1
    key = f"fallback {fcc.UNDECIDED_NAMES[code]}"
    COMPILED_STATS[key] = COMPILED_STATS.get(key, 0) + 1
    return positively_spans(primitive_wrenches(p, n, c, r, mu, n_edges))


def is_force_closure(W: np.ndarray) -> bool:
    """True iff the origin is strictly inside conv(W) (qhull; see the module docstring).

    Args:
        W: (M, 6) primitive wrenches.
    """
    return fc_and_epsilon(W)[0]


def epsilon_quality(W: np.ndarray) -> float:
    """Ferrari–Canny ε = min_k (−b_k) over the hull facets ``a_k·x + b_k ≤ 0``, |a_k| = 1.

    The radius of the largest origin-centred ball in conv(W) when FC; ≤ 0 when not
    (0.0 for degenerate input). This is Q_C1.

    Args:
        W: (M, 6) primitive wrenches.
    """
    return fc_and_epsilon(W)[1]


@dataclass(frozen=True)
class FCSettings:
    """Contact model of the force-closure test."""

    mu: float = 0.4
    """Coulomb friction coefficient between the hand and the object (> 0)."""
    n_edges: int = 8
    """Edges of each linearised friction cone (integer ≥ 3)."""

    def __post_init__(self) -> None:
        if not (isinstance(self.mu, int | float) and math.isfinite(self.mu) and self.mu > 0):
            raise SettingsError(f"mu must be a finite number > 0, got {self.mu!r}")
        if (
            isinstance(self.n_edges, bool)
            or not isinstance(self.n_edges, int | np.integer)
            or self.n_edges < 3
        ):
            raise SettingsError(f"n_edges must be an integer >= 3, got {self.n_edges!r}")

    def as_dict(self) -> dict[str, object]:
        """Plain dict (for hashing and JSON)."""
        return asdict(self)


class FCResult(NamedTuple):
    """Force-closure verdict of one grasp."""

    is_fc: bool
    """Origin strictly inside the hull of the primitive wrenches."""
    epsilon: float
    """Ferrari–Canny ε (Q_C1); ≤ 0 when not FC; NaN when not computed."""
    n_points: int
    """Number of primitive wrenches (contact points × cone edges)."""


def evaluate_fc(
    contacts: ContactSet,
    centroid: np.ndarray,
    r: float,
    settings: FCSettings | None = None,
    with_epsilon: bool = False,
    compiled: bool = True,
) -> FCResult:
    """Force closure (positive span) and, when asked, ε by qhull (else NaN).

    Args:
        contacts: the grasp's contact points and normals (object frame, mm).
        centroid: (3,) the object's centroid, object frame, mm.
        r: the object's largest radius, mm.
        settings: contact model (default ``FCSettings()``).
        with_epsilon: decide FC and compute ε with the qhull hull.
        compiled: decide FC with ``positively_spans_compiled`` (the same verdict, faster);
            False: ``positively_spans`` on numpy's wrenches (the reference).
    """
    s = settings or FCSettings()
    if len(contacts) == 0:
        return FCResult(False, 0.0, 0)
    if with_epsilon or not compiled:
        W = primitive_wrenches(contacts.p_object, contacts.n_object, centroid, r, s.mu, s.n_edges)
        if with_epsilon:
            fc, eps = fc_and_epsilon(W)
            return FCResult(fc, eps, len(W))
        return FCResult(positively_spans(W), math.nan, len(W))
    fc = positively_spans_compiled(
        contacts.p_object, contacts.n_object, centroid, r, s.mu, s.n_edges
    )
    return FCResult(fc, math.nan, len(contacts) * int(s.n_edges))
