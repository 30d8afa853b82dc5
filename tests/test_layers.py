"""The package's layers, read from the source with ``ast`` (no import runs):

    model < parallel < io < scene < engine < analysis < plot < studies < cli

with ``errors`` and ``hooks`` below them all and ``parslip/__init__.py`` (the facade) above.  A module
imports only its own layer or lower ones (at module level or inside a function alike, and through
``importlib.import_module`` with a name the source states; and analysis, which reads run files, never the
engine; plot, which reads measures and draws them, never the engine either), never a private
name (``_x``) of another subpackage, and the imports have no cycle (those inside a function included).  There is one scene
loader: only ``scene.load`` reads a scene file and applies overrides.  No function (method and nested
function included) is longer than ``MAX_LINES`` lines, from its ``def`` to its last line.  Each check is
also run on a drawn package that breaks it, so it can fail.
"""
import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "parslip"
LAYERS = ("model", "parallel", "io", "scene", "engine", "analysis", "plot", "studies", "cli")
BASE = ("errors", "hooks", "version")         # top-level modules below every layer
FACADE = ("__init__", "__main__")             # the package itself: above every layer
# Downward imports that are still refused: analysis reads run files and never imports the engine; plot draws
# what analysis measures and never imports the engine either.  (analysis importing plot is an upward import.)
FORBIDDEN = {("analysis", "engine"), ("plot", "engine")}
# The command line calls the public API of the facade (``parslip.run``, ``parslip.open``): it is the API's
# twin on the command line, so it may import the package itself.
FACADE_USERS = ("cli",)
# A function longer than this is split into named pieces: it no longer fits on a screen with its docstring.
MAX_LINES = 80


def modules(root: Path) -> dict:
    """module name -> (path, ast)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).with_suffix("")
        name = ".".join(rel.parts)
        if name.endswith(".__init__"):
            name = name[: -len(".__init__")]
        out[name] = (path, ast.parse(path.read_text(), str(path)))
    return out


def imports(name: str, path: Path, tree) -> list:
    """(imported module, imported name or None, at module level?) of one module, relative imports resolved."""
    pkg = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    top = {id(n) for n in tree.body}
    found = []
    for node in ast.walk(tree):
        level = id(node) in top
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                found.append((mod, a.name, level))
        elif isinstance(node, ast.Import):
            for a in node.names:
                found.append((a.name, None, level))
    found += [(mod, None, False) for mod in loaded_by_name(tree)]
    return [f for f in found if f[0].split(".")[0] == PACKAGE.name]


def _strings(node):
    """The strings of a string constant, or of a tuple or list of them; None for anything else."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, (ast.Tuple, ast.List)) and all(isinstance(e, ast.Constant) and isinstance(e.value, str)
                                                       for e in node.elts):
        return [e.value for e in node.elts]
    return None


def loaded_by_name(tree) -> list[str]:
    """The modules ``importlib.import_module(NAME)`` loads where the source states NAME: a string constant, a
    module-level name bound to a tuple or list of them, or a for-loop variable over either (a plugin list).
    A name only known when the code runs (a function's argument) is not followed."""
    known = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            if _strings(node.value) is not None:
                known[node.targets[0].id] = _strings(node.value)
    for node in ast.walk(tree):
        if isinstance(node, ast.For) and isinstance(node.target, ast.Name):
            it = known.get(node.iter.id) if isinstance(node.iter, ast.Name) else _strings(node.iter)
            if it is not None:
                known[node.target.id] = it
    found = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and node.args):
            continue
        f = node.func
        if (isinstance(f, ast.Attribute) and f.attr == "import_module" and isinstance(f.value, ast.Name)
                and f.value.id == "importlib") or (isinstance(f, ast.Name) and f.id == "import_module"):
            arg = node.args[0]
            found += _strings(arg) or (known.get(arg.id, []) if isinstance(arg, ast.Name) else [])
    return found


def rank(mod: str):
    """The layer index of a module of the package (-1 for errors/hooks, len(LAYERS) for the facade)."""
    parts = mod.split(".")
    if len(parts) == 1 or parts[1] in FACADE:
        return len(LAYERS)
    if parts[1] in BASE:
        return -1
    return LAYERS.index(parts[1]) if parts[1] in LAYERS else None


def target(mod: str, name, known) -> str:
    """``from parslip.io import contract`` imports the module parslip.io.contract."""
    return f"{mod}.{name}" if name and f"{mod}.{name}" in known else mod


