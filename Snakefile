# Reproduces Tables 1-2 and Figures 2-3 of Christof & Haubner (scalar Signorini problem), Section 7.
# The chain per scene and N: discretise -> solve -> norm -> errors/eoc -> tables/figures; see README.md.
import os
import sys

from snakemake.utils import min_version

min_version("9.0")

# Jobs import the package from src/ next to this Snakefile -- the very files the rules list as
# inputs -- whether or not (or from where) it is installed: script jobs inherit PYTHONPATH.
SRC = os.path.join(workflow.basedir, "src")
sys.path.insert(0, SRC)
os.environ.update(
    PYTHONPATH=os.pathsep.join(p for p in (SRC, os.environ.get("PYTHONPATH")) if p)
)
from signorini.pipeline.jobenv import job_environment

job_environment()  # one BLAS/OpenMP thread, freed memory reused, unless the caller says otherwise (jobs inherit it)
from signorini.pipeline import paths, patches

# Snakemake's scheduler would start one more re-evaluation timer chain per finished job, a main
# loop spinning ever faster during a long run: keep one timer pending (every patch of Snakemake's
# internals is in signorini/pipeline/patches.py)
patches.coalesce_reevaluations()

# Snakemake names no file or line for a YAML syntax error in a config file: check this one first
# (python -m signorini.pipeline.config my.yaml checks files given with --configfile).
from signorini.pipeline.config import (
    DEFAULT_CONFIG,
    SCHEMA,
    load_yaml,
    one_line_errors,
    validate_config,
)

# the config and schema next to this file, whatever the working directory (-d, -s); the files of
# --configfile Snakemake has read already, keeping the last block of a key given twice: refused
# with file and line
with one_line_errors():
    load_yaml(os.path.join(workflow.basedir, DEFAULT_CONFIG))
    for _path in getattr(workflow.config_settings, "configfiles", ()):
        load_yaml(os.path.relpath(_path))


configfile: os.path.join(workflow.basedir, DEFAULT_CONFIG)


# jsonschema would import rfc3987_syntax (a notebook dependency's extra; it compiles 38 lark
# grammars, about 1 s) for a string format this schema never uses: leave it out.
sys.modules.setdefault("rfc3987_syntax", None)
# one line naming the field, the value and what is allowed; also fills in the schema's defaults
# (diagonal, solver_options, conventions, figures_scene)
with one_line_errors():
    validate_config(
        config, os.path.join(workflow.basedir, SCHEMA), memo=paths.VALIDATED_CONFIG
    )


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/scene.smk"
include: "workflow/rules/paper.smk"
include: "workflow/rules/theory.smk"
include: "workflow/rules/work_precision.smk"
include: "workflow/rules/stability.smk"
include: "workflow/rules/true_norms.smk"
include: "workflow/rules/meshes.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/integrity.smk"


rule all:
    """Tables 1-2, Figures 2-3, the reproduction report and the run times (paper_figures/)."""
    default_target: True
    input:
        PAPER_OUTPUTS,
    localrule: True


IMPORTS.save()  # the code inputs' import cache (common.smk)
