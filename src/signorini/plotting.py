"""Figure style and saving, shared by every study.

Figure functions (``studies/*/figures.py``) take their data and an optional ``ax`` (or ``fig``),
draw, and return it; a notebook passes its own axes, a workflow stage creates a figure with
``new_figure`` and writes it with ``save``.  ``new_figure`` builds a ``matplotlib.figure.Figure``
without pyplot, so no backend is selected and nothing is left open.

``STYLE`` applies through ``style()``: matplotlib reads its rc parameters when an artist is
created (a title's font size) and when the figure is drawn (the tick labels), so figure functions
are decorated with ``styled`` and ``save`` draws inside the same context.
"""

from __future__ import annotations

import functools
import io
import os
from collections.abc import Callable
from typing import Any, TypeVar

from signorini.pipeline.artifacts import atomic_write_bytes

STYLE = {"font.size": 10, "svg.hashsalt": "signorini"}
DPI = 150

F = TypeVar("F", bound=Callable[..., Any])


def style():
    """A context manager applying ``STYLE`` (read at call time, so a changed ``STYLE`` applies)."""
    import matplotlib

    return matplotlib.rc_context(STYLE)


def styled(func: F) -> F:
    """Run a figure function inside ``style()``, so that the text it creates has the package style."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with style():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def new_figure(**kwargs: Any):
    """A ``matplotlib.figure.Figure`` (keyword arguments as for ``Figure``) in the package style."""
    from matplotlib.figure import Figure

    with style():
        return Figure(**kwargs)


def save(fig, *paths: str | os.PathLike) -> None:
    """Write ``fig`` to each path (format from the suffix) atomically, drawn inside ``style()``;
    PDF/PNG metadata without dates, so that a rerun on the same data gives the same files."""
    for path in paths:
        fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
        metadata = {"CreationDate": None, "ModDate": None} if fmt == "pdf" else {"Software": None}
        buf = io.BytesIO()
        with style():
            fig.savefig(buf, format=fmt, dpi=DPI, metadata=metadata)
        atomic_write_bytes(path, buf.getvalue())
