"""Simulate grasp hypotheses: the design-independent base stage, then the thumb stage.

Cost model (METHOD §3a; docs/cost-model.md): the approach stops at the first contact of
the open hand, thumb included, and the open thumb's shape depends on the CMC angle c only
(at q = 0 the MCP design angle m turns the thumb's capsules about their own axes). So the
approach, the back-off and the long fingers' closing (``simulate_base``) run once per
(hypothesis, c) and serve all MCP angles; the thumb closes last (``simulate_thumb``, per
design), against the object and, for self-collision, the palm and the long fingers in their
final posture.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Protocol

import fcl
import numpy as np

from app.model.contact_set import LONG_FINGERS, ContactSet
from app.model.design import ThumbDesign
from app.model.hand.chains import FingerChain, finger_chains
from app.model.hand.data import load_hand_dims
from app.model.hand.model import Hand
from app.model.target import GraspTarget
from app.sim.closing import (
    ClosingStats,
    Obstacles,
    StageEvent,
    approach,
    close_finger,
    fcl_transform,
)
from app.sim.closing_settings import ClosingSettings
from app.sim.contacts import ContactSettings, _reach, contacts_of_links, merge
from app.sim.hypotheses import Hypotheses

if TYPE_CHECKING:
    from app.sim.closing_compiled import ObstacleArrays


def _object_arrays(obj: GraspTarget, closing: ClosingSettings) -> ObstacleArrays | None:
    """The object's pieces as arrays when the compiled engine is asked for and can run."""
    if closing.engine != "compiled":
        return None
    from app.sim.closing_compiled import object_arrays

    return object_arrays(obj)


def _object_spheres(obj: GraspTarget) -> np.ndarray:
    """(P, 4) a bounding sphere (centre, radius; object frame) of each of the object's
    collision pieces, radius inf where there is none (an imported mesh): the closing stages'
    first lower bounds, so that far pieces are not queried. The same numbers on both engines
    (they come from the pieces' arrays), so the engines keep taking the same steps."""
    from app.sim.closing_compiled import object_arrays
    from app.sim.contacts_compiled import piece_spheres
    from app.sim.mesh_distance import MESH

    arr = object_arrays(obj)
    if arr is None:  # no array description: every piece is queried
        return np.full((len(list(obj.collision_objects())), 4), np.inf)
    out = piece_spheres(arr).copy()
    out[arr.typ == MESH, 3] = np.inf
    return out


class PalmarRule(Protocol):
    """The palmar-contact threshold (``GraspTypeSettings`` has it)."""

    @property
    def palmar_angle_deg(self) -> float:
        """A contact is palmar when angle(n_contact, the link's n_palmar) is below this (°)."""
        ...


class SimulationSettings(Protocol):
    """What simulating a grasp reads of the settings (``app.quality.settings.SimSettings``
    satisfies it; the sim layer does not import the quality layer)."""

    @property
    def closing(self) -> ClosingSettings:
        """Approach and closing (METHOD §4)."""
        ...

    @property
    def contact(self) -> ContactSettings:
        """Contact patches (METHOD §5)."""
        ...

    @property
    def grasp_type(self) -> PalmarRule:
        """The palmar classification of contacts."""
        ...


