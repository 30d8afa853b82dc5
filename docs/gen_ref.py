"""MkDocs hook: the reference pages generated from the code, so they cannot drift from it.

Named in ``mkdocs.yml`` under ``hooks:``; ``mkdocs build`` runs it, so the
build command alone makes the whole site.  It adds four pages that exist in
no file of ``docs/``:

  reference/keys.md           every scene key of ``parslip.scene.schema.SCHEMA``
  reference/cli.md            every subcommand of the parser ``parslip.cli.main``
                              builds, found by walking its subparsers (a new
                              subcommand, nested ones included, appears by itself)
  reference/output-format.md  the run file's datasets, from ``parslip.io.contract``
  reference/front-fields.md   every per-front field of the catalogue, from ``parslip.analysis.fronts.FIELDS``

and the files the site needs that git does not hold:

  model/scene.png             the model picture, drawn by ``parslip.plot.scene_picture`` from the
                              lattice of a small scene (``DOCS_SCENE``)
  examples/tour.ipynb         the tour notebook (``examples/tour.ipynb``), which mkdocs-jupyter executes
                              and renders with its outputs
  javascripts/mathjax/        MathJax 3 (npm package ``mathjax``, version ``MATHJAX_VERSION``): its
                              ``tex-mml-chtml.js``, CHTML fonts and TeX extensions, from
                              ``.cache/mathjax`` (``tests/install.sh`` installs it there; the hook runs npm
                              itself when it is missing), so pages typeset with no network

The Python API reference (``docs/reference/python-api.md``) is mkdocstrings' work, from the docstrings.
The parslip documented is the one in this checkout (the repository root is put
first on ``sys.path``).  The reference pages import the schema, the command-line parser module and
the output contract only: none of them starts MPI or compiles with numba
(``tests/test_docs.py`` checks that).  Each ``*_page()`` function returns the
Markdown of one page and can be called without MkDocs.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib
import inspect
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

GENERATED_NOTE = ("*Generated from the code by `docs/gen_ref.py` at every docs build "
                  "(source: {source}); edit the source, not this page.*\n")


# --- small Markdown helpers ------------------------------------------------------------------------

def _text(text) -> str:
    """Plain text from the code as Markdown: angle brackets and asterisks (2*WINDOW+1) taken literally."""
    return str(text).replace("<", "&lt;").replace(">", "&gt;").replace("*", "\\*")


def _cell(text) -> str:
    """One table cell: a single line, pipes escaped."""
    return _text(" ".join(str(text).split())).replace("|", "\\|")


def _code(text) -> str:
    """Inline code on one line (a pipe inside backticks does not split a table cell)."""
    s = " ".join(str(text).split())
    tick = "``" if "`" in s else "`"
    pad = " " if tick == "``" else ""
    return f"{tick}{pad}{s}{pad}{tick}"


def _toml(value) -> str:
    """A default as the TOML literal a scene file would hold (str, int, float, bool)."""
    return json.dumps(value)


# --- scene keys -----------------------------------------------------------------------------------

def keys_page() -> str:
    import tomli_w

    from parslip.scene.schema import SCHEMA

    out = ["# Scene keys", "",
           GENERATED_NOTE.format(source="`parslip/scene/schema.py`, `SCHEMA`"),
           "Every key a scene file may set, with its default, units and the accepted range; any other key "
           "is refused (exit 2).  A key a scene leaves out takes its default.  `--set KEY=VALUE` on the "
           "command line overrides one key (the value is a TOML literal; a bare word is a string).  "
           "`parslip keys` prints the same list.  Units: see [Scenes and units](../guide/scenes-and-units.md).",
           ""]
    sections: dict[str, list[str]] = {}
    for name in SCHEMA:
        sections.setdefault(name.split(".", 1)[0], []).append(name)
    for section, names in sections.items():
        out += [f"## `[{section}]`", "",
                "| key | default | type | units | accepted | meaning |",
                "| --- | --- | --- | --- | --- | --- |"]
        for name in names:
            k = SCHEMA[name]
            out.append(f"| {_code(name)} | {_code(_toml(k.default))} | {k.kind.__name__} | {_cell(k.units)} "
                       f"| {_cell(k.accepted)} | {_cell(k.help)} |")
        out.append("")

    scene: dict = {}
    for name, k in SCHEMA.items():
        section, _, key = name.partition(".")
        scene.setdefault(section, {})[key] = k.default
    out += ["## The default scene", "",
            "A scene file that sets every key to its default:", "",
            "```toml", tomli_w.dumps(scene).rstrip(), "```", ""]
    return "\n".join(out)


# --- command line ---------------------------------------------------------------------------------

def _cli_module():
    # importlib: ``parslip.cli``'s package namespace binds ``main`` to the function, not the module.
    return importlib.import_module("parslip.cli.main")


def build_parser() -> argparse.ArgumentParser:
    mod = _cli_module()
    factory = getattr(mod, "build_parser", None) or mod._parser   # noqa: SLF001 (the public alias may not exist yet)
    return factory()


def walk_commands(parser: argparse.ArgumentParser, prog: str = "parslip"):
    """(command line, parser, one-line help) for the parser and every subcommand below it, depth first.

    An alias lists the same parser under several names: it is given once, under its first name.
    """
    yield prog, parser, None
    seen = set()
    for action in parser._actions:                                  # noqa: SLF001 (argparse has no public walk)
        if not isinstance(action, argparse._SubParsersAction):     # noqa: SLF001
            continue
        helps = {a.dest: a.help for a in action._choices_actions}  # noqa: SLF001
        for name, sub in action.choices.items():
            if id(sub) in seen:
                continue
            seen.add(id(sub))
            aliases = [n for n, s in action.choices.items() if s is sub and n != name]
            own = helps.get(name) or ""
            if aliases:
                own = (own + "; " if own else "") + "alias: " + ", ".join(aliases)
            for i, (p, sp, h) in enumerate(walk_commands(sub, f"{prog} {name}")):
                yield p, sp, (own or None if i == 0 else h)


@contextlib.contextmanager
def _columns(n: int):
    """argparse wraps usage to $COLUMNS: fix it so the page does not depend on the terminal."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(n)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = old


