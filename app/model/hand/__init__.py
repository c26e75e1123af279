"""The parametric hand: dimensions from ``hand_models/``, Pinocchio kinematics, link shapes."""