class HandKit:
    """A hand's chains and its private FCL bodies (one kit per worker thread/process)."""

    def __init__(self, hand: Hand) -> None:
        self.hand = hand
        self.chains: dict[str, FingerChain] = finger_chains(hand)
        self.names = [lk.name for lk in hand.links]
        self.shapes = [lk.shape for lk in hand.links]
        self.T_link_fcl = np.stack([s.T_link_fcl() for s in self.shapes])
        self.moving = [fcl.CollisionObject(s.fcl_geometry(), fcl.Transform()) for s in self.shapes]
        self.static = [fcl.CollisionObject(s.fcl_geometry(), fcl.Transform()) for s in self.shapes]
        self.q_open = hand.q_open
        self.reach = np.array([_reach(sh) for sh in self.shapes])
        T_open = hand.link_poses(self.q_open)
        #: (16, 4, 4) every open-hand link's FCL frame in the palm frame: the approach takes
        #: the thumbless links (``non_thumb``) and the thumb's (``thumb_links``) in turn
        self.T_palm_approach = T_open @ self.T_link_fcl
        self._approach_arrays: dict[tuple[int, ...], ObstacleArrays] = {}
        self._approach_poses: dict[tuple[int, ...], np.ndarray] = {}
        #: the links a thumb closes against (self-collision): palm and long fingers
        self.non_thumb = [j for j, n in enumerate(self.names) if not n.startswith("thumb")]
        #: the thumb's links
        self.thumb_links = [j for j, n in enumerate(self.names) if n.startswith("thumb")]
        self._thumb_templates: dict[int, tuple[ObstacleArrays, ObstacleArrays]] = {}

    def approach_arrays(self, idx: tuple[int, ...]) -> ObstacleArrays:
        """The open-hand links ``idx``' shapes as arrays (compiled engine; poses are per
        call)."""
        got = self._approach_arrays.get(idx)
        if got is None:
            from app.sim.closing_compiled import link_arrays

            shapes = [self.shapes[j] for j in idx]
            got = link_arrays(shapes, np.tile(np.eye(4), (len(shapes), 1, 1)))
            self._approach_arrays[idx] = got
        return got

    def approach_poses(self, idx: tuple[int, ...]) -> np.ndarray:
        """(len(idx), 4, 4) the open-hand links ``idx``' FCL frames in the palm frame."""
        got = self._approach_poses.get(idx)
        if got is None:
            got = np.ascontiguousarray(self.T_palm_approach[list(idx)])
            self._approach_poses[idx] = got
        return got

    def thumb_obstacle_arrays(self, obj_arr: ObstacleArrays, T_fcl: np.ndarray) -> ObstacleArrays:
        """The object's pieces followed by the non-thumb links posed at ``T_fcl`` (13, 4, 4)
        (their FCL frames): the layout is built once per object, only the poses are new."""
        hit = self._thumb_templates.get(id(obj_arr))
        if hit is None or hit[0] is not obj_arr:
            eye = np.tile(np.eye(4), (len(self.non_thumb), 1, 1))
            from app.sim.closing_compiled import link_arrays

            shapes = [self.shapes[j] for j in self.non_thumb]
            hit = (obj_arr, obj_arr.concat(link_arrays(shapes, eye)))
            if len(self._thumb_templates) >= 16:
                self._thumb_templates.clear()
            self._thumb_templates[id(obj_arr)] = hit
        tpl, n = hit[1], len(obj_arr)
        R, t = tpl.R.copy(), tpl.t.copy()
        R[n:] = T_fcl[:, :3, :3]
        t[n:] = T_fcl[:, :3, 3]
        return dataclasses.replace(tpl, R=R, t=t)

    def link_arrays(self, idx: list[int], T_links: np.ndarray) -> ObstacleArrays:
        """Links ``idx`` posed at ``T_links`` (16, 4, 4) as obstacle arrays (compiled engine)."""
        from app.sim.closing_compiled import link_arrays

        T = T_links[idx] @ self.T_link_fcl[idx]
        return link_arrays([self.shapes[j] for j in idx], T)

    def contacts(
        self, obj: GraspTarget, T_links: np.ndarray, idx: list[int], settings: SimulationSettings
    ) -> tuple[ContactSet, int]:
        """Contacts of links ``idx`` posed at ``T_links`` (16, 4, 4) in the object frame, and
        the distance queries spent (the compiled engine computes them in one compiled call,
        ``app.sim.contacts_compiled``, where the object allows)."""
        counter = [0]
        if settings.closing.engine == "compiled":
            from app.sim.contacts_compiled import contacts_compiled

            got = contacts_compiled(
                obj,
                [self.names[j] for j in idx],
                [self.shapes[j] for j in idx],
                T_links[idx],
                settings.contact,
                settings.grasp_type.palmar_angle_deg,
                counter,
            )
            if got is not None:
                return got, counter[0]
        link_distance = None
        if settings.closing.engine == "compiled":
            arrays = _object_arrays(obj, settings.closing)
            pack = arrays.mesh if arrays is not None else None
            if pack is not None:  # an imported mesh: its distance field, not FCL's BVH
                from app.sim.closing_compiled import link_mesh_distance

                tol = settings.contact.contact_tol_mm
                link_distance = lambda sh, T: link_mesh_distance(sh, T, pack, tol)  # noqa: E731
        cs = contacts_of_links(
            obj,
            [self.names[j] for j in idx],
            [self.shapes[j] for j in idx],
            [self.moving[j] for j in idx],
            T_links[idx],
            self.T_link_fcl[idx],
            settings.contact,
            settings.grasp_type.palmar_angle_deg,
            counter,
            link_distance,
        )
        return cs, counter[0]

    def bodies(self, finger: str) -> list[fcl.CollisionObject]:
        """The moving FCL bodies of a finger's three links."""
        return [self.moving[i] for i in self.chains[finger].link_indices]


