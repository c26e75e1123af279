"""Layer 1, the model: the thumb design, the parametric hand and the objects.

Imports only the base modules (``app.errors``, ``app.hashing``, ``app.config_docs``).
"""
