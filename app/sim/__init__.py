"""Layer 2, simulation: grasp hypotheses, collision-driven closing, contacts, replay.

Imports the model layer and the base modules only.
"""