@dataclass(frozen=True)
class BaseGrasp:
    """The design-independent part of one hypothesis' grasp."""

    approached: bool
    """False when the approach line never brought the hand into contact (the GH fails)."""
    T_object_palm: np.ndarray
    """(4, 4) hand placement after approach and back-off."""
    q: np.ndarray
    """(15,) joint angles with the long fingers final and the thumb open, rad."""
    contacts: ContactSet
    """Contacts of the palm and the long fingers."""
    queries: int
    """FCL distance queries spent."""
    thumb_obstacles: Obstacles | None = field(default=None, repr=False, compare=False)
    """What the thumb closes against on this base (compiled engine: arrays only, so any kit
    of the same hand may reuse them; None: built per thumb)."""
    thumb_first_stage: dict[str, tuple[np.ndarray, StageEvent]] = field(default_factory=dict)
    """Memo of the thumb's CMC stage (sequential mode): with MCP and IP open, the thumb's
    capsules lie on the metacarpal's line whatever the MCP design angle, so every design
    sharing this base (same CMC angle) closes CMC identically (docs/cost-model.md)."""


@dataclass(frozen=True)
class Grasp:
    """A hypothesis' final grasp at one thumb design."""

    T_object_palm: np.ndarray
    """(4, 4) hand placement, object frame."""
    q: np.ndarray
    """(15,) final joint angles, rad."""
    contacts: ContactSet
    """All contacts (palm, long fingers, thumb), object frame."""
    thumb_n_main_object: np.ndarray
    """(3,) the thumb distal phalanx long axis, object frame."""
    approached: bool
    """False when the approach failed (no contacts, not FC)."""
    queries: int
    """FCL distance queries of the thumb stage (the base stage counts its own)."""
    events: tuple[str, ...] = ()
    """Closing stage events of the thumb, for the explorer's replay and debugging."""


def closing_fingers(grasp_type: str) -> tuple[str, ...]:
    """Fingers that close: thumb + index for PP, all for CG (METHOD §3a)."""
    return ("thumb", "index") if grasp_type == "PP" else ("thumb",) + LONG_FINGERS


@dataclass(frozen=True)
class PalmGrasp:
    """The design-independent part of one hypothesis: the thumbless hand's approach, the
    back-off and the long fingers (docs/cost-model.md). Every design's base starts from it;
    only a thumb that touches first during the approach moves the placement."""

    start_mm: float
    """Ray parameter where the approach starts, mm."""
    s_mm: float
    """Ray parameter at the first contact of the palm and long fingers, mm; NaN when they
    pass the target without touching."""
    T_object_palm: np.ndarray
    """(4, 4) hand placement after the back-off (at ``start_mm`` when ``s_mm`` is NaN)."""
    q: np.ndarray
    """(15,) joint angles with the long fingers final and the thumb open, rad."""
    contacts: ContactSet
    """Contacts of the palm and the long fingers."""
    queries: int
    """Distance queries spent."""
    derived: dict[str, Obstacles] = field(default_factory=dict, repr=False, compare=False)
    """Per-process memo of what every design derives alike from this stage (what the thumb
    closes against on the compiled engine: ``_thumb_obstacles``); not stored."""


def _placement(hyps: Hypotheses, i: int, s: float, kit: HandKit) -> np.ndarray:
    """(4, 4) T_object_palm with the approach point at ``target + s · ray``."""
    T = np.eye(4)
    R = hyps.R_object_palm[i]
    T[:3, :3] = R
    T[:3, 3] = hyps.target_object + s * hyps.ray_object[i] - R @ kit.hand.approach_point_palm
    return T


