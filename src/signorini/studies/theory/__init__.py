"""Beyond the paper: the theory on finer meshes.  ``quantities`` (Ritz projection and
supercloseness, the discrete ``H^{1/2}(∂Ω)`` norm, the contact set; stage
``theory_quantities``), ``report`` (the findings, the table, Table 2 continued; stage
``theory_report``) and ``figures`` (rate against p, supercloseness and the rest)."""
