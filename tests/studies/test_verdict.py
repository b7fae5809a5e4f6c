"""``signorini.studies.verdict``: a verdict names one of the four strengths."""

import pytest

from signorini.studies.verdict import STRENGTHS, Verdict


def test_a_verdict_carries_its_strength():
    assert Verdict("x", "measured").line() == "x (*measured*)"
    assert Verdict("x", "open", holds=False).holds is False and len(STRENGTHS) == 4


def test_an_unknown_strength_is_refused():
    with pytest.raises(ValueError, match="strength 'likely'"):
        Verdict("x", "likely")