def violations(root: Path) -> list[str]:
    mods = modules(root)
    bad = []
    graph = {m: set() for m in mods}
    for m, (path, tree) in mods.items():
        me = rank(m)
        if me is None:
            bad.append(f"{m}: in no layer; accepted: {', '.join(LAYERS + BASE)}")
            continue
        for mod, name, level in imports(m, path, tree):
            t = target(mod, name, mods)
            if t not in mods:
                bad.append(f"{m} imports {t}: no such module of the package (a module moved?)")
                continue
            other = rank(t)
            if other is None:
                continue
            if other > me and not (other == len(LAYERS) and 0 <= me < len(LAYERS) and LAYERS[me] in FACADE_USERS):
                bad.append(f"{m} imports {t}: an upper layer")
            elif (LAYERS[me] if 0 <= me < len(LAYERS) else None, t.split(".")[1] if "." in t else None) in FORBIDDEN:
                bad.append(f"{m} imports {t}: {m.split('.')[1]} must not import {t.split('.')[1]} (an upper layer "
                           f"of the rule)")
            same_sub = t.split(".")[:2] == m.split(".")[:2]
            if name and name.startswith("_") and not name.startswith("__") and not same_sub:
                bad.append(f"{m} imports the private {t}.{name}")
            if t in graph and t != m:
                graph[m].add(t)
    # Cycles among the imports, those made inside a function included: a cycle hidden in a function still
    # ties two modules into one.
    state = {}

    def visit(m, stack):
        state[m] = 1
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                bad.append("import cycle: " + " -> ".join(stack[stack.index(n):] + [n]))
            elif n not in state:
                visit(n, stack + [n])
        state[m] = 2
    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    # One scene loader.
    for m, (path, tree) in mods.items():
        if m.startswith(f"{root.name}.scene.load") or m.startswith(f"{root.name}.io.scenefile"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and node.id in ("load_scene_file", "parse_set", "resolve"):
                bad.append(f"{m} reads a scene itself ({node.id}); accepted: scene.load.load(scene, sets)")
                break
    return bad


def long_functions(root: Path, max_lines: int = MAX_LINES) -> list[str]:
    """Every function (method, nested function) of the package longer than ``max_lines``, as
    'module:line name (n lines)'."""
    found = []
    for m, (path, tree) in modules(root).items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > max_lines:
                    found.append(f"{m}:{node.lineno} {node.name} ({n} lines; accepted: <= {max_lines})")
    return found


def test_no_function_is_longer_than_80_lines():
    assert long_functions(PACKAGE) == []


def test_a_long_function_is_found(tmp_path):
    root = tmp_path / "parslip"
    (root / "io").mkdir(parents=True)
    body = "".join(f"    x{i} = {i}\n" for i in range(MAX_LINES))
    (root / "io" / "a.py").write_text(f"class A:\n    def short(self):\n        pass\n\n\ndef f():\n{body}")
    (root / "io" / "b.py").write_text("def g():\n" + "".join(f"    y{i} = {i}\n" for i in range(MAX_LINES - 1)))
    found = long_functions(root)
    assert len(found) == 1 and found[0].startswith("parslip.io.a:6 f (81 lines"), found


def test_the_package_keeps_its_layers():
    assert violations(PACKAGE) == []


def test_every_layer_exists_and_nothing_else_does():
    subs = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert subs == set(LAYERS)
    tops = {p.stem for p in PACKAGE.glob("*.py")}
    assert tops == set(BASE) | set(FACADE)


@pytest.mark.parametrize("files,expected", [
    ({"model/a.py": "from ..engine import b\n", "engine/b.py": ""}, "an upper layer"),
    ({"analysis/a.py": "def f():\n    from parslip.engine.b import run\n", "engine/b.py": ""}, "an upper layer"),
    ({"analysis/a.py": "def f():\n    from ..plot import b\n", "plot/b.py": ""}, "an upper layer"),
    ({"plot/a.py": "from ..engine import b\n", "engine/b.py": ""}, "plot must not import engine"),
    ({"cli/a.py": "from ..io.b import _private\n", "io/b.py": ""}, "private"),
    ({"io/a.py": "from . import b\n", "io/b.py": "from . import a\n"}, "import cycle"),
    ({"io/a.py": "from . import b\n", "io/b.py": "def f():\n    from . import a\n"}, "import cycle"),
    ({"model/a.py": "import importlib\nimportlib.import_module('parslip.engine.b')\n", "engine/b.py": ""},
     "an upper layer"),
    ({"cli/a.py": "import importlib\nMODS = ('parslip.cli.b',)\n\n\ndef f():\n    for m in MODS:\n"
                  "        importlib.import_module(m)\n", "cli/b.py": "def g():\n    from .a import MODS\n"},
     "import cycle"),
    ({"extra/a.py": ""}, "in no layer"),
    ({"cli/a.py": "def f():\n    from ..io.gone import x\n", "io/b.py": ""}, "no such module"),
    ({"cli/a.py": "from ..scene.load import resolve\nresolve({})\n", "scene/load.py": ""}, "reads a scene itself"),
])
def test_each_rule_can_fail(tmp_path, files, expected):
    root = tmp_path / "parslip"
    (root).mkdir()
    (root / "__init__.py").write_text("")
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        (p.parent / "__init__.py").touch()
        p.write_text(text)
    found = violations(root)
    assert any(expected in v for v in found), found
