"""The tests' Snakemake calls (``snakemake_server``) behave as the command: exit code, output,
the Snakefile's ``SystemExit`` message, the working directory and environment, a timeout."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest
from helpers import SNAKEMAKE
from snakemake_server import Server


@pytest.fixture(scope="module")
def server():
    return Server()


def test_a_call_runs_in_its_directory_with_its_environment(server, tmp_path):
    (tmp_path / "Snakefile").write_text(
        'import os, sys\nprint("cwd", os.getcwd(), os.environ["MARK"], sys.argv[1:])\n'
        'rule a:\n    output: "a.txt"\n    shell: "echo $MARK > {output}"\n',
        encoding="utf-8",
    )
    env = {**os.environ, "MARK": "seen"}
    proc = server.run(SNAKEMAKE, ["-c1", "a.txt"], tmp_path, env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert f"cwd {tmp_path} seen ['-c1', 'a.txt']" in proc.stdout + proc.stderr
    assert (tmp_path / "a.txt").read_text(encoding="utf-8") == "seen\n"


def test_a_snakefiles_exit_message_and_code_reach_the_caller(server, tmp_path):
    (tmp_path / "Snakefile").write_text('raise SystemExit("config error: x: unknown")\n', encoding="utf-8")
    proc = server.run(SNAKEMAKE, ["-n"], tmp_path, dict(os.environ), timeout=120)
    assert proc.returncode == 1 and "config error: x: unknown" in proc.stderr


def test_a_call_past_its_timeout_is_killed_and_the_server_goes_on(server, tmp_path):
    (tmp_path / "Snakefile").write_text("import time\ntime.sleep(60)\n", encoding="utf-8")
    start = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        server.run(SNAKEMAKE, ["-n"], tmp_path, dict(os.environ), timeout=2)
    assert time.monotonic() - start < 30
    (tmp_path / "Snakefile").write_text('rule a:\n    output: "b"\n    shell: "touch {output}"\n', encoding="utf-8")
    assert server.run(SNAKEMAKE, ["-c1", "b"], tmp_path, dict(os.environ), timeout=120).returncode == 0


def test_the_preload_loads_nothing_of_the_repository():
    """What the server loads before forking is Snakemake's: each child imports the package from the
    copy under test (and nothing numerical beyond what ``snakemake.cli`` loads itself)."""
    code = (
        "import sys; import snakemake.cli; before = set(sys.modules); from snakemake_server import preload; "
        "preload(); print(sorted(m for m in set(sys.modules) - before if m.split('.')[0] in ('signorini', 'numpy', "
        "'scipy', 'pandas')))"
    )
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    proc = subprocess.run([sys.executable, "-c", code], cwd=here, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
