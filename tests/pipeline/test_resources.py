"""The resources of a job (``signorini.pipeline.resources``): Slurm's limits read from ``sinfo``
and held against the jobs' requests."""

from __future__ import annotations

import pytest
from helpers import smoke_config as _smoke_config

from signorini.pipeline.config import ConfigError, check_config
from signorini.pipeline.resources import NodeLimits, parse_sinfo, slurm_time_minutes


@pytest.mark.parametrize(
    ("text", "minutes"),
    [("infinite", None), ("30", 30), ("30:00", 30), ("2:00:00", 120), ("1-00:00:00", 1440), ("2-12", 3600)],
)
def test_slurm_time_limits_are_read_in_minutes(text, minutes):
    assert slurm_time_minutes(text) == minutes


def test_the_largest_node_of_the_default_partition_is_the_limit():
    text = "main*|2|24105|infinite\nmain*|8|64000|infinite\nbig|64|512000|2-00:00:00\n"
    assert parse_sinfo(text) == NodeLimits("main", 8, 64000, None)
    assert parse_sinfo(text, "big") == NodeLimits("big", 64, 512000, 2880)
    with pytest.raises(ValueError, match="no node of partition gpu"):
        parse_sinfo(text, "gpu")


def test_a_job_longer_than_the_partition_allows_is_refused():
    """A mesh's Slurm job runs its discretise, solve and 7 norms one after another: it requests
    the sum of their run times (at N = 2001: 25 + 45 + (5 + 7 * 8) min)."""
    node = NodeLimits("short", 2, 64000, 120)
    check_config(_smoke_config([11, 1001]), node=node)
    message = (
        r"N\[1\]: N = 2001 requests 131 min for its mesh job \(discretise, solve and 7 norms one after "
        r"another\), more than the time limit of 120 min of Slurm partition short"
    )
    with pytest.raises(ConfigError, match=message):
        check_config(_smoke_config([11, 2001]), node=node)
    with pytest.raises(ConfigError, match=r"N = 9001 needs about .* GB for its solve job .* more than the 62.5 GB "
                       r"of the largest node of Slurm partition short"):
        check_config(_smoke_config([9001]), node=node)


def test_a_solve_job_requests_the_memory_of_the_route_it_takes():
    """``auto`` solves N = 301 by the direct route and N = 501 and 2001 by the multigrid route, whose
    request is the multigrid model's (measured 1.8 GiB against 7.3 GiB at N = 2001)."""
    from signorini.pipeline.resources import largest_job, mem_mb, solve_rule

    assert [solve_rule(s, 301) for s in ("active_set", "auto", "multigrid")] == ["solve", "solve", "solve_multigrid"]
    assert solve_rule("auto", 501) == "solve_multigrid"
    assert solve_rule("auto", 2001) == "solve_multigrid" and solve_rule("cvxpy_osqp", 2001) == "solve"
    assert 1.8 * 1024 < mem_mb("solve_multigrid", 2001) < mem_mb("solve", 2001)
    assert 6.9 * 1024 < mem_mb("solve_multigrid", 4001)
    assert largest_job(4001, "active_set")[0] == "solve" and largest_job(4001, "auto")[0] != "solve"


@pytest.mark.parametrize(("solver", "fits"), [("active_set", False), ("auto", True), ("multigrid", True)])
def test_a_mesh_fits_or_not_by_the_route_of_its_scene(solver, fits):
    """N = 4001 on 24 GB: the direct route's factor does not fit, the multigrid route's jobs do."""
    config = _smoke_config([11, 4001])
    config["scenes"]["smoke"]["solver"] = solver
    if fits:
        check_config(config, 24 * 1024)
    else:
        with pytest.raises(ConfigError, match=r"N = 4001 needs about 31\.8 GB for its solve job"):
            check_config(config, 24 * 1024)
