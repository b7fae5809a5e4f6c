"""The environment the project's processes compute in (``signorini.pipeline.jobenv``): one BLAS and
OpenMP thread unless the caller chose otherwise."""

from __future__ import annotations

import os
import subprocess
import sys

from signorini.pipeline.jobenv import THREAD_VARIABLES, single_threaded


def test_one_thread_unless_set_and_a_copy_for_a_subprocess_leaves_this_process_alone():
    first, *others = THREAD_VARIABLES
    environ = {first: "4", "PATH": "/bin"}
    assert single_threaded(environ) is environ
    assert environ == {first: "4", "PATH": "/bin", **dict.fromkeys(others, "1")}  # a choice is kept
    before = dict(os.environ)
    child = single_threaded({k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES})
    assert all(child[name] == "1" for name in THREAD_VARIABLES) and dict(os.environ) == before
    probe = "import os, sys; sys.stdout.write(' '.join(os.environ[n] for n in sys.argv[1:]))"
    out = subprocess.run([sys.executable, "-c", probe, *THREAD_VARIABLES], env=child, capture_output=True,
                         text=True, check=True).stdout
    assert out == " ".join("1" for _ in THREAD_VARIABLES)
