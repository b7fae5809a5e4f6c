"""``make check`` (``signorini.pipeline.check``): a run's outputs against the committed ones."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from signorini.pipeline.check import all_outputs, compare_file, main, numbers_and_text

MD = "**Table 1.** caption\n\n| h | L⁴(Ω) |\n| --- | ---: |\n| 1/101 | 5.8746·10⁻⁴ |\n| 1/201 | 1.4866·10⁻⁴ |\n"
TEX = "$1/101$ & $5.8746 \\cdot 10^{-4}$ \\\\\n$1/201$ & $1.4866 \\cdot 10^{-4}$ \\\\\n"


def test_numbers_of_the_markdown_and_latex_notations():
    assert numbers_and_text(MD)[0] == [1, 101, 5.8746e-4, 1, 201, 1.4866e-4]
    assert numbers_and_text(TEX)[0] == [1, 101, 5.8746e-4, 1, 201, 1.4866e-4]
    assert numbers_and_text("+0.12 % and -3.5e-05")[0] == [0.12, -3.5e-5]


def test_compare_file_statuses():
    csv = b"h,L4\n1/101,0.0005874566522550719\n"
    assert compare_file("t.csv", csv, csv).status == "identical"
    moved = compare_file("t.csv", b"h,L4\n1/101,0.0005874566523900000\n", csv)
    assert moved.status == "differs" and moved.differing == 1 and moved.numbers == 1
    assert moved.max_rel == pytest.approx(2.3e-10, rel=0.01) and "2.3e-10" in moved.detail
    assert compare_file("t.csv", b"h,L4\n1/101,0.0005874566523900000\n", csv, rtol=1e-9).status == "matched"
    assert compare_file("t.csv", b"h,L2\n1/101,0.0005874566522550719\n", csv).status == "differs"  # header
    md = MD.replace("1.4866", "1.4867").encode()
    assert compare_file("t.md", md, MD.encode()).max_rel == pytest.approx(1 / 14867, rel=1e-3)
    assert compare_file("t.md", MD.replace("caption", "other").encode(), MD.encode()).detail.startswith("the text")
    assert compare_file("f.png", b"\x89PNG1", b"\x89PNG2").status == "differs"
    assert compare_file("f.png", None, b"x").status == "missing"
    assert compare_file("f.png", b"x", None).status == "no reference"


def _git(repo, *args):
    subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)


def _render(repo, path: str, text: str, inputs: dict) -> None:
    """``path`` as a job of the workflow renders it in ``repo`` (sealed, with its inputs' digests)."""
    from signorini.pipeline.artifacts import atomic_write_text, recording

    cwd = Path.cwd()
    os.chdir(repo)
    try:
        with recording({"rule": "r", "code": "c", "params": {}, "wildcards": {}, "inputs": inputs}):
            atomic_write_text(path, text)
    finally:
        os.chdir(cwd)


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_main_against_git_head(tmp_path, capsys):
    from signorini.pipeline.artifacts import content_digest

    repo = tmp_path / "repo"
    (repo / "paper_figures").mkdir(parents=True)
    text = {path: "h,L4\n1/101,5.8746e-04\n" if path.endswith(".csv") else "x\n" for path in all_outputs()}
    for path in all_outputs():
        (repo / path).write_text(text[path], encoding="utf-8")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "outputs")
    assert main(["--root", str(repo)]) == 2  # the committed files, never rendered here
    assert "run `make all` first" in capsys.readouterr().err
    (repo / "results/paper").mkdir(parents=True)
    (repo / "results/paper/errors.csv").write_text("N,h\n", encoding="utf-8")
    assert main(["--root", str(repo)]) == 2  # a scene table (another run's) does not make them rendered
    capsys.readouterr()
    inputs = {"results/paper/errors.csv": content_digest(repo / "results/paper/errors.csv")}
    for path in all_outputs():
        _render(repo, path, text[path], inputs)
    assert main(["--root", str(repo)]) == 0
    out = capsys.readouterr().out
    n = len(all_outputs())
    assert f"reproduced: {n} of {n} files" in out and out.count("identical") == n
    (repo / "paper_figures/table1.csv").write_text("h,L4\n1/101,5.8747e-04\n", encoding="utf-8")
    _render(repo, "paper_figures/table1.csv", "h,L4\n1/101,5.8747e-04\n", inputs)
    (repo / "paper_figures/figure3.png").unlink()
    assert main(["--root", str(repo)]) == 1
    out = capsys.readouterr().out
    assert "paper_figures/table1.csv" in out and "1 of 1 numbers differ, largest relative difference 1.7e-05" in out
    assert "missing" in out and f"NOT reproduced: {n - 2} of {n}" in out
    assert main(["--root", str(repo), "--rtol", "1e-4", "paper_figures/table1.csv"]) == 0
    assert main(["--root", str(repo), "--reference", "nosuchrev"]) == 2
    assert "no revision 'nosuchrev'" in capsys.readouterr().err
    # the cache changed under the rendered files (another scene, a rebuilt table): not rendered from it
    (repo / "results/paper/errors.csv").write_text("N,h\n11,0.1\n", encoding="utf-8")
    assert main(["--root", str(repo), "paper_figures/table2.csv", "paper_figures/table1.md"]) == 2
    (repo / "results/paper/errors.csv").write_text("N,h\n", encoding="utf-8")
    (repo / "paper_figures/table1.md").write_text("x\n\n", encoding="utf-8")  # edited after rendering
    assert main(["--root", str(repo), "paper_figures/table2.csv", "paper_figures/table1.md"]) == 1
    out = capsys.readouterr().out
    assert "not rendered" in out and "bytes differ" in out and "table2.csv" in out and "run `make all`" in out
    # an input moved aside as damaged: a run of all keeps the rendered file, so the check names the
    # request that rebuilds the input, after which the file counts as rendered here again
    os.replace(repo / "results/paper/errors.csv", repo / "results/paper/errors.csv.corrupt")
    assert main(["--root", str(repo), "paper_figures/table2.csv"]) == 2
    out = capsys.readouterr().out
    assert "no longer holds intact; rebuild it: `.venv/bin/snakemake -c2 results/paper/errors.csv`" in out
    assert "make all" not in out
    (repo / "results/paper/errors.csv").write_text("N,h\n", encoding="utf-8")
    assert main(["--root", str(repo), "paper_figures/table2.csv"]) == 0


def test_main_without_git_repository_says_what_to_do(tmp_path, capsys):
    (tmp_path / "results/paper").mkdir(parents=True)
    assert main(["--root", str(tmp_path)]) == 2
    assert "--reference-dir" in capsys.readouterr().err
    ref = tmp_path / "committed"
    (tmp_path / "paper_figures").mkdir()
    ref.mkdir()
    (ref / "table1.csv").write_text("a\n", encoding="utf-8")
    _render(tmp_path, "paper_figures/table1.csv", "a\n", {})
    args = ["--root", str(tmp_path), "--reference-dir", str(ref), "paper_figures/table1.csv"]
    assert main(args) == 0
