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
    solve.add_argument("--norms", default="", help="comma-separated norm names of u - u_h, e.g. L4,W14,H12")
    solve.add_argument("--vtk", metavar="PATH", help="write u_h, u, the error, λ and the contact set as .vtu")
    solve.add_argument("--verbose", action="store_true", help="log the active-set method's Newton steps")
    return parser


def solve_command(args: argparse.Namespace) -> int:
    from signorini.fem.discrete import build
    from signorini.fem.norm_names import UnknownNormError, parse_norm_name
    from signorini.fem.solve import solve_discrete
    from signorini.fem.true_norms import evaluate_named_norms

    names = [n for n in args.norms.split(",") if n]
    try:
        for name in names:
            parse_norm_name(name)
        problem = Problem(x0=args.x0, R=args.R, A=args.A, c=args.c)
    except (UnknownNormError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    disc = build(problem, args.N, args.diagonal)
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
    if args.vtk:
        from signorini.vtu import solution_fields, write_vtu

        write_vtu(args.vtk, disc.mesh, solution_fields(problem, disc.mesh, result.u, result.lam, result.active))
        print(f"wrote {args.vtk}")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(format="%(asctime)s %(name)s: %(message)s", level=logging.WARNING)
    if args.verbose:
        logging.getLogger("signorini").setLevel(logging.INFO)
    return solve_command(args)
