"""The web design explorer (viser). The only package of handbench that imports viser.

Modules: ``server`` (startup, per-client sessions), ``session`` (one browser tab's state and
handlers), ``scene_*`` (what is drawn in 3-D), ``panel_*`` (the control panel),
``url_state`` (``?cmc=30&mcp=75&object=chips_can&gh=17`` links) and ``screenshot``
(headless-browser pictures). Scene units: metres (lengths from the core in mm are scaled
once here, by ``MM``); frames: the world is the object frame (conventions.md).
"""
