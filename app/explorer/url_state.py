"""Links that open a state: ``http://host:port/?cmc=30&mcp=75&object=chips_can&gh=17``
(``&tilt=radial`` for the radial CMC tilt; ulnar, the default, is left out).

viser does not tell the server a page's URL (the websocket URL drops the query). So each new
tab gets a hidden HTML element whose image ``onerror`` handler copies ``location.search``
into the tab's localStorage under a key unique to that tab; the server reads it back with
``client.local_storage.get_item`` (viser's own API) and applies it. A key per tab keeps two
tabs opened at once from reading each other's link.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from urllib.parse import parse_qs, urlencode

from app.errors import HandbenchError

TILTS: tuple[str, ...] = ("ulnar", "radial")
"""Valid values of the ``tilt`` link parameter (``ThumbDesign.cmc_tilt``)."""

LOCAL_STORAGE_PREFIX = "viser-user:"
"""The prefix viser's client puts before keys written through ``client.local_storage``."""


class UrlStateError(HandbenchError, ValueError):
    """A link whose query holds an invalid value."""


@dataclass(frozen=True)
class UrlState:
    """The state a link asks for (None: keep the default)."""

    cmc_deg: float | None = None
    mcp_deg: float | None = None
    object_key: str | None = None
    gh: str | None = None
    """Hypothesis index ('17') or id ('chips_can/r07/d00/t03')."""
    tab: str | None = None
    """Panel tab to open first: 'design', 'grasp', 'map' (for screenshots)."""
    tilt: str | None = None
    """CMC tilt: 'ulnar' or 'radial' (None: keep the current one)."""

    def query(self) -> str:
        """'?cmc=30&mcp=75&object=chips_can&gh=17' (unset fields left out)."""
        d = {
            "cmc": None if self.cmc_deg is None else f"{self.cmc_deg:g}",
            "mcp": None if self.mcp_deg is None else f"{self.mcp_deg:g}",
            "object": self.object_key,
            "gh": self.gh,
            "tab": self.tab,
            "tilt": self.tilt,
        }
        return "?" + urlencode({k: v for k, v in d.items() if v is not None}, safe="/")


def parse_query(search: str) -> UrlState:
    """Parse ``location.search`` ('?cmc=30&...'); unknown keys are ignored."""
    q = {k: v[-1] for k, v in parse_qs(search.lstrip("?")).items()}

    def num(name: str) -> float | None:
        if name not in q:
            return None
        try:
            return float(q[name])
        except ValueError:
            raise UrlStateError(f"link parameter {name}={q[name]!r} is not a number") from None

    tilt = q.get("tilt")
    if tilt is not None and tilt not in TILTS:
        raise UrlStateError(f"link parameter tilt={tilt!r} must be one of {TILTS}")
    return UrlState(num("cmc"), num("mcp"), q.get("object"), q.get("gh"), q.get("tab"), tilt)


def new_probe_key() -> str:
    """A localStorage key unique to one tab."""
    return f"handbench-url-{uuid.uuid4().hex}"


RENDERER_SUFFIX = "-webgl"
"""The probe also writes the page's WebGL renderer under its key + this suffix."""
SOFTWARE_RENDERERS = ("swiftshader", "llvmpipe", "softpipe", "software", "basic render")
"""Words of a software WebGL renderer's name (no GPU: a frame of the scene costs the CPU
0.15-0.45 s on 2 cores)."""
_RENDERER_JS = (
    "(function () { try { const c = document.createElement('canvas');"
    " const g = c.getContext('webgl2') || c.getContext('webgl'); if (!g) return 'none';"
    " const e = g.getExtension('WEBGL_debug_renderer_info');"
    " const r = String(g.getParameter(e ? e.UNMASKED_RENDERER_WEBGL : g.RENDERER));"
    " const l = g.getExtension('WEBGL_lose_context'); if (l) l.loseContext(); return r;"
    " } catch (x) { return 'unknown'; } })()"
)


def probe_html(key: str) -> str:
    """Hidden HTML that writes this tab's ``location.search`` to localStorage[key] and its
    WebGL renderer's name to localStorage[key + RENDERER_SUFFIX]."""
    k = f"{LOCAL_STORAGE_PREFIX}{key}"
    js = (
        f"localStorage.setItem('{k}{RENDERER_SUFFIX}', {_RENDERER_JS});"
        f" localStorage.setItem('{k}', window.location.search || '?');"
    )
    return f'<img alt="" src="data:image/gif;base64,x" style="display:none" onerror="{js}">'


def is_software_renderer(name: str) -> bool:
    """Whether a WebGL renderer's name is a software rasterizer's."""
    n = name.lower()
    return any(w in n for w in SOFTWARE_RENDERERS)
