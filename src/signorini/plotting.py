"""Figure style and saving, shared by every study.

Figure functions (``studies/*/figures.py``) take their data and an optional ``ax`` (or ``fig``),
draw, and return it; a notebook passes its own axes, a workflow stage creates a figure with
``new_figure`` and writes it with ``save``.  ``new_figure`` builds a ``matplotlib.figure.Figure``
without pyplot, so no backend is selected and nothing is left open.
"""

from __future__ import annotations

import io
import os
from typing import Any

from signorini.pipeline.artifacts import atomic_write_bytes

STYLE = {"font.size": 10, "svg.hashsalt": "signorini"}
DPI = 150


def new_figure(**kwargs: Any):
    """A ``matplotlib.figure.Figure`` (keyword arguments as for ``Figure``) in the package style."""
    import matplotlib
    from matplotlib.figure import Figure

    with matplotlib.rc_context(STYLE):
        return Figure(**kwargs)


def save(fig, *paths: str | os.PathLike) -> None:
    """Write ``fig`` to each path (format from the suffix) atomically; PDF/PNG metadata without
    dates, so that a rerun on the same data gives the same files."""
    for path in paths:
        fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
        metadata = {"CreationDate": None, "ModDate": None} if fmt == "pdf" else {"Software": None}
        buf = io.BytesIO()
        fig.savefig(buf, format=fmt, dpi=DPI, metadata=metadata)
        atomic_write_bytes(path, buf.getvalue())
