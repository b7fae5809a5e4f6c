"""Every named norm of the error ``e = u − u_h``, of both kinds, in one call.

A name under the paper's conventions (``L4``, ``H12``) is evaluated by ``fem.norms.conventional``,
a ``<name>_true`` name to a stated accuracy by ``fem.norms.true``; ``evaluate_named_norms`` is the
one place that tells the two apart.  Each name is parsed once, here, and passed on parsed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.names import NormName, norm_name
from signorini.fem.norms.true import TrueNorm, true_norm
from signorini.fem.problem import compiled_points_for

if TYPE_CHECKING:
    from skfem import MeshTri


def evaluate_named_norms(
    problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    names: Sequence[str | NormName],
    conventions: Conventions | None = None,
    details: bool = False,
) -> dict[str, float] | dict[str, float | TrueNorm]:
    """Every named norm of ``u − u_h``, in the order asked for: the names under the conventions in
    one pass of ``fem.norms.conventional.evaluate_norms`` (each chunk's error field shared by all of
    them; each value the one the name alone gives, bit for bit), and every ``<name>_true`` by
    ``fem.norms.true.true_norm``.  The values as floats; with ``details``, a ``_true`` name maps to
    its ``TrueNorm`` (value, error estimate, levels).  Unknown names raise ``UnknownNormError``
    before any work.  On large meshes ``u`` and ``∇u`` come from the compiled point kernels
    (``fem.problem.compiled_points_for``: the same bits)."""
    specs = [norm_name(name) for name in names]
    plain = [spec for spec in specs if not spec.true]
    with compiled_points_for(mesh.t.shape[1]):
        out: dict = dict(evaluate_norms(problem, mesh, u_h, plain, conventions)) if plain else {}
        for spec in specs:
            if spec.true:
                result = true_norm(problem, mesh, u_h, spec, conventions)
                out[spec.name] = result if details else result.value
    return {spec.name: out[spec.name] for spec in specs}
