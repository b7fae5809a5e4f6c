"""No committed figure is clipped: every PNG in ``paper_figures/`` has a white margin, so no dark
pixel (ink of a label, a tick label or a line) lies within ``MARGIN_PX`` pixels of an edge.  A
figure drawn past its canvas (an axis label or tick labels of a twin axis cut off at the right,
say) has ink on the edge where it was cut."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from helpers import ROOT

MARGIN_PX = 2
DARK = 128 / 255  # every colour channel below it: ink, not background or a light fill


def committed_pngs() -> list[Path]:
    """The PNGs of ``paper_figures/`` in git's index (every PNG there without git)."""
    proc = subprocess.run(["git", "-C", str(ROOT), "ls-files", "paper_figures/*.png"], capture_output=True, text=True)
    if proc.returncode == 0 and proc.stdout.strip():
        return [ROOT / line for line in proc.stdout.split()]
    return sorted((ROOT / "paper_figures").glob("*.png"))


def inked_edges(png: Path, margin: int = MARGIN_PX) -> dict[str, int]:
    """{edge: number of dark pixels within ``margin`` pixels of it} of the edges with any."""
    from matplotlib.image import imread

    image = imread(png)
    rgb = image[..., :3] if image.ndim == 3 else image[..., None]
    dark = np.all(rgb < DARK, axis=-1)
    if image.ndim == 3 and image.shape[2] == 4:  # a transparent pixel is no ink
        dark &= image[..., 3] > 0.5
    bands = {"top": dark[:margin], "bottom": dark[-margin:], "left": dark[:, :margin], "right": dark[:, -margin:]}
    return {edge: int(band.sum()) for edge, band in bands.items() if band.any()}


def test_the_edge_check_finds_ink_cut_off_at_an_edge(tmp_path):
    from matplotlib.image import imsave

    image = np.ones((40, 60, 3))
    image[10:20, 10:20] = 0.0  # ink well inside: not clipped
    imsave(tmp_path / "inside.png", image)
    assert inked_edges(tmp_path / "inside.png") == {}
    image[5:15, 58:] = 0.2  # a label cut off at the right edge
    imsave(tmp_path / "cut.png", image)
    assert inked_edges(tmp_path / "cut.png") == {"right": 20}


@pytest.mark.parametrize("png", committed_pngs(), ids=lambda p: p.name)
def test_no_committed_figure_is_clipped(png):
    assert inked_edges(png) == {}, f"{png.name}: dark pixels at its edges, the figure is cut off there"