def _help_text(action: argparse.Action, prog: str) -> str:
    h = action.help or ""
    if "%" in h:
        try:
            h = h % {**vars(action), "prog": prog}
        except (KeyError, TypeError, ValueError):
            pass
    return h


def _argument_rows(parser: argparse.ArgumentParser, prog: str) -> list[str]:
    rows = []
    for a in parser._actions:                                       # noqa: SLF001
        if isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)) or a.help == argparse.SUPPRESS:  # noqa: SLF001
            continue
        if a.option_strings:
            name = ", ".join(a.option_strings)
            if a.nargs != 0:
                metavar = a.metavar or (("{" + ",".join(map(str, a.choices)) + "}") if a.choices
                                        else a.dest.upper())
                if isinstance(metavar, tuple):
                    metavar = " ".join(metavar)
                name += f" {metavar}"
        else:
            name = a.metavar or a.dest
            if isinstance(name, tuple):
                name = " ".join(name)
        default = ""
        if a.default not in (None, argparse.SUPPRESS, False, []) and a.nargs != 0:
            default = _code(a.default)
        extra = []
        if a.choices and not a.option_strings:
            extra.append("one of " + ", ".join(map(str, a.choices)))
        if a.required and a.option_strings:
            extra.append("required")
        text = _help_text(a, prog)
        if isinstance(a, argparse._AppendAction) and "repeatable" not in text:   # noqa: SLF001
            extra.append("repeatable")
        if extra:
            text += f" ({'; '.join(extra)})"
        rows.append(f"| {_code(name)} | {default} | {_cell(text)} |")
    return rows


def cli_page() -> str:
    from parslip.errors import EXIT_BAD_INPUT, EXIT_RUN_FAILED

    parser = build_parser()
    mod = _cli_module()
    out = ["# Command line", "",
           GENERATED_NOTE.format(source="the argparse parser of `parslip/cli/main.py` and the `register(sub)` "
                                        "of every module in its `COMMAND_MODULES`"),
           f"Exit codes: 0 done (or stopped with a checkpoint), {EXIT_BAD_INPUT} bad input (one line naming what "
           f"is wrong and what is accepted), {EXIT_RUN_FAILED} a run that failed on the way, 130 interrupted by "
           "Ctrl-C; in full: [Getting started](../getting-started.md#exit-codes).", ""]
    commands = list(walk_commands(parser))
    out += ["| command | what it does |", "| --- | --- |"]
    for prog, _, h in commands[1:]:
        anchor = prog.replace(" ", "-")
        out.append(f"| [`{prog}`](#{anchor}) | {_cell(h or '')} |")
    out.append("")
    with _columns(100):
        for prog, p, h in commands:
            out += [f"## {prog} {{ #{prog.replace(' ', '-')} }}", ""]
            if h:
                out += [_cell(h) + ".", ""]
            if p.description:
                out += [_text(p.description.strip()), ""]
            out += ["```text", p.format_usage().strip(), "```", ""]
            rows = _argument_rows(p, prog)
            if rows:
                out += ["| argument | default | meaning |", "| --- | --- | --- |", *rows, ""]
            if p.epilog and (prog == "parslip" or p.epilog != parser.epilog):
                out += ["```text", p.epilog.strip(), "```", ""]
    out += ["Module: `" + mod.__name__ + "`; further subcommands come from "
            + ", ".join(f"`{m}`" for m in getattr(mod, "COMMAND_MODULES", ())) + ".", ""]
    return "\n".join(out)


