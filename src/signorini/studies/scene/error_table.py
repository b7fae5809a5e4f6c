"""Stage ``errors``: the scene's ``errors.csv`` (one row per ``N``; columns ``N``, ``h``, then one
per norm in scene order)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

from signorini.pipeline.artifacts import atomic_write_csv
from signorini.studies.scene.store import read_errors


def errors_stage(
    scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str | os.PathLike]], out_csv: str | os.PathLike
) -> None:
    """``errors.csv`` from the per-norm artifacts (``norm_jsons[name][k]`` belongs to ``scene_N[k]``)."""
    atomic_write_csv(read_errors(scene_N, norm_jsons), out_csv)
