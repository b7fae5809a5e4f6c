"""Beyond the paper: error against run time of every solver on the paper's problem.

``study`` (the solver configurations of a scene's ``study`` block), ``measure`` (stage
``work_precision_measure``), ``table`` (stage ``work_precision_table``), ``findings`` and
``report`` (stage ``work_precision_report``), ``figures`` (stage ``work_precision_figures``)."""
