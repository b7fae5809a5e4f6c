"""The package (``signorini``): its version is the project's, and the citation names it."""

from __future__ import annotations

from helpers import ROOT


def test_the_package_version_is_the_project_version():
    import tomllib

    import signorini

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert signorini.__version__ == project["version"]


def test_citation_names_this_version_and_the_paper():
    import yaml

    import signorini

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and str(cff["version"]) == signorini.__version__
    (paper,) = cff["references"]
    assert paper["doi"].startswith("10.1007/s00211") and paper["journal"] == "Numerische Mathematik"
    assert cff["license"] in (ROOT / "LICENSE").read_text().replace("BSD 3-Clause", "BSD-3-Clause")
