"""The S_GAS panel: a progress bar and the table of the latest ``ScoreSnapshot``."""

from __future__ import annotations

import viser

from app.explorer.live_score import ScoreSnapshot, snapshot_markdown


class ScorePanel:
    """Progress bar and table."""

    def __init__(self, gui: viser.GuiApi) -> None:
        self.progress = gui.add_progress_bar(0.0, animated=False)
        self.table = gui.add_markdown("S_GAS: waiting for the first design")
        self.last: ScoreSnapshot | None = None

    def show(self, s: ScoreSnapshot) -> None:
        """Render a snapshot."""
        self.last = s
        total = sum(s.n_gh.values())
        have = sum(min(c[0], s.n_gh[k]) for k, c in s.counts.items())
        self.progress.value = 100.0 * have / total if total else 100.0
        self.progress.animated = s.state in ("computing", "waiting")
        self.table.content = snapshot_markdown(s)
