"""The documentation site builds with warnings as errors, its generated references are complete, the README is short.

One ``mkdocs build --strict`` of the whole site (``mkdocs.yml`` at the root; the
reference pages are written by the hook ``docs/gen_ref.py`` during the build)
into a temporary directory; the reference checks then read the built pages, so
they fail when generation breaks, not only when the code changes.
"""
from __future__ import annotations

import argparse
import html
import importlib
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
README_MAX_LINES = 300
WARNING = re.compile(r"\bWARNING\b|Warning:")


@pytest.fixture(scope="module")
def site(docs_site) -> pathlib.Path:
    """The site, built once per session (``docs_site`` in conftest.py, shared with tests/test_site.py)."""
    return docs_site


def _page(site: pathlib.Path, name: str) -> str:
    path = site / "reference" / f"{name}.html"
    assert path.is_file(), f"the generated page {name} is missing from the build: {sorted(site.rglob('*.html'))}"
    return html.unescape(path.read_text())


def _commands(parser: argparse.ArgumentParser, prog: str = "parslip") -> list[str]:
    """Every subcommand below ``parser`` as its command line ("parslip run"), nested ones included.

    An alias names the same parser again: only its first name is expected on the page.
    """
    found, seen = [], set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if id(sub) not in seen:
                    seen.add(id(sub))
                    found.append(f"{prog} {name}")
                    found += _commands(sub, f"{prog} {name}")
    return found


def test_docs_build_with_warnings_as_errors(site):
    assert (site / "index.html").is_file()


def test_keys_reference_lists_every_scene_key(site):
    from parslip.scene.schema import SCHEMA

    page = _page(site, "keys")
    assert SCHEMA, "SCHEMA is empty"
    missing = [k for k in SCHEMA if f"<code>{k}</code>" not in page]
    assert not missing, f"scene keys missing from reference/keys: {missing}"


def test_cli_reference_lists_every_subcommand(site):
    cli = importlib.import_module("parslip.cli.main")
    parser = getattr(cli, "build_parser", None) or cli._parser
    commands = _commands(parser())
    assert {"parslip run", "parslip info", "parslip keys"} <= set(commands), commands
    page = _page(site, "cli")
    missing = [c for c in commands if f'id="{c.replace(" ", "-")}"' not in page]
    assert not missing, f"subcommands missing from reference/cli: {missing}"


def test_output_reference_lists_every_interface_dataset(site):
    from parslip.io.contract import INTERFACE, INTERFACE_DATASETS

    page = _page(site, "output-format")
    assert INTERFACE_DATASETS, "INTERFACE_DATASETS is empty"
    missing = [n for n in INTERFACE_DATASETS if f"<code>/{INTERFACE}/{n}</code>" not in page]
    assert not missing, f"datasets missing from reference/output-format: {missing}"


def test_generating_the_references_loads_neither_mpi_nor_numba():
    code = ("import runpy, sys\n"
            f"g = runpy.run_path({str(ROOT / 'docs' / 'gen_ref.py')!r})\n"
            "for make in g['PAGES'].values():\n"
            "    assert make().startswith('# ')\n"
            "print(' '.join(sorted(m for m in ('mpi4py', 'numba') if m in sys.modules)))\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.strip() == "", f"generating the reference pages imported {r.stdout.strip()}"


def test_readme_is_at_most_300_lines():
    n = len((ROOT / "README.md").read_text().splitlines())
    assert n <= README_MAX_LINES, f"README.md has {n} lines; at most {README_MAX_LINES}: move the rest into docs/"
