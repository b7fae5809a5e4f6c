"""Snakemake calls of the tests without paying Snakemake's import in every call.

``python snakemake_server.py`` imports ``snakemake.cli`` once and then, for every request it reads
(a JSON line: working directory, arguments, environment, files for stdout and stderr), forks a
child that runs ``snakemake.cli.main`` on those arguments as the ``snakemake`` command would: in
the working directory, with exactly that environment and ``sys.argv``, in a session of its own
(so that a timeout kills its jobs too), its output written to the files.  It answers with the
child's pid, then with its exit code.

A child is a fresh process in all that a test observes (working directory, environment,
arguments, signals, output); it differs from ``snakemake ...`` in a shell only in having Snakemake's
own modules loaded before it starts: those of ``snakemake.cli``, which the command loads first
anyway, and ``PRELOADED``, the third-party modules every planning call loads on its way (the
report plugins' registry, the source cache's transports, the notebook reader).  Nothing of the
repository (``signorini``) is imported before the fork: each child imports the package from the copy
under test, as the Snakefile says.  (numpy is: ``snakemake.cli`` loads it through its scheduler's LP
solver, in the command too.)

``Server`` is the client: one server per process that asks (a pytest worker), started on first use.
"""

from __future__ import annotations

import atexit
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path


def _child(request: dict) -> None:
    """In the forked child: become the ``snakemake`` command of ``request``.  Whatever ends it
    propagates to the interpreter's top, which ends the process as it ends the command: an exit
    code, a ``SystemExit`` message on stderr, a traceback; Snakemake's exit handlers run."""
    os.setsid()
    signal.signal(signal.SIGINT, signal.default_int_handler)
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    for fd, name in ((1, "out"), (2, "err")):
        target = os.open(request[name], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(target, fd)
        os.close(target)
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    sys.argv = [request["argv0"], *request["args"]]  # what the Snakefile reads
    from snakemake.cli import main

    main(request["args"])
    sys.exit(0)


# loaded by every call that plans a DAG (``snakemake -n`` of any target), after ``snakemake.cli``:
# about half of what a dry run's process costs on top of its DAG when each child loaded them again
PRELOADED = (
    "snakemake.api",
    "snakemake.dag",
    "snakemake.report",
    "snakemake_interface_report_plugins.registry",
    "snakemake_interface_executor_plugins.registry",
    "smart_open",
    "requests",
    "nbformat",
)


def preload(modules: bool = True) -> None:
    """Import ``snakemake.cli`` and (``modules``) ``PRELOADED``, and collect the report and executor
    plugins (what the first call in every child would do); a module that is not installed is left
    to the child."""
    import importlib

    import snakemake.cli  # noqa: F401 -- the import every call would otherwise pay

    if not modules:
        return
    for name in PRELOADED:
        try:
            importlib.import_module(name)
        except ImportError:
            continue
    from snakemake_interface_executor_plugins.registry import ExecutorPluginRegistry
    from snakemake_interface_report_plugins.registry import ReportPluginRegistry

    ReportPluginRegistry()
    ExecutorPluginRegistry()


def serve(modules: bool = True) -> None:
    """The server's loop: a request per line of stdin, ``{"pid": ...}`` and ``{"rc": ...}`` on stdout;
    ``modules=False`` (``--no-preload``): only ``snakemake.cli`` loaded before the fork."""
    sys.dont_write_bytecode = True
    preload(modules)

    for line in sys.stdin:
        request = json.loads(line)
        pid = os.fork()
        if pid == 0:
            _child(request)
        print(json.dumps({"pid": pid}), flush=True)
        _, status = os.waitpid(pid, 0)
        print(json.dumps({"rc": os.waitstatus_to_exitcode(status)}), flush=True)


class Server:
    """A client of one server process (started on first use, stopped at exit)."""

    def __init__(self, preload: bool = True) -> None:
        self._proc: subprocess.Popen | None = None
        self._preload = preload
        self._lock = threading.Lock()

    def _server(self) -> subprocess.Popen:
        if self._proc is None or self._proc.poll() is not None:
            self._proc = subprocess.Popen(
                [sys.executable, __file__, *([] if self._preload else ["--no-preload"])],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
                env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
            )
            atexit.register(self._proc.kill)
        return self._proc

    def run(self, argv0: str, args: list[str], cwd: Path, env: dict[str, str], timeout: float):
        """``argv0 args...`` in ``cwd`` with ``env``: a ``subprocess.CompletedProcess`` with text output,
        or ``subprocess.TimeoutExpired`` after ``timeout`` seconds (the child's session killed)."""
        with self._lock, tempfile.TemporaryDirectory(prefix="snakemake-call-") as tmp:
            out, err = Path(tmp, "out"), Path(tmp, "err")
            request = dict(argv0=argv0, args=list(args), cwd=str(cwd), env=env, out=str(out), err=str(err))
            proc = self._server()
            proc.stdin.write(json.dumps(request) + "\n")
            proc.stdin.flush()
            pid = json.loads(proc.stdout.readline())["pid"]
            answer: list[str] = []
            reader = threading.Thread(target=lambda: answer.append(proc.stdout.readline()), daemon=True)
            reader.start()
            reader.join(timeout)
            if not answer:
                try:
                    os.killpg(pid, signal.SIGKILL)
                except ProcessLookupError:  # it ended meanwhile
                    pass
                reader.join()
                raise subprocess.TimeoutExpired([argv0, *args], timeout)
            rc = json.loads(answer[0])["rc"]
            text = [path.read_text(encoding="utf-8", errors="replace") for path in (out, err)]
            return subprocess.CompletedProcess([argv0, *args], rc, *text)


if __name__ == "__main__":
    serve(modules="--no-preload" not in sys.argv[1:])
