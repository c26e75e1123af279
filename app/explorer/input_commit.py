"""Slider number boxes that commit on Enter or blur, never per keystroke.

viser's slider has a number box whose every keystroke is sent to the server: typing "500"
sends 5, 50, 500. This page script (installed once per tab through a hidden HTML element,
like the link probe) holds back the box's ``input``/``change`` events until Enter or blur,
then checks the text against the slider's range (``aria-valuemin``/``max`` of its knob).
A valid number is let through as one event; anything else puts the last value back and
shows an inline message (``.hb-input-msg``) under the row. The server validates again
(``DesignPanel``): this script only keeps intermediate text from becoming a value.
"""

from __future__ import annotations

import base64

MESSAGE_CLASS = "hb-input-msg"
"""CSS class of the inline message a rejected entry shows (tests look for it)."""

_JS = r"""
(function () {
  if (window.__hbCommit) return;
  const st = (window.__hbCommit = { pass: false });
  const rowOf = (t) =>
    t instanceof HTMLInputElement && t.type === "text"
      ? t.closest("div:has(> .mantine-Slider-root)")
      : null;
  const knobOf = (row) => row.querySelector("[role=slider]");
  function message(row, text) {
    let m = row.parentElement.querySelector(":scope > .MSGCLASS");
    if (!text) { if (m) m.remove(); return; }
    if (!m) {
      m = document.createElement("div");
      m.className = "MSGCLASS";
      m.setAttribute("role", "alert");
      m.style.cssText = "color:#c92a2a;font-size:0.75rem;margin:0.1rem 0 0.2rem 0;";
      row.insertAdjacentElement("afterend", m);
    }
    m.textContent = text;
  }
  function commit(inp) {
    const row = rowOf(inp);
    const knob = knobOf(row);
    const lo = Number(knob.getAttribute("aria-valuemin"));
    const hi = Number(knob.getAttribute("aria-valuemax"));
    const last = inp.dataset.hbLast ?? knob.getAttribute("aria-valuenow") ?? "";
    const text = inp.value.trim();
    const v = Number(text);
    let err = null;
    if (text === "" || !Number.isFinite(v)) err = `"${text}" is not a number`;
    else if (v < lo || v > hi) err = `${text} is outside ${lo} to ${hi}`;
    if (err) {
      message(row, `${err}; kept ${last}.`);
      inp.value = last;
    } else {
      message(row, null);
    }
    st.pass = true;
    try { inp.dispatchEvent(new Event("input", { bubbles: true })); }
    finally { st.pass = false; }
    inp.dataset.hbLast = inp.value;
  }
  window.addEventListener("focusin", (e) => {
    if (rowOf(e.target)) e.target.dataset.hbLast = e.target.value;
  }, true);
  for (const kind of ["input", "change"]) {
    window.addEventListener(kind, (e) => {
      if (!st.pass && rowOf(e.target)) e.stopImmediatePropagation();
    }, true);
  }
  window.addEventListener("keydown", (e) => {
    if (e.key === "Enter" && rowOf(e.target)) commit(e.target);
  }, true);
  window.addEventListener("focusout", (e) => {
    if (rowOf(e.target)) commit(e.target);
  }, true);
})();
""".replace("MSGCLASS", MESSAGE_CLASS)


def commit_script_html() -> str:
    """Hidden HTML whose image ``onerror`` installs the script (once per page)."""
    b64 = base64.b64encode(_JS.encode()).decode()
    return (
        '<img alt="" src="data:image/gif;base64,x" style="display:none" '
        f"onerror=\"eval(atob('{b64}'))\">"
    )
