"""The chain every scene runs: ``discretise`` (mesh and assembly) → ``solve`` (S_h) → ``norm``
(one norm of the error per job) → ``errors`` (``errors.csv``, ``eoc.csv``); ``store`` reads
their artifacts back."""
