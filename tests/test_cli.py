"""The command line (``python -m signorini solve``, ``signorini.cli``): the certificate, the norms and
the ParaView export it writes, and the arguments it refuses as the config check does."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

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
        (["--N", "100000000"], "error: --N: N = 100000000 needs about {need} GB for its solve job"),
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
    from signorini.pipeline.resources import largest_job

    if "{need}" in message:  # the memory model's estimate, as the message writes it
        message = message.format(need=f"{largest_job(int(args[1]))[1] / 1024:.1e}")
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


def test_an_exponent_a_double_cannot_hold_is_refused_before_the_solve(capsys, no_mesh):
    code, out, err = run_cli(capsys, "--N", "8", "--norms", "L4,L99999")
    assert code == 2 and "the exponent p = 99999 of L99999 is too large" in err, (out, err)


def test_a_non_finite_norm_is_an_error(capsys, monkeypatch):
    """A norm that still comes out as inf or NaN (a true norm's bound overflowing) is printed,
    then named as an error, exit code 1."""
    import signorini.fem.norms.evaluate as evaluate

    monkeypatch.setattr(evaluate, "evaluate_named_norms", lambda *a: {"L4": 1.0, "L1000_true": float("inf")})
    code, out, err = run_cli(capsys, "--N", "8", "--norms", "L4,L1000_true")
    assert code == 1 and "L1000_true = inf is not a finite number" in err, (out, err)


def test_an_output_that_cannot_be_written_is_refused_before_the_solve(capsys, no_mesh, tmp_path, monkeypatch):
    """``--vtk`` onto a FIFO (a device node as root), into a directory that cannot be written, or
    through a link loop: one line, exit code 2, before any mesh; a FIFO stays a FIFO."""
    import os
    import stat

    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "loop").symlink_to("loop")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    if os.geteuid() == 0:  # root writes anywhere: ask os.access as a user would be answered
        access = os.access
        monkeypatch.setattr(os, "access", lambda p, mode: access(p, mode) and Path(p).resolve() != locked)
    cases = {
        "fifo": "is a named pipe (FIFO), not a regular file",
        "locked/u.vtu": "the directory locked is not writable",
        "loop": "loop cannot be used: Too many levels of symbolic links",
    }
    if os.geteuid() == 0:
        os.mknod(tmp_path / "null", 0o600 | stat.S_IFCHR, os.makedev(1, 3))  # a private /dev/null
        cases["null"] = "is a character device, not a regular file"
    monkeypatch.chdir(tmp_path)
    for path, message in cases.items():
        code, out, err = run_cli(capsys, "--N", "11", "--vtk", path)
        assert code == 2 and out == "" and err.startswith("error: --vtk: "), err
        assert message in err and err.count("\n") == 1, err
    assert stat.S_ISFIFO(os.lstat(tmp_path / "fifo").st_mode)


def test_through_a_symlink_the_target_is_written_and_the_link_kept(capsys, tmp_path):
    target = tmp_path / "u.vtu"
    target.write_text("old", encoding="utf-8")
    (tmp_path / "link.vtu").symlink_to(target)
    code, out, err = run_cli(capsys, "--N", "6", "--vtk", str(tmp_path / "link.vtu"))
    assert code == 0 and f"wrote {target} (the file the link {tmp_path / 'link.vtu'} points to)" in out, err
    assert (tmp_path / "link.vtu").is_symlink() and read_vtu(target)["u_h"].shape == (49,)


def test_an_overflowing_system_is_refused_before_the_solve(capsys, monkeypatch):
    """An amplitude whose load vector overflows: one line, exit code 2, no solve, whatever bounds the
    argument checks know (here none: ``check_amplitude`` checks nothing)."""
    import signorini.fem.solve
    import signorini.pipeline.config

    def refuse(*args, **kwargs):
        raise AssertionError("the solver ran")

    monkeypatch.setattr(signorini.pipeline.config, "check_amplitude", lambda *args, **kwargs: None)
    monkeypatch.setattr(signorini.fem.solve, "solve_discrete", refuse)
    code, out, err = run_cli(capsys, "--N", "11", "--A", "1e308")
    assert code == 2 and out == "", err
    assert err.startswith("error: --A: 1e+308 is too large: the load vector b") and err.count("\n") == 1, err


def test_ctrl_c_prints_one_line_and_writes_nothing(capsys, monkeypatch, tmp_path):
    import signorini.fem.solve

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(signorini.fem.solve, "solve_discrete", interrupted)
    code, out, err = run_cli(capsys, "--N", "6", "--vtk", str(tmp_path / "u.vtu"))
    assert code == 130 and err == f"interrupted; {tmp_path / 'u.vtu'} was not written\n", err
    assert not list(tmp_path.iterdir())
