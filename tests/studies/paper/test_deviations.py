"""Verdicts on Table 1's deviations (``signorini.studies.paper.deviations``), each checked on data
perturbed so that the condition behind it flips."""

from __future__ import annotations

import pandas as pd
import pytest

from signorini.fem.norms.conventions import Conventions
from signorini.studies.paper import deviations as dv

ROWS = ("1/101", "1/201", "1/301", "1/401", "1/501")


def _tables(devs: dict[str, list[float]]) -> tuple[dict, dict]:
    paper = {row: {n: 1.0 for n in devs} for row in ROWS}
    ours = {row: {n: 1.0 + devs[n][k] for n in devs} for k, row in enumerate(ROWS)}
    return ours, paper


def _conventions(tmp_path, worst: dict[str, dict[str, float]]) -> str:
    """A conventions table whose worst deviation per quadrature rule is ``worst[norm][rule]``."""
    rows = []
    for rule in ("stroud4_acute1", "stroud4_right", "stroud4_acute2", "dunavant8"):
        for form in ("geometric_full", "geometric_semi"):
            row = {"N": 101, "diagonal": "sw_ne", "quadrature": rule, "points": "quadrature", "w1p_form": "components"}
            row["h12_form"] = form
            for norm in dv.OPTIONS:
                key = form if norm == "H12" else rule
                row[f"dev_{norm}"] = worst.get(norm, {}).get(key, 1e-4 if norm not in worst else 0.05)
            rows.append(row)
    path = tmp_path / "conventions.csv"
    pd.DataFrame(rows).to_csv(path, index=False)
    return str(path)


def test_digits():
    assert dv.digits_agreeing(8e-5) == 4 and dv.digits_agreeing(0.0493) == 1 and dv.digits_agreeing(2.0) == 0
    assert dv.digits_phrase(0.05) == "1 significant digit" and dv.digits_phrase(0.001) == "3 significant digits"


def test_a_fitted_rule_is_by_construction_and_a_tie_is_not(tmp_path):
    conv = Conventions(w1inf_points="quadrature", linf_points="quadrature")
    fitted = _conventions(tmp_path, {"W1inf": {"stroud4_acute1": 0.0017, "stroud4_right": 0.011}})
    by_rule = dv.rule_dependence(fitted, "W1inf", conv)
    devs = {row: 0.0017 for row in ROWS}
    assert dv.agreement_verdict(devs, by_rule, "stroud4_acute1").strength == "by construction"
    # perturbed: every rule as close as the chosen one
    rules = ("stroud4_acute1", "stroud4_right", "stroud4_acute2", "dunavant8")
    tie = _conventions(tmp_path, {"W1inf": dict.fromkeys(rules, 0.0017)})
    verdict = dv.agreement_verdict(devs, dv.rule_dependence(tie, "W1inf", conv), "stroud4_acute1")
    assert verdict.strength == "measured" and "the same for each of the 4" in verdict.text
    # perturbed: two rules alike, the others far
    two = _conventions(tmp_path, {"W1inf": dict.fromkeys(rules[:2], 0.0017)})
    verdict = dv.agreement_verdict(devs, dv.rule_dependence(two, "W1inf", conv), "stroud4_acute1")
    assert "2 of the 4 candidate rules give it alike: not fitted" in verdict.text
    # perturbed: the chosen rule is not the closest
    worse = _conventions(tmp_path, {"W1inf": {"stroud4_acute1": 0.011, "stroud4_right": 0.0017}})
    verdict = dv.agreement_verdict(devs, dv.rule_dependence(worse, "W1inf", conv), "stroud4_acute1")
    assert "not the closest" in verdict.text


def test_outlier_row_and_steady_offset():
    base = [0.0008, 0.0493, 0.0068, 0.0068, 0.0095]
    devs = dict(zip(ROWS, base, strict=True))
    assert dv.outlier_rows(devs) == ["1/201"]
    assert dv.steady_offset(devs) == pytest.approx((0.0068, 0.0095))
    calm = dict(zip(ROWS, [0.0008, 0.0070, 0.0068, 0.0068, 0.0095], strict=True))
    assert dv.outlier_rows(calm) == []
    flipped = dict(zip(ROWS, [0.0008, 0.0493, -0.0068, 0.0068, 0.0095], strict=True))
    assert dv.steady_offset(flipped) is None  # the sign changes
    spread = dict(zip(ROWS, [0.0008, 0.0493, 0.002, 0.0068, 0.0095], strict=True))
    assert dv.steady_offset(spread) is None  # spread above half the mean
    tiny = dict(zip(ROWS, [0.0, 0.0, 1e-5, 1e-5, 1e-5], strict=True))
    assert dv.steady_offset(tiny) is None  # below the printed digits


def test_load_rule_verdict_flips_at_the_printed_precision(tmp_path):
    path = tmp_path / "load_rule.csv"
    frame = pd.DataFrame({"N": [101, 201], "h": [0.01, 0.005], "norm": ["L4", "H12"], "relative_change": [1e-7, -2e-6]})
    frame.to_csv(path, index=False)
    verdict = dv.load_rule_verdict(path)
    assert "explains none" in verdict.text and "H^{1/2}(∂Ω) at h = 1/201" in verdict.text
    frame.loc[1, "relative_change"] = 0.004
    frame.to_csv(path, index=False)
    assert "explains none" not in dv.load_rule_verdict(path).text and "0.40 %" in dv.load_rule_verdict(path).text


def test_boundary_split_share_of_the_offset(tmp_path):
    path = tmp_path / "h12.csv"
    pd.DataFrame({"N": [101], "h": [0.01], "whole_edges": [1.0], "split": [1.001]}).to_csv(path, index=False)
    assert "8 % of its steady offset" in dv.boundary_split_verdict(path, (0.012, 0.013)).text
    assert "offset" not in dv.boundary_split_verdict(path, None).text


def test_table1_verdicts_in_order(tmp_path):
    ours, paper = _tables({"L4": [0.0008, 0.0493, 0.0068, 0.0068, 0.0095], "W14": [1e-4] * 5})
    conventions = _conventions(tmp_path, {})
    topics = [topic for topic, _ in dv.table1_verdicts(ours, paper, conventions)]
    assert topics == ["L4", "W14", "h = 1/201", "L4"]


def test_meshes_the_paper_did_not_use_give_one_verdict(tmp_path):
    ours = {"1/11": {"L4": 1.0}, "1/21": {"L4": 0.3}}
    paper = {row: {"L4": 1.0} for row in ROWS}
    ((topic, verdict),) = dv.table1_verdicts(ours, paper, _conventions(tmp_path, {}), tables=("a.csv",))
    assert topic == "Table 1" and "share no mesh width" in verdict.text and verdict.sources == ("a.csv",)
