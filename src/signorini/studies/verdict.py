"""A finding of a generated page: its sentence, how strong it is and the files its numbers come from.

Every verdict a page prints is chosen by a computed condition on the data (the functions that
build verdicts live with their study); ``STRENGTHS`` are the four kinds of support a verdict can
have: true *by construction* (how the comparison was set up), *measured* (read off the data by
the stated condition), *explained* (measured, and a measured cause accounts for it), *open*
(measured, no cause established).
"""

from __future__ import annotations

from dataclasses import dataclass

STRENGTHS = ("by construction", "measured", "explained", "open")


@dataclass(frozen=True)
class Verdict:
    """A statement about the data, its strength (``STRENGTHS``), the files its numbers come from,
    and whether the property it is about holds (a verdict may say that a property fails)."""

    text: str
    strength: str
    sources: tuple[str, ...] = ()
    holds: bool = True

    def __post_init__(self) -> None:
        if self.strength not in STRENGTHS:
            raise ValueError(f"strength {self.strength!r} is not one of {STRENGTHS}")

    def line(self) -> str:
        """The sentence with its strength appended: ``text (*strength*)``."""
        return f"{self.text} (*{self.strength}*)"
