"""The mathematics: the manufactured problem, Friedrichs–Keller meshes, quadrature, P1
assembly, the discrete problem (S_h) and its solution, norms of the error and rates.

No file I/O, no pandas, no plotting.  This ``__init__`` imports nothing, so that importing
one module runs only that module and its own imports (the workflow derives each rule's
code inputs from those imports).
"""
