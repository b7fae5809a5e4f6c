"""The norms of the error e = u − u_h: their names (``names``, the grammar), the ``conventions``
that fix the paper's formulas, what each norm combines (``families``: its parts and how they
combine), three evaluators: ``conventional`` (the paper's fixed rules and point sets), ``true``
(the same norms to a stated accuracy) and ``p1`` (norms of P1 functions, exactly: the algebraic
error), and ``evaluate``, the one entry point for a list of names of both kinds.  Imports nothing
(see ``signorini.__init__``).
"""
