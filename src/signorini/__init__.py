"""Finite element replication of Christof & Haubner's scalar Signorini experiments (Section 7).

Subpackages: ``fem`` (the mathematics), ``solvers`` (the discrete variational inequality),
``pipeline`` (workflow infrastructure: paths, config checks, artifacts, job logs, code
dependencies) and ``studies`` (one folder per study: its stages, reports and figures).
This ``__init__`` imports nothing, so that a job runs only the modules it uses.
"""

__version__ = "0.2.0"