# --- output format --------------------------------------------------------------------------------

def output_format_page() -> str:
    import numpy as np

    from parslip.io import contract

    g = contract.INTERFACE
    frame_fields = set(getattr(contract, "FRAME_FIELDS", ()))
    out = ["# Output format", "",
           GENERATED_NOTE.format(source="`parslip/io/contract.py`"),
           "One HDF5 file per run (`.vtkhdf`).  What the run file holds and how to open it: "
           "[Output and viewing](../guide/output-and-viewing.md).", "",
           f"## The `/{g}` group", "",
           "| dataset | dtype | per frame | units |", "| --- | --- | --- | --- |"]
    for name, (dtype, per_frame, units) in contract.INTERFACE_DATASETS.items():
        pf = "yes" if per_frame or name in frame_fields else "no"
        out.append(f"| `/{g}/{name}` | {np.dtype(dtype).name} | {pf} | {_cell(units)} |")
    out += ["", f"Per-frame datasets hold `frames_written` valid frames (an attribute of `/{g}`); "
            "the readers below cut them to it.", "",
            f"## The `/{contract.ENERGY}` group", "",
            "One float64 value per interface frame, in m c_r^2: "
            "`work_drive + work_normal + formed = elastic + kinetic + damping + broken + residual`.", "",
            "| dataset | meaning |", "| --- | --- |"]
    out += [f"| `/{contract.ENERGY}/{name}` | {_cell(meaning)} |" for name, meaning in contract.ENERGY_DATASETS.items()]
    out += ["",
            "## The contract", "", "From the module's docstring:", "",
            "```text", inspect.cleandoc(contract.__doc__ or ""), "```", "",
            "## Readers", "",
            "Every read of a run file outside the writer goes through these functions:", ""]
    funcs = [f for n, f in inspect.getmembers(contract, inspect.isfunction)
             if not n.startswith("_") and f.__module__ == contract.__name__]
    for f in sorted(funcs, key=lambda f: f.__code__.co_firstlineno):
        doc = inspect.getdoc(f) or ""
        out += [f"### `{f.__name__}{inspect.signature(f)}`", "", doc.split("\n\n")[0].strip() or "(no docstring)", ""]
    return "\n".join(out)


def front_fields_page() -> str:
    """Every per-front field of the catalogue, from its registry (``parslip.analysis.fronts.FIELDS``)."""
    from parslip.analysis.fronts import FIELDS

    out = ["# Front fields", "",
           GENERATED_NOTE.format(source="`parslip.analysis.fronts.FIELDS`, filled where each field is defined"),
           "Each rupture front of `parslip fronts --json` holds these keys, and `run.fronts()` these "
           "attributes (`front.fate`); the text table shows those with a column.  How the catalogue is "
           "made: [Analysis](../guide/analysis.md).  Null (None) where a value is missing.", "",
           "| field | units | table column | defined in | meaning |", "| --- | --- | --- | --- | --- |"]
    for f in FIELDS.values():
        out.append(f"| `{f.name}` | {_cell(f.units)} | {_cell(f.col or '')} | `{f.source}` | {_cell(f.doc)} |")
    return "\n".join(out) + "\n"


PAGES = {
    "reference/keys.md": keys_page,
    "reference/cli.md": cli_page,
    "reference/output-format.md": output_format_page,
    "reference/front-fields.md": front_fields_page,
}


# --- MathJax, vendored ---------------------------------------------------------------------------

MATHJAX_VERSION = "3.2.2"
MATHJAX_PREFIX = ROOT / ".cache" / "mathjax"                 # npm install --prefix; git ignores .cache/
MATHJAX_ES5 = MATHJAX_PREFIX / "node_modules" / "mathjax" / "es5"
MATHJAX_DEST = "javascripts/mathjax"                         # in the site, beside mathjax-config.js


