"""The environment the project's processes compute in (``signorini.pipeline.jobenv``): one BLAS and
OpenMP thread, and freed memory kept for reuse, unless the caller chose otherwise."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

from signorini.pipeline.jobenv import ALLOCATOR_VARIABLES, THREAD_VARIABLES, job_environment, single_threaded


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


def test_the_job_environment_sets_threads_and_allocator_and_keeps_a_choice():
    name = next(iter(ALLOCATOR_VARIABLES))
    environ = job_environment({name: "65536"})
    assert environ[name] == "65536"  # the caller's choice is kept
    assert all(environ[n] == "1" for n in THREAD_VARIABLES)
    assert {n: environ[n] for n in ALLOCATOR_VARIABLES if n != name} == {
        n: v for n, v in ALLOCATOR_VARIABLES.items() if n != name
    }


# A child allocates and fills a 64 MiB array, frees it, and does the same again; it prints the
# page faults of the second round (the pages the kernel had to map and zero afresh).
SECOND_ROUND_FAULTS = """
import resource
def fill():
    a = bytearray(64 << 20)
    for k in range(0, len(a), 4096):
        a[k] = 1
fill()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
fill()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="the allocator settings are glibc's")
def test_a_job_reuses_freed_memory_instead_of_faulting_it_in_again():
    """Under the job environment a process's second large temporary takes the pages the first
    one freed; under glibc's defaults it is mapped afresh (16 384 pages of 4 KiB)."""
    plain = {k: v for k, v in os.environ.items() if k not in ALLOCATOR_VARIABLES}

    def faults(env: dict) -> int:
        out = subprocess.run([sys.executable, "-c", SECOND_ROUND_FAULTS], env=env, capture_output=True,
                             text=True, check=True).stdout
        return int(out)

    pages = (64 << 20) // 4096
    assert faults(plain) > pages // 2  # the defaults map the second array afresh
    assert faults(job_environment(dict(plain))) < pages // 100
