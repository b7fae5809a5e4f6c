"""The mesh-family study: the rates of Theorem 6.1 on triangulations the paper did not use
(``fem.mesh_families``), against the paper's Friedrichs–Keller mesh (``snakemake -c2 meshes``)."""
