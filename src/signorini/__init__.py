"""Finite element replication of Christof & Haubner's scalar Signorini experiments (Section 7)."""

from signorini.problem import Problem, ProblemParameterError

__all__ = ["Problem", "ProblemParameterError"]
