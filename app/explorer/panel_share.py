"""Export and sharing: save the view as PNG (and download it), the state link, a share URL."""

from __future__ import annotations

import io
import socket
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np
import viser

SHARE_TIMEOUT_S = 10.0
RENDER_SIZE = (900, 1400)  # (height, width)


def png_bytes(rgb: np.ndarray) -> bytes:
    """Encode an (H, W, 3|4) uint8 image as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    plt.imsave(buf, np.ascontiguousarray(rgb), format="png")
    return buf.getvalue()


WRAP = "<div style='overflow-wrap:anywhere;word-break:break-word'>{}</div>"
"""Long paths and links wrap inside the panel instead of running out of it."""


def short_path(path: Path) -> str:
    """``path`` relative to the working folder, or with ``~`` for the home folder."""
    path = Path(path).absolute()
    for base, shown in ((Path.cwd(), ""), (Path.home(), "~/")):
        try:
            return shown + str(path.relative_to(base))
        except ValueError:
            continue
    return str(path)


def lan_hint(port: int) -> str:
    """How to reach this server from another machine of the network."""
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.connect(("192.0.2.1", 9))  # no packet is sent (UDP connect)
            ip = s.getsockname()[0]
    except OSError:
        ip = "<this machine's IP>"
    return (
        f"On the local network: run `handbench serve --host 0.0.0.0 --port {port}` and open "
        f"`http://{ip}:{port}`."
    )


def _tunnel_in_a_thread() -> None:
    """Make viser run its share tunnel in a thread of this process.

    viser starts the tunnel in a ``multiprocessing`` process when the main script has an
    ``if __name__ == "__main__"`` guard (the ``handbench`` entry point has one): with the
    default 'fork' start method that copies the whole server (450-640 MB), and the copy
    outlives a SIGTERM of the server, holding its port. viser's own thread mode is chosen
    by ``viser._tunnel._is_multiprocess_ok``; answering False selects it.
    """
    import viser._tunnel as tunnel  # noqa: PLC2701 - no public switch for this

    tunnel._is_multiprocess_ok = lambda: False  # type: ignore[assignment]  # noqa: SLF001


def request_share_url(server: viser.ViserServer, timeout_s: float = SHARE_TIMEOUT_S) -> str | None:
    """viser's public share URL (its tunnel in a thread of this process, never a forked
    copy), or None when offline or slower than ``timeout_s``."""
    _tunnel_in_a_thread()
    box: list[str | None] = [None]

    def run() -> None:
        try:
            box[0] = server.request_share_url(verbose=False)
        except Exception:  # noqa: BLE001 - offline shows up as any network error
            box[0] = None

    t = threading.Thread(target=run, name="share-url", daemon=True)
    t.start()
    t.join(timeout_s)
    return box[0]


class SharePanel:
    """'Save PNG', the link of the current state, 'Public share URL'.

    Like the other panels it knows nothing of the session: the session hands it callbacks.
    """

    def __init__(
        self,
        gui: viser.GuiApi,
        *,
        state_link: Callable[[], str],
        render: Callable[[int, int], np.ndarray],
        shot_name: Callable[[], str],
        shots_dir: Path,
        download: Callable[[str, bytes], None],
        share_url: Callable[[], str | None],
        port: Callable[[], int],
    ) -> None:
        self._state_link = state_link
        self._render = render
        self._shot_name = shot_name
        self._shots_dir = shots_dir
        self._download = download
        self._share_url = share_url
        self._port = port
        self.save = gui.add_button("Save PNG of the view", icon=viser.Icon.CAMERA)
        self.saved = gui.add_markdown("")
        self.link = gui.add_markdown("")
        self.share = gui.add_button("Public share URL", icon=viser.Icon.SHARE)
        self.share_md = gui.add_markdown("")
        self.save.on_click(lambda _: self._save())
        self.share.on_click(lambda _: self._share())

    def update_link(self) -> None:
        """Show the link that reopens the current design, object and GH."""
        url = self._state_link()
        self.link.content = WRAP.format(f"Link to this state:<br><a href='{url}'>{url}</a>")

    def _save(self) -> None:
        self.saved.content = "rendering…"
        h, w = RENDER_SIZE
        try:
            img = self._render(h, w)
        except (TimeoutError, RuntimeError) as e:
            self.saved.content = f"could not render: {e}"
            return
        data = png_bytes(img)
        name = self._shot_name()
        self._shots_dir.mkdir(parents=True, exist_ok=True)
        path = self._shots_dir / name
        path.write_bytes(data)
        self._download(name, data)
        folder = short_path(path.parent)
        self.saved.content = WRAP.format(
            f"saved <b>{name}</b><br>in <code>{folder}</code> (and sent as a download)"
        )

    def _share(self) -> None:
        self.share_md.content = "asking viser's share server…"
        url = self._share_url()
        if url:
            self.share_md.content = f"Public URL (24 h): [{url}]({url})"
        else:
            self.share_md.content = (
                "No public share URL (offline, or the share server did not answer in "
                f"{SHARE_TIMEOUT_S:g} s).  \n" + lan_hint(self._port())
            )
