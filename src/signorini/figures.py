"""Figures 2 and 3 of the paper.

Rendering only: ``figure2`` plots the sampled ``u`` and ``f`` (artifact of the
workflow's ``sample`` stage), ``figure3`` the ``L⁴`` and ``W^{1,4}`` errors read
from the norm artifacts.  Outputs are written atomically, with fixed metadata so
that a rerun on the same data gives the same files.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping

from signorini.artifacts import atomic_write_bytes

FIGURE3_NORMS = ("L4", "W14")
FIGURE3_LABELS = {"L4": r"$\|u-u_h\|_{L^4(\Omega)}$", "W14": r"$\|u-u_h\|_{W^{1,4}(\Omega)}$"}
REFERENCE_SLOPES = {"L4": 2.0, "W14": 1.0}  # the expected orders, drawn as h² and h¹


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.hashsalt": "signorini", "font.size": 10})
    return plt


def _save(fig, path: str | os.PathLike) -> None:
    """Save atomically; PDF/PNG metadata without dates, so reruns are byte-stable."""
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    metadata = {"CreationDate": None, "ModDate": None} if fmt == "pdf" else {"Software": None}
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=150, metadata=metadata)
    atomic_write_bytes(path, buf.getvalue())


def figure2(fields: Mapping, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """Surface plots of ``u`` (left) and ``f`` (right) on the unit square, like the paper's Fig. 2."""
    plt = _pyplot()
    X, Y = fields["x"], fields["y"]
    fig = plt.figure(figsize=(11.0, 4.6))
    for k, (key, title) in enumerate((("u", "solution $u$"), ("f", "right-hand side $f = -\\Delta u + c\\,u$"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        Z = fields[key]
        ax.plot_surface(X, Y, Z, cmap="viridis", rstride=2, cstride=2, linewidth=0.1, edgecolor="k", antialiased=True)
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        ax.set_title(title)
        ax.view_init(elev=28, azim=-125)
        ax.set_box_aspect((1.0, 1.0, 0.6))
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.04, top=0.92, wspace=0.08)
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)


def figure3(errors, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """``L⁴`` and ``W^{1,4}`` errors against ``h`` (double-logarithmic) with reference slopes h² and h¹.

    ``errors``: a frame with columns ``h``, ``L4``, ``W14``.
    """
    plt = _pyplot()
    h = errors["h"].to_numpy(dtype=float)
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    markers = {"L4": "o", "W14": "s"}
    for norm in FIGURE3_NORMS:
        e = errors[norm].to_numpy(dtype=float)
        (line,) = ax.loglog(h, e, marker=markers[norm], label=FIGURE3_LABELS[norm])
        # reference line through the coarsest point, shifted down by a factor of two
        order = REFERENCE_SLOPES[norm]
        ref = 0.5 * e[h.argmax()] * (h / h.max()) ** order
        slope = "h^2" if order == 2 else "h"
        ax.loglog(h, ref, linestyle="--", color=line.get_color(), alpha=0.7, label=f"${slope}$ (reference)")
    ax.set_xlabel("mesh width $h$")
    ax.set_ylabel("error")
    ax.set_title(r"$L^4$- and $W^{1,4}$-errors")
    ax.grid(True, which="both", linewidth=0.3, alpha=0.6)
    ax.legend(loc="best", fontsize=9)
    fig.tight_layout()
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)
