"""The command line: solve one discrete Signorini problem without the workflow.

    python -m signorini solve --N 201 [--x0 0.5 --R 0.45 --A 10 --c 1] [--diagonal sw_ne]
                              [--norms L4,W14] [--vtk solution.vtu] [--verbose]

prints the problem, the size, the solver's iterations and KKT certificate, the timings and the
requested norms of the error ``u - u_h``; ``--vtk`` writes the solution for ParaView;
``--verbose`` shows the active-set method's progress (one line per Newton step).
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from signorini.fem.mesh import DEFAULT_DIAGONAL, DIAGONALS
from signorini.fem.problem import Problem


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m signorini", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    solve = commands.add_parser("solve", help="mesh, assemble and solve (S_h); print certificate, timings, norms")
    solve.add_argument("--N", type=int, required=True, help="cells per side, h = 1/N")
    defaults = Problem()
    for name, text in (("x0", "free point (x0, 0)"), ("R", "support radius"), ("A", "amplitude"), ("c", "reaction")):
        solve.add_argument(
            f"--{name}", type=float, default=getattr(defaults, name), help=f"{text} (default %(default)s)"
        )
    solve.add_argument("--diagonal", choices=DIAGONALS, default=DEFAULT_DIAGONAL)
    solve.add_argument("--norms", help="comma-separated norm names of u - u_h, e.g. L4,W14,H12")
    solve.add_argument("--vtk", metavar="PATH", help="write u_h, u, the error, λ and the contact set as .vtu")
    solve.add_argument("--verbose", action="store_true", help="log the active-set method's Newton steps")
    return parser


class UsageError(ValueError):
    """An argument the command cannot use; the message names the option."""


def check_arguments(args: argparse.Namespace) -> tuple[Problem, list[str]]:
    """The problem and the norm names, checked as the workflow's config is (the same functions of
    ``signorini.pipeline.config``, the same messages, with the option as the field), and the
    memory the mesh needs, before anything is allocated.  Raises ``UsageError``."""
    from signorini.fem.problem import ProblemParameterError
    from signorini.pipeline.config import (
        ConfigError,
        check_amplitude,
        check_memory,
        check_mesh_size,
        check_norm_names,
    )
    from signorini.pipeline.resources import usable_memory

    try:
        check_mesh_size("--N", args.N)
        check_memory("--N", args.N, *usable_memory())  # the machine's, its cgroup's or ulimit's
        names = [] if args.norms is None else [n.strip() for n in args.norms.split(",")]
        if args.norms is not None:  # given, so at least one name: --norms '' is an error
            names = [] if names == [""] else names
            check_norm_names("--norms", names)
        try:
            problem = Problem(x0=args.x0, R=args.R, A=args.A, c=args.c)
        except ProblemParameterError as err:
            raise ConfigError(f"--x0/--R/--A/--c: {err}") from None
        check_amplitude("--A", problem.A, problem.R, [args.N], c=problem.c)
        if args.vtk:
            _check_output("--vtk", args.vtk)
    except ConfigError as err:
        raise UsageError(str(err)) from None
    return problem, names


def _check_output(option: str, path: str) -> None:
    """The file ``--vtk`` names can be written (``signorini.vtu.output_target``), checked before the
    solve, not after it."""
    from signorini.pipeline.config import ConfigError
    from signorini.vtu import OutputPathError, output_target

    try:
        output_target(path)
    except OutputPathError as err:
        raise ConfigError(f"{option}: {err}") from None


def check_assembled(problem: Problem, disc) -> None:
    """The assembled system is finite: an amplitude or reaction so large that ``f`` or ``c`` times
    the mass matrix overflows is refused before the solve (``UsageError``), whatever bounds the
    argument checks know."""
    import numpy as np

    if not np.all(np.isfinite(disc.A.data)):
        raise UsageError(f"--c: {problem.c!r} is too large: the stiffness plus c times the mass matrix overflows")
    if not np.all(np.isfinite(disc.b)):
        bad = int(np.count_nonzero(~np.isfinite(disc.b)))
        raise UsageError(
            f"--A: {problem.A!r} is too large: the load vector b (the integrals of f = -Δu + cu, proportional "
            f"to A) has {bad} of {disc.b.size} entries that overflow a double; take a smaller --A"
        )


def solve_command(args: argparse.Namespace) -> int:
    import math

    import numpy as np

    from signorini.fem.discrete import build
    from signorini.fem.norms.evaluate import evaluate_named_norms
    from signorini.fem.solve import solve_discrete

    try:
        problem, names = check_arguments(args)
    except UsageError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    with np.errstate(over="ignore", invalid="ignore"):  # an overflow is refused just below, in one line
        disc = build(problem, args.N, args.diagonal)
    try:
        check_assembled(problem, disc)
    except UsageError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    t1 = time.perf_counter()
    result = solve_discrete(disc)
    t2 = time.perf_counter()
    print(
        f"problem {problem.as_dict()}, N = {args.N} ({args.diagonal}): {disc.b.size} unknowns, "
        f"{disc.boundary.size} constrained"
    )
    print(
        f"active set: {result.iterations} Newton steps, {result.active.size} nodes in contact; "
        f"KKT certificate: {result.certificate.describe()}"
    )
    print(f"time: assembly {t1 - t0:.2f} s, solve {t2 - t1:.2f} s (cascade warm start included)")
    if names:
        t3 = time.perf_counter()
        values = evaluate_named_norms(problem, disc.mesh, result.u, names)
        norms = ", ".join(f"{name} {value:.6e}" for name, value in values.items())
        print(f"‖u − u_h‖: {norms} ({time.perf_counter() - t3:.2f} s)")
        bad = [f"{name} = {value}" for name, value in values.items() if not math.isfinite(value)]
        if bad:
            print(f"error: --norms: {', '.join(bad)} is not a finite number; no error is reported", file=sys.stderr)
            return 1
    if args.vtk:
        from signorini.vtu import OutputPathError, solution_fields, write_vtu

        fields = solution_fields(problem, disc.mesh, result.u, result.lam, result.active)
        try:
            written = write_vtu(args.vtk, disc.mesh, fields)
        except (OSError, OutputPathError) as err:  # changed or full since the check before the solve
            print(f"error: --vtk: {args.vtk} was not written: {getattr(err, 'strerror', None) or err}", file=sys.stderr)
            return 1
        if Path(args.vtk).is_symlink():
            print(f"wrote {written} (the file the link {args.vtk} points to)")
        else:
            print(f"wrote {args.vtk}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(format="%(asctime)s %(name)s: %(message)s", level=logging.WARNING)
    if args.verbose:
        logging.getLogger("signorini").setLevel(logging.INFO)
    try:
        return solve_command(args)
    except KeyboardInterrupt:  # Ctrl-C: one line; the .vtu is written atomically, so not at all
        print(f"interrupted{f'; {args.vtk} was not written' if args.vtk else ''}", file=sys.stderr)
        return 130
