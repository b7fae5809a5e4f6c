"""The grammar of norm names (``signorini.fem.norms.names``): what a name parses into, its one
spelling, and the names outside the grammar."""

from __future__ import annotations

import math
import re

import pytest

from signorini.fem.norms.names import (
    GRAMMAR,
    NAMED_NORMS,
    NORM_PATTERN,
    UnknownNormError,
    canonical_norm_name,
    lp_names,
    norm_name,
    parse_norm_name,
    true_name,
)


@pytest.mark.parametrize(
    ("name", "family", "p", "part", "true", "canonical"),
    [
        ("L4", "L", 4.0, "", False, "L4"),
        ("L1.0", "L", 1.0, "", False, "L1"),
        ("L01", "L", 1.0, "", False, "L1"),
        ("W12.50", "W1", 2.5, "", False, "W12.5"),
        ("Linfminus", "L", math.inf, "minus", False, "Linfminus"),
        ("L4plus_true", "L", 4.0, "plus", True, "L4plus_true"),
        ("W1inf_true", "W1", math.inf, "", True, "W1inf_true"),
        ("H1", "H1", 2.0, "", False, "H1"),
        ("H12_true", "H12", None, "", True, "H12_true"),
        ("L2boundary", "L2boundary", None, "", False, "L2boundary"),
    ],
)
def test_a_name_parses_into_its_norm_and_has_one_spelling(name, family, p, part, true, canonical):
    spec = parse_norm_name(name)
    assert (spec.family, spec.p, spec.part, spec.true) == (family, p, part, true)
    assert canonical_norm_name(name) == canonical
    again = parse_norm_name(canonical)
    assert (again.family, again.p, again.part, again.true) == (family, p, part, true)
    assert spec.base == name.removesuffix("_true")
    assert spec.is_max == (p == math.inf) and spec.on_boundary == (family in ("H12", "L2boundary"))


@pytest.mark.parametrize("name", ["L0.5", "W14plus", "l4", "L4_true_true", "H12plus", "Lp", ""])
def test_names_outside_the_grammar_are_refused(name):
    with pytest.raises(UnknownNormError):
        parse_norm_name(name)
    with pytest.raises(UnknownNormError):
        canonical_norm_name(name)


def test_true_names_and_the_names_of_an_exponent():
    assert [true_name(n) for n in ("L4", "W1inf", "H12_true")] == ["L4_true", "W1inf_true", "H12_true"]
    assert lp_names(6) == ("L6", "W16") and lp_names(2.5) == ("L2.5", "W12.5")
    assert lp_names(math.inf) == ("Linf", "W1inf") and lp_names(4.0) == ("L4", "W14")


def test_a_parsed_name_is_taken_as_it_is_and_the_grammar_names_every_named_norm():
    spec = parse_norm_name("W1inf_true")
    assert norm_name(spec) is spec and norm_name("W1inf_true") == spec
    with pytest.raises(UnknownNormError):
        norm_name("W1infplus")
    for name in NAMED_NORMS:
        assert name in GRAMMAR and re.match(NORM_PATTERN, name) and re.match(NORM_PATTERN, name + "_true")
    assert [parse_norm_name(name).p for name in NAMED_NORMS] == list(NAMED_NORMS.values())


def test_the_schema_admits_exactly_the_names_the_parser_parses():
    """The config schema's norm pattern and ``parse_norm_name`` are two statements of one grammar:
    over every combination of family, exponent, part and suffix (and the named norms) they agree,
    except that only the parser refuses an exponent below 1 (a value, which the pattern's shape
    cannot see)."""
    import itertools

    import yaml
    from helpers import ROOT

    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text(encoding="utf-8"))
    assert schema["$defs"]["norm"]["pattern"] == NORM_PATTERN  # the grammar's one regular expression
    pattern = re.compile(schema["$defs"]["norm"]["pattern"])
    exponents = ["", "0", "0.5", "1", "2.5", "4", "16", "inf", "Inf", "1e3", "4.", "99999"]
    names = {
        family + p + part + suffix
        for family, p, part, suffix in itertools.product(
            ["L", "W1", "H", "X", ""], exponents, ["", "plus", "minus", "boundary"], ["", "_true", "_TRUE"]
        )
    } | {"H1", "H12", "L2boundary", "H12_true", "L2boundary_true", "H12plus"}

    def parses(name: str) -> bool:
        try:
            parse_norm_name(name)
        except UnknownNormError:
            return False
        return True

    differ = {name for name in names if parses(name) != bool(pattern.match(name))}
    below_one = {name for name in differ if re.match(r"^(L|W1)0", name)}
    assert differ == below_one and below_one and not any(parses(name) for name in below_one)
