"""The evaluation conventions of the discrete norms (``signorini.fem.norms.conventions``)."""

from __future__ import annotations

import pytest

from signorini.fem.norms.conventions import H12_FORMS, QUADRATURES, W1P_FORMS, Conventions


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(quadrature="gauss"),
        dict(w1p_form="sum"),
        dict(linf_points="nodes"),
        dict(w1inf_points="everywhere"),
        dict(h12_form="exact"),
    ],
)
def test_conventions_reject_unknown_options(kwargs):
    with pytest.raises(ValueError):
        Conventions(**kwargs)


def test_conventions_as_dict_names_every_choice():
    d = Conventions().as_dict()
    assert set(d) == {"quadrature", "w1p_form", "linf_points", "w1inf_points", "h12_form"}
    assert d["quadrature"] in QUADRATURES and d["w1p_form"] in W1P_FORMS and d["h12_form"] in H12_FORMS
