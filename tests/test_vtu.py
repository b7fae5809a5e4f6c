"""ParaView files of a discrete solution (``signorini.vtu``): the triangulation with nodal fields,
the doubles themselves read back, and the fields of a solution."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import read_vtu

from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.vtu import solution_fields, vtu_mesh, write_vtu


def test_a_field_is_written_bit_for_bit_on_the_triangles(tmp_path):
    mesh = friedrichs_keller(3, jitter=0.2)
    field = np.sin(7.0 * mesh.p[0]) + 1e-300 * mesh.p[1]
    write_vtu(tmp_path / "f.vtu", mesh, {"f": field})
    data = read_vtu(tmp_path / "f.vtu")
    np.testing.assert_array_equal(data["f"], field)
    np.testing.assert_array_equal(data["Points"], np.vstack([mesh.p, np.zeros(16)]).T)
    np.testing.assert_array_equal(data["triangles"], mesh.t.T)
    assert [p.name for p in tmp_path.iterdir()] == ["f.vtu"]  # no scratch file left beside it
    with pytest.raises(ValueError, match="'g' has shape"):
        vtu_mesh(mesh, {"g": field[:-1]})


def test_solution_fields_put_the_multiplier_on_the_boundary_and_mark_the_contact_set():
    mesh, problem = friedrichs_keller(4), Problem()
    B = boundary_nodes(mesh)
    u_h = np.linspace(0.0, 1.0, mesh.p.shape[1])
    lam = np.arange(1.0, B.size + 1.0)
    fields = solution_fields(problem, mesh, u_h, lam, B[:3])
    np.testing.assert_array_equal(fields["error"], problem.u(mesh.p) - u_h)
    np.testing.assert_array_equal(fields["lambda"][B], lam)
    assert np.all(np.delete(fields["lambda"], B) == 0.0)
    np.testing.assert_array_equal(np.flatnonzero(fields["contact"]), B[:3])


def test_a_fifo_or_a_device_is_refused_and_left_as_it_is(tmp_path):
    """The write renames a temporary file over the target: onto a device (``/dev/null`` as root) or
    a FIFO that would put a regular file in its place.  Refused, the node untouched."""
    import os
    import stat

    from signorini.vtu import OutputPathError

    mesh = friedrichs_keller(2)
    nodes = {"fifo": stat.S_ISFIFO}
    os.mkfifo(tmp_path / "fifo")
    if os.geteuid() == 0:  # a private node like /dev/null (char 1, 3), never a system one
        os.mknod(tmp_path / "null", 0o600 | stat.S_IFCHR, os.makedev(1, 3))
        nodes["null"] = stat.S_ISCHR
    for name, kind in nodes.items():
        with pytest.raises(OutputPathError, match=f"{name} is a .*, not a regular file"):
            write_vtu(tmp_path / name, mesh, {"f": mesh.p[0]})
        assert kind(os.lstat(tmp_path / name).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(nodes)  # no temporary left


def test_a_symlink_is_followed_and_stays_a_link(tmp_path):
    """The link's target gets the new content (written atomically beside it), the link stays."""
    mesh = friedrichs_keller(2)
    (tmp_path / "data").mkdir()
    target = tmp_path / "data/u.vtu"
    target.write_text("old", encoding="utf-8")
    link = tmp_path / "u.vtu"
    link.symlink_to("data/u.vtu")
    assert write_vtu(link, mesh, {"f": mesh.p[0]}) == target.resolve()
    assert link.is_symlink() and link.readlink() == Path("data/u.vtu")
    np.testing.assert_array_equal(read_vtu(target)["f"], mesh.p[0])
    dangling = tmp_path / "new.vtu"  # a link to a file not yet there: that file is created
    dangling.symlink_to("data/new.vtu")
    write_vtu(dangling, mesh, {"f": mesh.p[1]})
    assert dangling.is_symlink() and (tmp_path / "data/new.vtu").is_file()


def test_a_directory_or_a_missing_or_unwritable_one_is_refused(tmp_path, monkeypatch):
    import os

    from signorini.vtu import OutputPathError, output_target

    with pytest.raises(OutputPathError, match="is a directory; give a file name"):
        output_target(tmp_path)
    with pytest.raises(OutputPathError, match="the directory .*no/such does not exist"):
        output_target(tmp_path / "no/such/u.vtu")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    if os.geteuid() == 0:  # root writes anywhere: ask os.access as a user would be answered
        access = os.access
        monkeypatch.setattr(os, "access", lambda p, mode: access(p, mode) and Path(p) != locked)
    with pytest.raises(OutputPathError, match="locked is not writable"):
        output_target(locked / "u.vtu")
    assert output_target(tmp_path / "u.vtu") == tmp_path / "u.vtu"
