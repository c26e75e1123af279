"""The grasp panel: choose a grasp hypothesis (GH) through filters, play its replay, and
read its outcome (FC, correct, and why not) next to the contact legend."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import viser

from app.explorer.scene_object import CONTACT_COLORS
from app.quality.outcome import GraspOutcome
from app.sim.closing_settings import CLOSING_MODES
from app.sim.hypotheses import Hypotheses

ALL: str = "all"
OUTCOME_FILTERS = (ALL, "FC", "correct", "FC not correct", "failed (not FC)")

LEGEND_MD = (
    "  \n".join(
        f"<span style='color:rgb{CONTACT_COLORS[k]}'>&#9679;</span> {text}"
        for k, text in (
            ("palmar", "palmar contact on a finger"),
            ("non_palmar", "non-palmar contact on a finger"),
            ("palm", "contact on the palm"),
        )
    )
    + "  \n<span style='color:rgb(200,30,160)'>&#9679;</span> P and hand vector n"
)


def outcome_passes(o: GraspOutcome | None, kind: str) -> bool:
    """Whether a stored outcome matches an outcome filter (unknown outcomes never do)."""
    if kind == ALL:
        return True
    if o is None:
        return False
    return {
        "FC": o.is_fc,
        "correct": o.is_correct,
        "FC not correct": o.is_fc and not o.is_correct,
        "failed (not FC)": not o.is_fc,
    }[kind]


def outcome_markdown(o: GraspOutcome, gh_id: str, n_contacts: int) -> str:
    """FC yes/no, correct yes/no and the reasons, as panel markdown."""
    yes = "**yes**"
    lines = [
        f"`{gh_id}`",
        f"FC: {yes if o.is_fc else 'no'}" + (f" (ε = {o.epsilon:.3g})" if o.epsilon > 0 else ""),
        f"correct: {yes if o.is_correct else 'no'}",
        f"contact points: {n_contacts}",
    ]
    if o.reasons:
        lines.append("why not: " + "; ".join(o.reasons))
    return "  \n".join(lines)


class ReplayPanel:
    """GH filters, the GH slider (over the filtered list), play, mode, outcome and legend."""

    def __init__(
        self,
        gui: viser.GuiApi,
        on_select: Callable[[int], None],
        on_play: Callable[[], None],
        on_mode: Callable[[str], None],
        load_outcomes: Callable[[], Mapping[str, GraspOutcome]],
    ) -> None:
        self._on_select = on_select
        self._muted = False
        self.indices: np.ndarray = np.zeros(0, dtype=int)
        only_all: tuple[str, ...] = (ALL,)
        self.standoff = gui.add_dropdown("Standoff", options=only_all, initial_value=ALL)
        self.roll = gui.add_dropdown("Roll", options=only_all, initial_value=ALL)
        self.ray = gui.add_dropdown("Ray", options=only_all, initial_value=ALL)
        self.outcome = gui.add_dropdown("Outcome", options=OUTCOME_FILTERS, initial_value=ALL)
        gui.add_markdown(
            "<small>Outcome: the stored outcome of this design (the S_GAS worker's).</small>"
        )
        self.gh = gui.add_slider("GH", min=0, max=1, step=1, initial_value=0)
        self.count = gui.add_markdown("")
        self.play = gui.add_button("Play replay", icon=viser.Icon.PLAYER_PLAY)
        self.mode = gui.add_dropdown(
            "Closing", options=CLOSING_MODES, initial_value=CLOSING_MODES[0]
        )
        gui.add_markdown(
            "<small>Closing: sequential (published), independent thumb, or coupled tendon "
            "(METHOD §4).</small>"
        )
        self.stage = gui.add_markdown("")
        self.result = gui.add_markdown("")
        gui.add_markdown(LEGEND_MD)
        for dd in (self.standoff, self.roll, self.ray, self.outcome):
            dd.on_update(lambda _: self._filter_changed())
        self.gh.on_update(lambda _: self._slider_changed())
        self.play.on_click(lambda _: on_play())
        self.mode.on_update(lambda _: on_mode(self.mode.value))
        self._hyps: Hypotheses | None = None
        self._load_outcomes = load_outcomes
        self._outcomes: Mapping[str, GraspOutcome] = {}
        self._known: set[str] = set()

    def set_hypotheses(self, hyps: Hypotheses) -> None:
        """New object: rebuild the filter choices."""
        self._hyps = hyps
        self._muted = True
        try:
            st = sorted(set(np.round(hyps.standoff_mm, 3).tolist()))
            rl = sorted(set(np.round(np.rad2deg(hyps.roll_rad), 2).tolist()))
            self.standoff.options = (ALL, *(f"{v:g} mm" for v in st))
            self.roll.options = (ALL, *(f"{v:g}°" for v in rl))
            self.ray.options = (ALL, *(str(r) for r in sorted(set(hyps.ray_index.tolist()))))
            for dd in (self.standoff, self.roll, self.ray, self.outcome):
                dd.value = ALL
        finally:
            self._muted = False
        self._outcomes = {}
        self._known = set()
        self._refresh_slider(keep=None)  # the GH range of the new object, not the old one
        self._update_count()

    def set_known(self, ids: set[str]) -> None:
        """Ids of the GHs with a stored outcome for the current design (the outcome filter
        loads their outcomes only while it is in use)."""
        self._known = ids
        if self.outcome.value != ALL:
            self._filter_changed()
        else:
            self._update_count()

    def filtered(self) -> np.ndarray:
        """Indices of the hypotheses passing every filter."""
        h = self._hyps
        if h is None:
            return np.zeros(0, dtype=int)
        keep = np.ones(len(h), dtype=bool)
        if self.standoff.value != ALL:
            keep &= np.isclose(h.standoff_mm, float(self.standoff.value.split()[0]))
        if self.roll.value != ALL:
            keep &= np.isclose(np.rad2deg(h.roll_rad), float(self.roll.value[:-1]), atol=0.01)
        if self.ray.value != ALL:
            keep &= h.ray_index == int(self.ray.value)
        if self.outcome.value != ALL:
            kind = self.outcome.value
            if set(self._outcomes) != self._known:
                self._outcomes = self._load_outcomes()
            keep &= np.array([outcome_passes(self._outcomes.get(i), kind) for i in h.ids])
        return np.flatnonzero(keep)

    def select_index(self, i: int) -> None:
        """Point the slider at hypothesis ``i`` (clearing filters that exclude it)."""
        if i not in self.indices:
            self._muted = True
            for dd in (self.standoff, self.roll, self.ray, self.outcome):
                dd.value = ALL
            self._muted = False
            self._refresh_slider(keep=None)
        pos = int(np.searchsorted(self.indices, i))
        self._muted = True
        self.gh.value = pos
        self._muted = False
        self._update_count()

    def current(self) -> int | None:
        """The selected hypothesis index, or None when the filters leave nothing."""
        if len(self.indices) == 0:
            return None
        return int(self.indices[min(int(self.gh.value), len(self.indices) - 1)])

    def _refresh_slider(self, keep: int | None) -> None:
        self.indices = self.filtered()
        n = len(self.indices)
        self._muted = True
        try:
            self.gh.max = max(n - 1, 1)
            self.gh.disabled = n == 0
            pos = 0
            if keep is not None and n and keep in self.indices:
                pos = int(np.searchsorted(self.indices, keep))
            self.gh.value = pos
        finally:
            self._muted = False

    def _update_count(self) -> None:
        h = self._hyps
        n = len(self.indices)
        if h is None or n == 0:
            self.count.content = "no hypothesis passes the filters"
            return
        i = self.current()
        assert i is not None
        known = len(self._known)
        self.count.content = (
            f"GH {int(self.gh.value) + 1} of {n} shown (of {len(h)}); index {i}  \n"
            f"stored outcomes for this design: {known}/{len(h)}"
        )

    def _filter_changed(self) -> None:
        if self._muted:
            return
        keep = self.current()
        self._refresh_slider(keep)
        self._update_count()
        i = self.current()
        if i is not None:
            self._on_select(i)

    def _slider_changed(self) -> None:
        if self._muted:
            return
        self._update_count()
        i = self.current()
        if i is not None:
            self._on_select(i)