def _approach_start(obj: GraspTarget, hyps: Hypotheses, closing: ClosingSettings) -> float:
    """Where the approach starts on the ray: clear of the object by the approach clearance."""
    start = float(np.linalg.norm(hyps.target_object - obj.centroid_object)) + obj.max_radius
    return start + closing.approach_clearance_mm


def _approach_links(
    kit: HandKit,
    obj: GraspTarget,
    hyps: Hypotheses,
    i: int,
    idx: list[int],
    start: float,
    closing: ClosingSettings,
    stats: ClosingStats,
    floor_mm: float | None = None,
) -> float:
    """First contact (ray parameter, mm; NaN for none) of the open hand's links ``idx``;
    NaN too when there is none above ``floor_mm`` (``approach``)."""
    obj_arr = _object_arrays(obj, closing)
    key = tuple(idx)
    s = approach(
        [kit.moving[j] for j in idx] if obj_arr is None else [],  # the arrays are read
        kit.approach_poses(key),
        hyps.R_object_palm[i],
        hyps.ray_object[i],
        hyps.target_object,
        kit.hand.approach_point_palm,
        list(obj.collision_objects()) if obj_arr is None else [],
        start,
        closing,
        stats,
        None if obj_arr is None else (kit.approach_arrays(key), obj_arr),
        floor_mm,
    )
    return math.nan if s is None else s


def _close_long_fingers(
    kit: HandKit,
    obj: GraspTarget,
    hyps: Hypotheses,
    i: int,
    s_contact: float,
    settings: SimulationSettings,
    stats: ClosingStats,
    fingers: tuple[str, ...] | None,
) -> tuple[np.ndarray, np.ndarray, ContactSet, int]:
    """Back off from the first contact at ``s_contact`` by the standoff, close the long
    fingers; (T_object_palm, q, contacts of palm + long fingers, their queries)."""
    closing = settings.closing
    T = _placement(hyps, i, s_contact + float(hyps.standoff_mm[i]), kit)
    q = kit.q_open.copy()
    pieces = list(obj.collision_objects())
    obstacles = Obstacles(
        pieces, len(pieces), spheres=_object_spheres(obj), arrays=_object_arrays(obj, closing)
    )
    for finger in fingers if fingers is not None else closing_fingers(obj.spec.grasp_type):
        if finger == "thumb":
            continue
        ch = kit.chains[finger]
        q[list(ch.joints)] = close_finger(ch, kit.bodies(finger), T, obstacles, closing, stats)
    cs, n_q = kit.contacts(obj, T @ kit.hand.link_poses(q), kit.non_thumb, settings)
    return T, q, cs, n_q


def simulate_palm(
    kit: HandKit,
    obj: GraspTarget,
    hyps: Hypotheses,
    i: int,
    settings: SimulationSettings,
    stats: ClosingStats | None = None,
    fingers: tuple[str, ...] | None = None,
) -> PalmGrasp:
    """The thumbless hand: approach, back off by the standoff, close the long fingers; the
    contacts of palm + long fingers. Independent of the thumb design (any kit of the hand
    file gives the same numbers). ``fingers`` as in ``simulate_base``."""
    stats = stats if stats is not None else ClosingStats()
    start = _approach_start(obj, hyps, settings.closing)
    q0 = stats.queries
    s = _approach_links(kit, obj, hyps, i, kit.non_thumb, start, settings.closing, stats)
    if math.isnan(s):
        T = _placement(hyps, i, start, kit)
        return PalmGrasp(start, s, T, kit.q_open.copy(), ContactSet(), stats.queries - q0)
    T, q, cs, n_q = _close_long_fingers(kit, obj, hyps, i, s, settings, stats, fingers)
    return PalmGrasp(start, s, T, q, cs, stats.queries - q0 + n_q)


