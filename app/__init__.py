"""handbench: design explorer and simulation benchmark for anthropomorphic hands.

Layers, bottom to top (docs/architecture.md): base modules (``errors``, ``hashing``,
``config_docs``) ← ``model`` ← ``sim`` ← ``quality`` ← ``runs`` ← ``reports`` / ``explorer`` /
``cli``. The numerical core never imports the UI; only ``app.explorer`` imports viser.
"""

__version__ = "0.1.0"
