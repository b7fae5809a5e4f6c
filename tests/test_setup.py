"""``make setup`` is atomic: an interrupted set-up leaves nothing that fails the next one."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import ROOT

# --- make setup is atomic -------------------------------------------------------------------------

# Stand-ins for the interpreter, pip and uv that `make setup` calls: they behave like the real
# ones where it matters (pip writes uv's metadata, then the binary, and does nothing once the
# metadata is there: "Requirement already satisfied") and can be made to hang, to be interrupted.
# The hang writes its marker from the process that then sleeps, after restoring SIGINT's default:
# a shell's `touch; sleep` leaves a window where Ctrl-C reaches the shell between the two and is
# lost by the forked child, which then sleeps out its full time.
FAKE_PYTHON = """#!/bin/bash
[ "$1 $2" = "-m venv" ] || exit 2
dir="$3"; mkdir -p "$dir/bin" "$dir/lib"
cat > "$dir/bin/pip" <<PIP
#!/bin/bash
[ -e "$dir/lib/uv.dist-info" ] && exit 0
mkdir -p "$dir/lib/uv.dist-info"
printf 'half a binary' > "$dir/bin/uv"
[ -n "\\$FAKE_HANG_PIP" ] && "\\$FAKE_SLEEP" "\\$FAKE_HANG_PIP"
cp "$FAKE_UV" "$dir/bin/uv" && chmod +x "$dir/bin/uv"
PIP
chmod +x "$dir/bin/pip"
"""
FAKE_SLEEP = """#!{python}
import pathlib, signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_DFL)
pathlib.Path(sys.argv[1]).touch()
time.sleep(60)
"""
FAKE_UV = """#!/bin/bash
case "$1" in
  --version) echo "uv 0.0.0 (stand-in)" ;;
  venv) for arg; do last="$arg"; done; mkdir -p "$last/bin"
        printf '#!/bin/sh\\nexit 0\\n' > "$last/bin/python"; chmod +x "$last/bin/python" ;;
  pip) if [ "$2" = sync ] && [ -n "$FAKE_HANG_SYNC" ]; then "$FAKE_SLEEP" "$FAKE_HANG_SYNC"; fi ;;
esac
"""


def _make_setup(repo: Path, hang: str | None = None, **env: str) -> subprocess.Popen:
    env = {**os.environ, "FAKE_UV": str(repo / "fake-uv"), "FAKE_SLEEP": str(repo / "fake-sleep"), **env}
    if hang:
        env[hang] = str(repo / "hanging")
    # Ctrl-C must reach make even when the suite itself was started with SIGINT ignored (a
    # background job of a shell, nohup): an ignored signal stays ignored across exec, so make
    # starts from a Python that restores the default first
    restore = "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execvp('make', sys.argv[1:])"
    return subprocess.Popen(
        [sys.executable, "-c", restore, "make", "setup", "UV=", f"PYTHON={repo / 'fake-python'}"],
        cwd=repo,
        env=env,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        encoding="utf-8",
    )


@pytest.fixture
def setup_copy(tmp_path):
    import shutil

    for name in ("Makefile", "environment.lock", "pyproject.toml"):
        shutil.copy2(ROOT / name, tmp_path / name)
    sleep = FAKE_SLEEP.format(python=sys.executable)
    fakes = (("fake-python", FAKE_PYTHON), ("fake-uv", FAKE_UV), ("fake-sleep", sleep))
    for name, text in fakes:
        (tmp_path / name).write_text(text)
        (tmp_path / name).chmod(0o755)
    return tmp_path


@pytest.mark.parametrize("hang", ["FAKE_HANG_PIP", "FAKE_HANG_SYNC"])
def test_an_interrupted_make_setup_leaves_nothing_that_fails_the_next(setup_copy, hang):
    """Ctrl-C while uv is being installed (or while the venv is synced): the next ``make setup``
    succeeds; no half-written .tools/bin/uv, no stamp that trusts a half-synced venv."""
    run = _make_setup(setup_copy, hang)
    deadline = time.monotonic() + 60
    while not (setup_copy / "hanging").exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert run.poll() is None, run.stdout.read()
    os.killpg(run.pid, signal.SIGINT)
    run.wait(timeout=30)
    assert not (setup_copy / ".venv/.installed-from-lock").exists()
    again = _make_setup(setup_copy)
    out, _ = again.communicate(timeout=60)
    assert again.returncode == 0, out
    assert subprocess.run([setup_copy / ".tools/bin/uv", "--version"], capture_output=True).returncode == 0
    assert (setup_copy / ".venv/.installed-from-lock").exists()


def test_a_broken_uv_left_by_an_older_set_up_is_replaced(setup_copy):
    """A .tools whose uv was cut off (not executable, its metadata installed) is not trusted."""
    (setup_copy / ".tools/bin").mkdir(parents=True)
    (setup_copy / ".tools/lib/uv.dist-info").mkdir(parents=True)
    (setup_copy / ".tools/bin/uv").write_text("half a binary")
    run = _make_setup(setup_copy)
    out, _ = run.communicate(timeout=60)
    assert run.returncode == 0, out
    version = subprocess.run([setup_copy / ".tools/bin/uv", "--version"], capture_output=True, encoding="utf-8")
    assert "stand-in" in version.stdout
