"""Beyond the paper: the numerical stability atlas of extreme cases.  ``atlas`` (the scene's
``atlas`` block), ``cases`` (stage ``stability_case``: every solver on one case, isolated),
``table``, ``report`` (stage ``stability_atlas``) and ``figures``."""
