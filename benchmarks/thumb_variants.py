"""Write the thumb readings screened in docs/validation.md as hand files.

Usage: python benchmarks/thumb_variants.py NAME [NAME ...]   (or 'all')
Each file is hand_models/study/<NAME>.toml: the first reading's hand (imma_right_v1.toml)
with only the thumb's reading keys, CMC position and joint ranges replaced. Run a sweep on
one with HANDBENCH_HAND=hand_models/study/<NAME>.toml.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

from app.model.hand.data import V1_READING

ROOT = Path(__file__).resolve().parents[1]
BASE = ROOT / "hand_models" / "imma_right_v1.toml"
HUMAN = [[0, 70], [0, 50], [0, 80]]
WIDE = [[0, 70], [0, 90], [0, 90]]


def inplane(beta_deg: float) -> list[float]:
    """A palm-plane direction beta degrees from +y (distal) toward +x (radial)."""
    b = math.radians(beta_deg)
    return [math.sin(b), math.cos(b), 0.0]


def raised(g_deg: float) -> list[float]:
    """The radial direction raised g degrees toward palmar (about the palm's y axis)."""
    g = math.radians(g_deg)
    return [math.cos(g), 0.0, math.sin(g)]


def normal_of_raised(g_deg: float) -> list[float]:
    """The palmar normal of a metacarpal raised g degrees: (-sin g, 0, cos g)."""
    g = math.radians(g_deg)
    return [-math.sin(g), 0.0, math.cos(g)]


#: name -> (description, thumb keys). Missing keys keep the first reading's value.
V1 = {
    **V1_READING,
    "cmc": [30.0, 18.0, 0.0],
    "limits": HUMAN,
}


def pins(beta: float, **kw) -> dict:
    """Bones fixed along the palm plane at beta from +y; c and m turn the hinge pins in the
    palm plane (about the palm normal), c ulnar from the proximal-distal axis, MCP at c + m."""
    return {
        **V1,
        "rest_direction": inplane(beta),
        "cmc_axis": [0, -1, 0],
        "cmc_tilt_line": [0, 0, 1],
        "bones_turn": False,
        "mcp_turn_line": "cmc_tilt_line",
        "mcp_sense": 1,
        **kw,
    }


VARIANTS: dict[str, tuple[str, dict]] = {
    "A_metacarpal_tilt": (
        "c turns the CMC axis about the metacarpal (c adds to m), human ranges",
        {**V1, "cmc_tilt_line": [-1, 0, 0]},
    ),
    "B_metacarpal_tilt_wide": (
        "A with printed MCP/IP ranges 0-90",
        {**V1, "cmc_tilt_line": [-1, 0, 0], "limits": WIDE},
    ),
    "D_v1_radial": (
        "v1 with the CMC axis leaning radially (c about -z)",
        {**V1, "cmc_tilt_line": [0, 0, -1]},
    ),
    "E_dorsal_mneg": (
        "A with m toward the metacarpal's dorsal side (c and m opposite)",
        {**V1, "cmc_tilt_line": [-1, 0, 0], "mcp_sense": -1},
    ),
    "F_palmar_mneg": (
        "CMC axis distal end leaning palmar (c about +x), m dorsal: c adds to m",
        {**V1, "cmc_tilt_line": [1, 0, 0], "mcp_sense": -1},
    ),
    "G_palmar": (
        "CMC axis distal end leaning palmar (c about +x), m palmar",
        {**V1, "cmc_tilt_line": [1, 0, 0]},
    ),
    "H_v1_mneg": ("v1 with m toward the metacarpal's dorsal side", {**V1, "mcp_sense": -1}),
    "I_A_cmc45": (
        "A, printed ranges CMC 0-45, MCP 0-90, IP 0-90",
        {**V1, "cmc_tilt_line": [-1, 0, 0], "limits": [[0, 45], [0, 90], [0, 90]]},
    ),
    "I_A_cmc30": (
        "A, printed ranges CMC 0-30, MCP 0-90, IP 0-90",
        {**V1, "cmc_tilt_line": [-1, 0, 0], "limits": [[0, 30], [0, 90], [0, 90]]},
    ),
    "J_v1_cmc45": (
        "v1, printed ranges CMC 0-45, MCP 0-90, IP 0-90",
        {**V1, "limits": [[0, 45], [0, 90], [0, 90]]},
    ),
    "K_A_g30_cmc45": (
        "I_A_cmc45 with the open metacarpal raised 30 deg palmar (thenar rest)",
        {
            **V1,
            "rest_direction": raised(30),
            "cmc_tilt_line": [-v for v in raised(30)],
            "limits": [[0, 45], [0, 90], [0, 90]],
        },
    ),
    "K_A_g45_wide": (
        "A with the open metacarpal raised 45 deg palmar, CMC 0-45, MCP/IP 0-90",
        {
            **V1,
            "rest_direction": raised(45),
            "cmc_tilt_line": [-v for v in raised(45)],
            "limits": [[0, 45], [0, 90], [0, 90]],
        },
    ),
    "D_wide": (
        "D (CMC axis leaning radially) with MCP/IP 0-90",
        {**V1, "cmc_tilt_line": [0, 0, -1], "limits": WIDE},
    ),
    "P_D_cmc90_wide": (
        "D (CMC axis leaning radially) with printed ranges CMC 0-90, MCP 0-90, IP 0-90: "
        "at full CMC the metacarpal stands along the palm normal, the line c turns about, "
        "so the MCP axis there sits at c + m",
        {**V1, "cmc_tilt_line": [0, 0, -1], "limits": [[0, 90], [0, 90], [0, 90]]},
    ),
    "Q_D_cmc100_wide": (
        "P_D_cmc90_wide with CMC 0-100: the abducted thumb may lean 10 deg past the palm "
        "normal toward the palm's middle",
        {**V1, "cmc_tilt_line": [0, 0, -1], "limits": [[0, 100], [0, 90], [0, 90]]},
    ),
    "L_D_cmc45": (
        "D (CMC axis leaning radially) with CMC 0-45, MCP/IP 0-90",
        {**V1, "cmc_tilt_line": [0, 0, -1], "limits": [[0, 45], [0, 90], [0, 90]]},
    ),
    "N_normal": (
        "v1, but m turns the MCP axis (and the phalanges) about the metacarpal's palmar "
        "normal, the line c turns about: the open thumb bends toward distal by c + m",
        {**V1, "mcp_turn_line": "metacarpal_normal"},
    ),
    "N_normal_wide": (
        "N_normal with MCP/IP 0-90",
        {**V1, "mcp_turn_line": "metacarpal_normal", "limits": WIDE},
    ),
    "O_normal_g45_wide": (
        "N_normal with the open metacarpal raised 45 deg palmar (c and m about its palmar "
        "normal), CMC 0-45, MCP/IP 0-90",
        {
            **V1,
            "rest_direction": raised(45),
            "cmc_tilt_line": normal_of_raised(45),
            "mcp_turn_line": "metacarpal_normal",
            "limits": [[0, 45], [0, 90], [0, 90]],
        },
    ),
    "C_pins_b45": ("bones fixed at 45 deg from y; pins turn in the palm plane", pins(45)),
    "C_pins_b60": ("bones fixed at 60 deg from y; pins turn in the palm plane", pins(60)),
    "C_pins_b45_wide": ("C_pins_b45 with MCP/IP 0-90", pins(45, limits=WIDE)),
    "C_pins_b60_wide": ("C_pins_b60 with MCP/IP 0-90", pins(60, limits=WIDE)),
}


def _toml(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return f"{round(float(v), 6) + 0.0:g}"


def render(name: str, desc: str, k: dict) -> str:
    s = BASE.read_text()
    s = s.replace('name = "imma_right_v1"', f'name = "study_{name}"')
    s = re.sub(
        r"# VARIANT v1:.*?imma_right.toml\.\n", f"# STUDY VARIANT {name}: {desc}\n", s, flags=re.S
    )
    s = s.replace("[DESIGN, first reading, docs/design.md]", f"[STUDY {name}]")
    s = re.sub(r"^ {20,}#.*\n", "", s, flags=re.M)  # continuation comments of v1's keys
    for key, v in k.items():
        if key == "limits":
            s = re.sub(r"^limits = \[\[0.0, 70.0\].*$", f"limits = {_toml(v)}", s, flags=re.M)
        else:
            s = re.sub(rf"^{key} = .*$", f"{key} = {_toml(v)}", s, flags=re.M)
    return s


def main() -> None:
    names = list(VARIANTS) if sys.argv[1:] == ["all"] else sys.argv[1:]
    for n in names:
        desc, k = VARIANTS[n]
        out = ROOT / "hand_models" / "study" / f"{n}.toml"
        out.write_text(render(n, desc, k))
        print(out)


if __name__ == "__main__":
    main()
