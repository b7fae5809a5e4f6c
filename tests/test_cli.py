"""The command line (``python -m signorini solve``, ``signorini.cli``): the certificate, the norms and
the ParaView export it writes, and the arguments it refuses as the config check does."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from helpers import read_vtu

from signorini.fem.discrete import build
from signorini.fem.mesh import boundary_nodes
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete


def test_solve_command_prints_certificate_norms_and_writes_vtu(tmp_path):
    vtu = tmp_path / "s.vtu"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "signorini",
            "solve",
            "--N",
            "11",
            "--c",
            "2",
            "--norms",
            "L4,W14",
            "--vtk",
            str(vtu),
            "--verbose",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    problem = Problem(c=2.0)
    disc = build(problem, 11)
    result = solve_discrete(disc)
    norms = evaluate_norms(problem, disc.mesh, result.u, ["L4", "W14"])
    assert "144 unknowns, 44 constrained" in proc.stdout and "KKT certificate: stationarity=" in proc.stdout
    assert f"L4 {norms['L4']:.6e}, W14 {norms['W14']:.6e}" in proc.stdout
    assert "iteration 1:" in proc.stderr  # --verbose: the Newton steps
    data = read_vtu(vtu)
    assert data["Points"].shape == (144, 3) and data["triangles"].shape == (2 * 11 * 11, 3)
    np.testing.assert_array_equal(data["u_h"], result.u)  # binary: the doubles themselves
    np.testing.assert_array_equal(data["error"], problem.u(disc.mesh.p) - result.u)
    np.testing.assert_array_equal(data["triangles"], disc.mesh.t.T)
    np.testing.assert_array_equal(data["Points"][:, :2], disc.mesh.p.T)
    contact = np.flatnonzero(data["contact"])
    np.testing.assert_array_equal(contact, np.sort(result.active))
    assert np.all(data["lambda"][np.setdiff1d(np.arange(144), boundary_nodes(disc.mesh))] == 0)


def test_solve_command_rejects_bad_input():
    for args in (["--norms", "L4x"], ["--R", "0.6"]):
        proc = subprocess.run(
            [sys.executable, "-m", "signorini", "solve", "--N", "8", *args], capture_output=True, text=True
        )
        assert proc.returncode == 2 and proc.stderr.startswith("error:"), proc.stderr


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    """``python -m signorini solve ARGS`` in this process: exit code, stdout, stderr."""
    from signorini.cli import main

    code = main(["solve", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture
def no_mesh(monkeypatch):
    """Fails a test that meshes or allocates: a refused argument must stop the command first."""
    import signorini.fem.discrete

    def refuse(*args, **kwargs):
        raise AssertionError("the mesh was built")

    monkeypatch.setattr(signorini.fem.discrete, "build", refuse)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--N", "0"], "error: --N: 0 is not allowed; a mesh has at least 1 cell per side (N ≥ 1)"),
        (["--N", "-5"], "error: --N: -5 is not allowed; a mesh has at least 1 cell per side (N ≥ 1)"),
        (["--N", "100000000"], "error: --N: N = 100000000 needs about 2.0e+10 GB for its solve job"),
        (["--N", "11", "--norms", ""], "error: --norms: no norm given; name at least one"),
        (["--N", "11", "--norms", "L4,W1_4"], "error: --norms[1]: unknown norm 'W1_4'; a norm is L or W1 followed"),
        (["--N", "11", "--norms", "L1,L1.0"], "error: --norms[1]: 'L1.0' is the norm L1; write it L1"),
        (["--N", "11", "--norms", "L4,L4"], "error: --norms[1]: L4 is listed twice (also --norms[0])"),
        (["--N", "11", "--A", "1e-320"], "error: --A: 1e-320 is too small: at N = 11 the errors"),
        (["--N", "11", "--A", "0"], "error: --A: 0 makes u ≡ 0 and every error vanish"),
        (["--N", "11", "--x0", "2"], "error: --x0/--R/--A/--c: x0=2.0 must lie strictly inside"),
        (["--N", "11", "--vtk", "."], "error: --vtk: . is a directory; give a file name"),
        (["--N", "11", "--vtk", "no/such/dir/u.vtu"], "error: --vtk: the directory no/such/dir does not exist"),
    ],
)
def test_the_cli_refuses_what_the_config_check_refuses(capsys, no_mesh, args, message):
    """One line naming the option, exit code 2, before any mesh is built (the memory estimate of
    ``pipeline.resources`` refuses an impossible mesh before it is allocated)."""
    code, out, err = run_cli(capsys, *args)
    assert code == 2 and out == "" and err.startswith(message) and err.count("\n") == 1, err


def test_the_cli_and_the_config_check_give_the_same_message(capsys, no_mesh):
    """One implementation: the config's message with the option in place of the field."""
    from helpers import ROOT

    from signorini.pipeline.config import ConfigError, check_config, load_config

    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"]["problem"]["A"] = 1e-320
    config["scenes"]["smoke"]["N"] = [11]
    config["figures_scene"] = "paper"
    with pytest.raises(ConfigError) as info:
        check_config(config)
    _, _, err = run_cli(capsys, "--N", "11", "--A", "1e-320")
    assert str(info.value).replace("scenes.smoke.problem.A", "--A") == err.removeprefix("error: ").strip()


def test_a_non_finite_norm_is_an_error(capsys):
    code, out, err = run_cli(capsys, "--N", "8", "--norms", "L4,L99999")
    assert code == 1 and "L99999 = inf is not a finite number" in err, (out, err)
