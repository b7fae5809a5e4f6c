# Shared helpers: the package import, config checks, path templates, scenes, code inputs.
import os
import sys
from pathlib import Path

# Jobs import the package from src/ next to this Snakefile -- the very files the rules list
# as inputs -- whether or not (or from where) it is installed: script jobs inherit PYTHONPATH.
SRC = str(Path(workflow.basedir) / "src")
sys.path.insert(0, SRC)
os.environ.update(
    PYTHONPATH=os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
)

from signorini import pipeline
from signorini.figures import FIGURE3_NORMS
from signorini.tables import TABLE1_NORMS, TABLE2_NORMS

pipeline.check_config(config)  # integer N, known norms (parse_norm), admissible problem

# A cached artifact damaged after it was written (truncated npz, incomplete JSON) is moved
# to <name>.corrupt before Snakemake inspects any file, so that it is rebuilt, not read.
if workflow.is_main_process:
    pipeline.quarantine_corrupt(pipeline.cached_artifacts("results", config["scenes"]))


wildcard_constraints:
    scene=r"[A-Za-z0-9_-]+",
    N=r"[1-9][0-9]*",
    norm=r"[A-Za-z0-9.]+",


PATHS = pipeline.PATHS
FIG = config.get("figures_scene", "paper")
FIGDIR = "paper_figures"


def scene_of(wildcards):
    """The config block of the job's scene."""
    name = wildcards if isinstance(wildcards, str) else wildcards.scene
    try:
        return config["scenes"][name]
    except KeyError:
        raise ValueError(
            f"unknown scene {name!r}; configured: {sorted(config['scenes'])}"
        ) from None


def code(stage):
    """The package modules a stage runs (inputs, so that editing them reruns the stage)."""
    return [f"src/signorini/{m}" for m in pipeline.STAGE_MODULES[stage]]


def norm_jsons(scene, norms):
    """{norm: [artifact per N of the scene]}"""
    Ns = scene_of(scene)["N"]
    return {
        n: [PATHS["norm_json"].format(scene=scene, N=N, norm=n) for N in Ns]
        for n in norms
    }


def flat(mapping):
    return [p for paths in mapping.values() for p in paths]


PAPER_FIGURES = [
    *expand(
        f"{FIGDIR}/{{name}}.{{ext}}",
        name=["table1", "table2"],
        ext=["csv", "md", "tex"],
    ),
    *expand(
        f"{FIGDIR}/{{name}}.{{ext}}", name=["figure2", "figure3"], ext=["pdf", "png"]
    ),
    f"{FIGDIR}/reproduction.md",
    f"{FIGDIR}/runtime.csv",
    PATHS["errors_csv"].format(scene=FIG),
    PATHS["eoc_csv"].format(scene=FIG),
]