def ensure_mathjax() -> pathlib.Path:
    """The es5 directory of the npm package mathjax@MATHJAX_VERSION in .cache/mathjax, installed with npm
    when missing (as ``tests/install.sh`` does); a clear error when that cannot be done."""
    def version():
        try:
            return json.loads((MATHJAX_ES5.parent / "package.json").read_text())["version"]
        except (OSError, ValueError, KeyError):
            return None
    if version() != MATHJAX_VERSION:
        npm = shutil.which("npm")
        if npm is None:
            raise RuntimeError(f"MathJax {MATHJAX_VERSION} is not in {MATHJAX_PREFIX} and npm is missing: install "
                               "Node.js and npm, then run `bash tests/install.sh` (or `npm install --prefix "
                               f".cache/mathjax --no-save mathjax@{MATHJAX_VERSION}`)")
        MATHJAX_PREFIX.mkdir(parents=True, exist_ok=True)
        r = subprocess.run([npm, "install", "--prefix", str(MATHJAX_PREFIX), "--no-save", "--no-audit", "--no-fund",
                            "--loglevel=error", f"mathjax@{MATHJAX_VERSION}"], capture_output=True, text=True,
                           timeout=600)
        if r.returncode != 0 or version() != MATHJAX_VERSION:
            raise RuntimeError(f"npm install mathjax@{MATHJAX_VERSION} into {MATHJAX_PREFIX} failed: "
                               + (r.stderr or r.stdout).strip()[-500:])
    return MATHJAX_ES5


def mathjax_files() -> list[tuple[pathlib.Path, str]]:
    """(source, path in the site) of what the pages load: the combined component, the CHTML fonts and the
    TeX extensions MathJax's autoload may fetch (\\boldsymbol, \\cancel, ...)."""
    es5 = ensure_mathjax()
    out = [(es5 / "tex-mml-chtml.js", f"{MATHJAX_DEST}/tex-mml-chtml.js")]
    for sub in ("output/chtml/fonts/woff-v2", "input/tex/extensions"):
        for f in sorted((es5 / sub).rglob("*")):
            if f.is_file():
                out.append((f, f"{MATHJAX_DEST}/{f.relative_to(es5).as_posix()}"))
    return out


# --- the model picture and the notebook -------------------------------------------------------------

MODEL_PICTURE = "model/scene.png"
NOTEBOOKS = {"examples/tour.ipynb": ROOT / "examples" / "tour.ipynb"}


def model_picture() -> bytes:
    from parslip.plot.scene_picture import DOCS_SCENE, scene_png
    return scene_png(DOCS_SCENE)


# --- the MkDocs hook --------------------------------------------------------------------------------

try:
    from mkdocs.plugins import event_priority
except ImportError:                         # the page functions above work without MkDocs
    def event_priority(priority):
        return lambda f: f


@event_priority(100)                        # before mkdocs-jupyter's on_files, which must see the notebook
def on_files(files, config):
    from mkdocs.exceptions import PluginError
    from mkdocs.structure.files import File

    for uri, make in PAGES.items():
        if files.get_file_from_path(uri) is not None:
            raise PluginError(f"docs/{uri} is generated by docs/gen_ref.py: remove the file from docs/")
        files.append(File.generated(config, uri, content=make()))
    files.append(File.generated(config, MODEL_PICTURE, content=model_picture()))
    for uri, src in NOTEBOOKS.items():        # a File with a source directory, which mkdocs-jupyter can wrap
        files.append(File(uri, src_dir=str(src.parents[uri.count("/")]), dest_dir=config["site_dir"],
                          use_directory_urls=config["use_directory_urls"]))
    try:
        vendored = mathjax_files()
    except RuntimeError as e:
        raise PluginError(str(e)) from None
    for src, uri in vendored:
        files.append(File.generated(config, uri, abs_src_path=str(src)))
    return files


_NBCONVERT_MATHJAX = re.compile(r"<!-- Load mathjax -->.*?<!-- End of mathjax configuration -->", re.S)


def on_page_content(html, page, config, files):
    """A notebook page brings nbconvert's MathJax 2 from a CDN: drop it, the site's vendored MathJax 3 typesets."""
    if page.file.src_uri.endswith(".ipynb"):
        html = _NBCONVERT_MATHJAX.sub("", html)
    return html
