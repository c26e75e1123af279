"""Two of viser's own toasts, tamed by a page script (installed like ``input_commit``'s).

- "Software WebGL rendering detected" (viser's BrowserWarning) has no auto-close: it stayed
  on screen for the whole session. The script closes it after ``WEBGL_TOAST_S``.
- "File uploaded successfully." (viser's upload button) appeared beside the import panel's
  own verdict ("import failed: ..."), which is the one that matters: the script closes it
  as soon as the upload is done.

Each toast is closed through its own close button (Mantine animates it away), or removed
when it has none.
"""

from __future__ import annotations

import base64

WEBGL_TOAST_S = 4.0
"""Seconds the software-WebGL toast stays up."""

_JS = r"""
(function () {
  if (window.__hbToasts) return;
  window.__hbToasts = [];  // what was closed (title | description), for tests
  const rules = [
    { match: (t, d) => t.startsWith("Software WebGL rendering"), after: WEBGL_MS },
    { match: (t, d) => d.startsWith("File uploaded successfully"), after: 0 },
  ];
  const handled = new WeakSet();
  const text = (n, part) =>
    (n.querySelector(".mantine-Notification-" + part) || {}).textContent || "";
  function close(n, what) {
    window.__hbToasts.push(what);
    const b = n.querySelector(".mantine-Notification-closeButton");
    if (b) b.click();
    else n.remove();
  }
  function scan() {
    for (const n of document.querySelectorAll(".mantine-Notification-root")) {
      if (handled.has(n)) continue;
      const t = text(n, "title"), d = text(n, "description");
      for (const r of rules) {
        if (!r.match(t, d)) continue;
        handled.add(n);
        n.dataset.hbAutoClose = String(r.after);
        const what = t + " | " + d;
        if (r.after > 0) setTimeout(() => close(n, what), r.after);
        else close(n, what);
        break;
      }
    }
  }
  new MutationObserver(scan).observe(document.body, {
    childList: true, subtree: true, characterData: true,
  });
  scan();
})();
""".replace("WEBGL_MS", str(int(WEBGL_TOAST_S * 1000)))


def toast_script_html() -> str:
    """Hidden HTML whose image ``onerror`` installs the script (once per page)."""
    b64 = base64.b64encode(_JS.encode()).decode()
    return (
        '<img alt="" src="data:image/gif;base64,x" style="display:none" '
        f"onerror=\"eval(atob('{b64}'))\">"
    )
