"""The package figure style (``signorini.plotting``): ``STYLE`` reaches the drawn text."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from signorini import plotting
from signorini.studies.paper.figures import figure3


def _errors() -> pd.DataFrame:
    h = 1.0 / np.array([11.0, 21.0, 41.0])
    return pd.DataFrame({"h": h, "L4": 0.3 * h**2, "W14": 0.8 * h})


def _png(tmp_path, name: str) -> bytes:
    ax = figure3(_errors())
    out = tmp_path / f"{name}.png"
    plotting.save(ax.figure, out)
    return out.read_bytes()


def test_font_size_of_the_style_changes_the_png(tmp_path, monkeypatch):
    default = _png(tmp_path, "default")
    assert _png(tmp_path, "again") == default  # deterministic, so a difference means the style
    monkeypatch.setitem(plotting.STYLE, "font.size", 16)
    assert _png(tmp_path, "large") != default


def test_style_sizes_the_text_a_figure_function_creates(monkeypatch):
    monkeypatch.setitem(plotting.STYLE, "font.size", 17)
    ax = figure3(_errors())
    assert ax.title.get_fontsize() == pytest.approx(17 * 1.2)  # axes.titlesize: "large"
    assert ax.xaxis.label.get_fontsize() == pytest.approx(17)


def test_tick_labels_are_drawn_in_the_style(tmp_path, monkeypatch):
    """Tick labels are created when the figure is drawn: ``save`` draws inside the style."""
    monkeypatch.setitem(plotting.STYLE, "font.size", 15)
    ax = figure3(_errors())
    plotting.save(ax.figure, tmp_path / "f.png")
    sizes = {t.get_fontsize() for t in ax.xaxis.get_majorticklabels()}
    assert sizes == {15.0}
