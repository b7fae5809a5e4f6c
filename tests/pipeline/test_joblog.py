"""A job's log (``signorini.pipeline.joblog``)."""

from __future__ import annotations


def test_ctrl_c_in_a_job_is_one_line_in_its_log_only(tmp_path, capsys):
    import pytest

    from signorini.pipeline.joblog import job_log

    with pytest.raises(KeyboardInterrupt), job_log(tmp_path / "job.log"):
        raise KeyboardInterrupt
    assert capsys.readouterr().err == ""
    assert (tmp_path / "job.log").read_text(encoding="utf-8").strip().endswith("job interrupted")
