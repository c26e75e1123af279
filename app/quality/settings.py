"""All simulation settings in one typed tree: closing, contacts, force closure, grasp type.

Every threshold has the published default; ``SimSettings.key()`` is part of every stored
result's key, so changing any setting never mixes results.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from app.quality.force_closure import FCSettings
from app.quality.grasp_type import GraspTypeSettings
from app.sim.closing_settings import ClosingSettings
from app.sim.contacts import ContactSettings

#: Bumped whenever a code change alters simulated outcomes: part of the settings key, so a
#: store never serves results of an older engine as current.
ENGINE_VERSION = 8  # 8: capsule-capsule and capsule-cylinder distances in closed form, GJK
# climbing large hulls' edges (distances equal to ~1e-9 mm; a stop can move within the
# stage's tolerance band)
# 7: the approach stops at the later of the thumbless hand's and the open
# thumb's first contacts, each found by its own steps (the thumbless part is shared by designs)
# 6: a contact patch is every link sample within tol (no 30 mm disc about
# the nearest point), thinned in the link frame
# 5: base stage always by the MCP-0 kit (results independent of grouping)
# 4: stage stop refined by false position (gap within 0.001 mm of tol)


@dataclass(frozen=True)
class SimSettings:
    """Everything that changes a simulated outcome besides the design, object and GH."""

    closing: ClosingSettings = field(default_factory=ClosingSettings)
    """Approach and closing (METHOD §4)."""
    contact: ContactSettings = field(default_factory=ContactSettings)
    """Contact patches and palmar classification (METHOD §5)."""
    fc: FCSettings = field(default_factory=FCSettings)
    """Force closure: friction and cone linearisation (METHOD §5)."""
    grasp_type: GraspTypeSettings = field(default_factory=GraspTypeSettings)
    """Grasp-type correctness criteria (METHOD §5)."""

    def __post_init__(self) -> None:
        from app.errors import SettingsError

        if self.closing.stop_tol_mm > self.contact.contact_tol_mm:
            raise SettingsError(
                f"stop_tol_mm ({self.closing.stop_tol_mm}) must not exceed contact_tol_mm "
                f"({self.contact.contact_tol_mm}): a stopped link must count as touching"
            )

    def as_dict(self) -> dict[str, object]:
        """Nested plain dict (JSON, hashing)."""
        return asdict(self)

    def key(self) -> str:
        """Stable hash of all settings (store key).

        The closing engine enters the key only when it is 'compiled' (the default since
        engine 6), as it did when 'fcl' was the default, so the two engines' results are never
        mixed."""
        from app.hashing import stable_hash

        d = self.as_dict()
        closing = d["closing"]
        assert isinstance(closing, dict)
        if closing.get("engine") == "fcl":
            del closing["engine"]
        return stable_hash({"engine_version": ENGINE_VERSION, **d})
