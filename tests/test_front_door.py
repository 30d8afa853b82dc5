"""The project's front door: ``LICENSE`` is the licence pyproject names, ``CITATION.cff`` cites the software
at its version and the paper it implements (title and authors as the paper's source gives them), and
``parslip --version`` gives the version and the commit of a checkout, "(modified)" for uncommitted changes to
tracked files, and from a package outside any git checkout a line that says so instead of a commit.

The commit is compared with what git itself says about a drawn repository (a copy of the package committed
in a temporary directory), and the package outside git runs with ``python -S`` (no site-packages: no
numpy, h5py or MPI), as an installed package missing its dependencies would.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from parslip.version import __version__

ROOT = Path(__file__).resolve().parents[1]


def test_license_is_the_mit_text_pyproject_names():
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert 'license = { text = "MIT" }' in pyproject
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License\n\nCopyright (c) 2026 the parslip developers\n")
    assert "THE SOFTWARE IS PROVIDED \"AS IS\", WITHOUT WARRANTY OF ANY KIND" in text


def test_citation_cites_this_version_and_the_paper():
    yaml = pytest.importorskip("yaml")
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software" and cff["license"] == "MIT"
    assert str(cff["version"]) == __version__
    for key in ("message", "title", "authors"):
        assert cff[key], key
    (paper,) = cff["references"]
    assert paper["type"] == "article"
    assert paper["title"] == "On the onset of slip at adhesive elastic interfaces"
    # As the paper's source (onset-of-slip.tex) gives them in its title and author lines.
    assert [(a["given-names"], a["family-names"]) for a in paper["authors"]] == [("Vineet", "Dawara"),
                                                                                  ("Koushik", "Viswanathan")]


def _version(pkg_parent: Path, cwd: Path, isolated: bool = False) -> subprocess.CompletedProcess:
    cmd = [sys.executable] + (["-S"] if isolated else []) + ["-m", "parslip", "--version"]
    env = {"PYTHONPATH": str(pkg_parent), "PATH": "/usr/bin:/bin", "HOME": str(cwd)}
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=120, env=env)


def _git(repo: Path, *args) -> str:
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *args], cwd=repo, check=True,
                          capture_output=True, text=True).stdout.strip()


def _copy_package(dest: Path) -> Path:
    shutil.copytree(ROOT / "parslip", dest / "parslip", ignore=shutil.ignore_patterns("__pycache__"))
    return dest


def test_version_names_the_commit_and_says_when_the_checkout_is_modified(tmp_path):
    repo = _copy_package(tmp_path / "repo")
    _git(repo, "init", "-q")
    _git(repo, "add", "parslip")
    _git(repo, "commit", "-q", "-m", "drawn")
    head = _git(repo, "rev-parse", "HEAD")
    r = _version(repo, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == f"parslip {__version__}, commit {head}", r.stdout
    (repo / "parslip" / "errors.py").write_text((repo / "parslip" / "errors.py").read_text() + "\n# edited\n")
    r = _version(repo, cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.strip() == f"parslip {__version__}, commit {head} (modified)", r.stdout
    (repo / "untracked.txt").write_text("not part of the checkout's tracked files")
    _git(repo, "checkout", "parslip/errors.py")
    r = _version(repo, cwd=tmp_path)
    assert r.stdout.strip() == f"parslip {__version__}, commit {head}", r.stdout


def test_version_outside_a_checkout_says_so_and_needs_no_dependency(tmp_path):
    site = _copy_package(tmp_path / "site")
    r = _version(site, cwd=tmp_path, isolated=True)
    assert r.returncode == 0, r.stderr
    line = r.stdout.strip()
    assert line.startswith(f"parslip {__version__}, an installed package at ") and "not a git checkout" in line
    assert "commit " not in line.replace("no commit", ""), line
    # The same copy inside a repository of something else: still not parslip's checkout.
    _git(tmp_path, "init", "-q")
    r = _version(site, cwd=tmp_path, isolated=True)
    assert "not a git checkout" in r.stdout, r.stdout
