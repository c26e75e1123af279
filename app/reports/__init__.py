"""Layer 5, reports: tables, plots, the design map, Table 3 and off-screen pictures.

The only layer besides the explorer that imports matplotlib.
"""
