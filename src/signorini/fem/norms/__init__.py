"""The norms of the error e = u − u_h: their names (``names``, the grammar), the ``conventions``
that fix the paper's formulas, and three evaluators: ``conventional`` (the paper's fixed rules and
point sets), ``true`` (the same norms to a stated accuracy) and ``p1`` (norms of P1 functions,
exactly: the algebraic error).  Imports nothing (see ``signorini.__init__``).
"""
