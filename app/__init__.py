"""handbench: design explorer and simulation benchmark for anthropomorphic hands.

The numerical core (hand, objects, hypotheses, closing, contacts, force closure, scores,
sweep, store) never imports the UI; only ``app.explorer`` imports viser.
"""

__version__ = "0.1.0"
