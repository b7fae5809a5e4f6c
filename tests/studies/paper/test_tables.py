"""Tables 1–2 (``signorini.studies.paper.tables``): the certified digits, the same in every format,
and unmoved by a perturbation within the uncertainty."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from signorini.formatting import sci_md
from signorini.published import TABLE1_NORMS, TABLE2_NORMS


def _errors(scale: float = 1.0) -> tuple[pd.DataFrame, pd.DataFrame]:
    N = [101, 201, 301, 401, 501]
    h = 1.0 / np.array(N, dtype=float)
    names = sorted(set(TABLE1_NORMS) | set(TABLE2_NORMS))
    errors = pd.DataFrame({"N": N, "h": h, **{n: (k + 1) * 1e-3 * h ** (1 + k / 4) for k, n in enumerate(names)}})
    unc = errors.copy()
    for n in names:
        unc[n] = scale * 1e-9 * errors[n]
    return errors, unc


def _render(tmp_path, errors, unc) -> dict[str, str]:
    from signorini.fem.convergence import eoc, regression_slope
    from signorini.studies.paper.tables import eoc_uncertainties, table1, table2

    outs = {f"{t}.{x}": tmp_path / f"{t}.{x}" for t in ("table1", "table2") for x in ("csv", "md", "tex")}
    table1(errors, outs["table1.csv"], outs["table1.md"], outs["table1.tex"], uncertainties=unc)
    h = errors["h"].to_numpy()
    rows = {n: [*eoc(h, errors[n].to_numpy())[1:], regression_slope(h, errors[n].to_numpy())] for n in TABLE2_NORMS}
    eocs = pd.DataFrame({"N": [*map(str, errors["N"][1:]), "regression"], "h": [*h[1:], math.nan], **rows})
    table2(
        eocs,
        list(errors["N"]),
        outs["table2.csv"],
        outs["table2.md"],
        outs["table2.tex"],
        uncertainty=eoc_uncertainties(errors, unc, TABLE2_NORMS),
    )
    return {name: path.read_text(encoding="utf-8") for name, path in outs.items()}


def test_tables_print_the_certified_digits_the_same_in_every_format(tmp_path):
    errors, unc = _errors()
    out = _render(tmp_path, errors, unc)
    first = out["table1.csv"].splitlines()[1].split(",")
    assert first[0] == "1/101" and all(len(c.split("e")[0].replace(".", "")) == 5 for c in first[1:])
    value = float(first[1])
    assert sci_md(value, 4) in out["table1.md"] and "digits that round-off in u_h cannot change" in out["table1.md"]
    assert sci_md(value, 4).replace("·10", " \\cdot 10^{").split("⁻")[0] in out["table1.tex"]
    eoc_row = out["table2.csv"].splitlines()[1].split(",")
    assert all(len(c.split(".")[1]) == 4 for c in eoc_row[1:])
    # a large uncertainty: fewer digits, the same in CSV and Markdown
    out = _render(tmp_path, errors, _errors(scale=1e5)[1])  # 1e-4 relative: 4 significant digits
    cell = out["table1.csv"].splitlines()[1].split(",")[1]
    assert len(cell.split("e")[0].replace(".", "")) == 4
    assert sci_md(float(cell), 3) in out["table1.md"]


def test_tables_do_not_move_under_a_perturbation_within_the_uncertainty(tmp_path):
    """Errors moved by 1e-3 of their uncertainty (as round-off of another processor would) give the
    same bytes in every table."""
    errors, unc = _errors()
    reference = _render(tmp_path, errors, unc)
    rng = np.random.default_rng(7)
    for _ in range(5):
        moved = errors.copy()
        for n in errors.columns[2:]:
            moved[n] = errors[n] * (1 + 1e-12 * rng.uniform(-1, 1, len(errors)))
        assert _render(tmp_path, moved, unc) == reference
