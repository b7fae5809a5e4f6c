"""Workflow infrastructure: artifact paths (``paths``), config checks (``config``), atomic
artifacts (``artifacts``), cache checks (``cache``), job logs (``joblog``) and the code
dependencies of every rule (``codedeps``).  Imports nothing (see ``signorini.__init__``).
"""
