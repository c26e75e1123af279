"""Layer 3, quality: force closure, grasp-type correctness, the judged outcome, S_GAS, the
simulation settings and the grasp quality measures (``gqm/``).

Imports the sim and model layers and the base modules only.
"""