def simulate_base(
    kit: HandKit,
    obj: GraspTarget,
    hyps: Hypotheses,
    i: int,
    settings: SimulationSettings,
    stats: ClosingStats | None = None,
    fingers: tuple[str, ...] | None = None,
    palm: PalmGrasp | None = None,
) -> BaseGrasp:
    """Approach, back off by the standoff, close the long fingers; contacts of palm + fingers.

    The approach stops at the first contact of the open hand, thumb included: the later of
    the palm-and-long-fingers' first contact (``palm``, computed when not given) and the open
    thumb's (this kit's CMC angle). Only when the thumb touches first are the long fingers
    closed again from its placement. ``fingers``: the fingers that close (default
    ``closing_fingers`` of the object's grasp type; the brute-force set closes all). The
    thumb, if listed, is left to ``simulate_thumb``.
    """
    closing = settings.closing
    stats = stats if stats is not None else ClosingStats()
    n_stages = len(stats.stages) if stats.stages is not None else 0
    if palm is None:
        palm = simulate_palm(kit, obj, hyps, i, settings, stats, fingers)
    mark, queries = stats.queries, palm.queries
    start = palm.start_mm
    # the open thumb matters only if it touches before the palm and long fingers do
    floor = None if math.isnan(palm.s_mm) else palm.s_mm
    s_thumb = _approach_links(kit, obj, hyps, i, kit.thumb_links, start, closing, stats, floor)
    T, q, cs, s = palm.T_object_palm, palm.q, palm.contacts, palm.s_mm
    if not math.isnan(s_thumb) and (math.isnan(s) or s_thumb > s):
        s = s_thumb  # the open thumb touches first: the hand stops there
        if stats.stages is not None:
            del stats.stages[n_stages:]  # the long fingers close again from here
        T, q, cs, n_q = _close_long_fingers(kit, obj, hyps, i, s, settings, stats, fingers)
        queries += n_q
    queries += stats.queries - mark
    if math.isnan(s):
        return BaseGrasp(False, T, q.copy(), ContactSet(), queries)
    if stats.stages is not None:
        stats.approach_s = (start, s)
    if T is palm.T_object_palm:
        obstacles = palm_thumb_obstacles(kit, obj, palm, closing)
    else:
        obstacles = _thumb_obstacles(kit, obj, T, q, closing)
    shared = obstacles if obstacles.arrays is not None else None  # FCL bodies are the kit's
    base = BaseGrasp(True, T, q.copy(), cs, queries, shared)
    if closing.mode == "sequential":
        # the thumb's CMC stage, shared by every MCP angle, is closed here by this (the base)
        # kit, so that it never depends on which design happens to close its thumb first
        thumb, st = kit.chains["thumb"], ClosingStats()
        close_finger(thumb, kit.bodies("thumb"), T, obstacles,
                     closing, st, base.thumb_first_stage, first_stage_only=True)  # fmt: skip
        base = dataclasses.replace(base, queries=base.queries + st.queries)
    return base


def palm_thumb_obstacles(
    kit: HandKit, obj: GraspTarget, palm: PalmGrasp, closing: ClosingSettings
) -> Obstacles:
    """What the thumb closes against on the palm stage's placement: the same posed object and
    non-thumb links for every design, so made once per palm stage and process and kept in
    ``palm.derived`` (compiled engine: arrays only; FCL bodies are the kit's, made anew).
    Any kit of the hand file gives the same obstacles."""
    got = palm.derived.get("thumb_obstacles")
    if got is None:
        got = _thumb_obstacles(kit, obj, palm.T_object_palm, palm.q, closing)
        if got.arrays is not None:
            palm.derived["thumb_obstacles"] = got
    return got


def _thumb_obstacles(
    kit: HandKit, obj: GraspTarget, T: np.ndarray, q: np.ndarray, closing: ClosingSettings
) -> Obstacles:
    """What the thumb closes against: the object, and (self-collision) the palm and the long
    fingers posed at ``q`` (15,), the base posture (the same in every design of a hand
    file)."""
    pieces = list(obj.collision_objects())
    others = kit.non_thumb
    T_fcl = T @ kit.hand.link_poses(q)[others] @ kit.T_link_fcl[others]  # (13, 4, 4)
    obj_arr = _object_arrays(obj, closing)
    if obj_arr is None:  # the compiled engine reads the arrays only
        for n, j in enumerate(others):
            kit.static[j].setTransform(fcl_transform(T_fcl[n]))
    objs = pieces + [kit.static[j] for j in others]
    mask = np.ones((3, len(objs)), bool)
    mask[0, len(pieces)] = False  # the metacarpal sits in the thenar: never against the palm
    spheres = np.full((len(objs), 4), np.inf)
    spheres[: len(pieces)] = _object_spheres(obj)
    spheres[len(pieces) :, :3] = T_fcl[:, :3, 3]
    spheres[len(pieces) :, 3] = kit.reach[others]
    arrays = None if obj_arr is None else kit.thumb_obstacle_arrays(obj_arr, T_fcl)
    return Obstacles(objs, len(pieces), mask, spheres, arrays)


