"""One folder per study: its stages (a rule's script calls one ``*_stage`` function), reports and
figures.

``scene``: the chain every scene runs (discretise, solve, norm, errors/EOCs); ``paper``: the
paper's Tables 1–2, Figures 2–3, the reproduction report and the run times; ``theory``,
``work_precision`` and ``stability``: the studies beyond the paper; ``report``: the Snakemake
report of them all (its pages, and what each target's outputs are rendered from).
"""