def _thumb_poses(
    thumb: FingerChain, T: np.ndarray, q_thumb: np.ndarray, closing: ClosingSettings
) -> np.ndarray:
    """(3, 4, 4) T_object_link of the thumb's links at its joint angles (3,): the compiled
    engine's own product (one call), else the chain's."""
    if closing.engine == "compiled":
        from app.sim.closing_compiled import chain_arrays, thumb_link_poses

        return thumb_link_poses(chain_arrays(thumb)[0], np.ascontiguousarray(q_thumb, float),
                                np.ascontiguousarray(T, float))  # fmt: skip
    return T @ thumb.link_poses(q_thumb)


def _n_main(kit: HandKit, T_distal: np.ndarray) -> np.ndarray:
    """The thumb distal link's long axis from its pose (link +y unless the hand file's
    reading builds the thumb oblique to its hinges: ``Hand.thumb_bones``)."""
    b = kit.hand.thumb_bones[2]
    return T_distal[:3, 1].copy() if b[1] == 1.0 else T_distal[:3, :3] @ b


def simulate_thumb(
    kit: HandKit,
    obj: GraspTarget,
    base: BaseGrasp,
    settings: SimulationSettings,
    stats: ClosingStats | None = None,
) -> Grasp:
    """Close the thumb of ``kit``'s design on a base grasp; all contacts of the final grasp."""
    q = base.q.copy()
    T = base.T_object_palm
    thumb = kit.chains["thumb"]
    if not base.approached:
        n_main = _n_main(kit, T @ kit.hand.link_poses(q)[thumb.link_indices[2]])
        return Grasp(T, q, base.contacts, n_main, False, 0)
    closing = settings.closing
    stats = stats if stats is not None else ClosingStats()
    obstacles = base.thumb_obstacles or _thumb_obstacles(kit, obj, T, q, closing)
    q[list(thumb.joints)] = close_finger(
        thumb, kit.bodies("thumb"), T, obstacles, closing, stats, base.thumb_first_stage
    )
    idx = list(thumb.link_indices)
    T_links = np.empty((len(kit.names), 4, 4))  # only the thumb's rows are read
    T_links[idx] = _thumb_poses(thumb, T, q[list(thumb.joints)], closing)
    cs, n_q = kit.contacts(obj, T_links, idx, settings)
    return Grasp(
        T,
        q,
        merge(base.contacts, cs),
        _n_main(kit, T_links[idx[2]]),
        True,
        stats.queries + n_q,
        tuple(stats.events),
    )


@lru_cache(maxsize=256)
def cached_kit(cmc_deg: float, mcp_deg: float, tilt: str) -> HandKit:
    """The simulation kit of a design (per process; the hand file is the default one)."""
    return HandKit(Hand(ThumbDesign(cmc_deg, mcp_deg, tilt), load_hand_dims()))  # type: ignore[arg-type]


#: The MCP angle of the kit that computes a design's base stage. With MCP and IP open the
#: thumb's capsules lie on the metacarpal's line (for a hand file whose reading keeps the open
#: thumb straight), so the base stage (approach, back-off, long fingers, and the memo of the
#: thumb's CMC stage) is the same for every MCP angle up to rounding; computing it always with
#: one kit makes every result independent of which other designs were simulated beside it (a
#: sweep's task grouping, the explorer's replay).
BASE_MCP_DEG = 0.0


def base_mcp_deg(design: ThumbDesign) -> float:
    """The MCP angle of the kit that computes ``design``'s base stage: ``BASE_MCP_DEG``, or
    the design's own when the default hand file bends the open thumb by m."""
    if load_hand_dims().thumb.reading.open_thumb_depends_on_mcp:
        return design.mcp_deg
    return BASE_MCP_DEG


def base_kit(design: ThumbDesign) -> HandKit:
    """The kit that computes the base stage of ``design`` (shared by every design with the
    same CMC angle and tilt, unless the open thumb depends on m)."""
    return cached_kit(design.cmc_deg, base_mcp_deg(design), design.cmc_tilt)
