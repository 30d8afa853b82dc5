"""examples/: every shipped scene is paired with a script and a figure, every script runs (``--quick``),
and the notebook's cells run as written."""
import json
import re
import subprocess
import sys


from helpers import REPO, cli_env

EXAMPLES = REPO / "examples"


def _run(args, cwd, timeout=300):
    p = subprocess.run([sys.executable, *map(str, args)], cwd=cwd, env=cli_env(), capture_output=True, text=True,
                       timeout=timeout)
    assert p.returncode == 0, p.stderr[-3000:]
    return p


def test_every_scene_has_a_script_and_a_figure():
    text = (EXAMPLES / "README.md").read_text()
    rows = [r for r in text.splitlines() if r.startswith("| `run/")]
    listed = {s for r in rows for s in re.findall(r"`(run/[^`]+\.toml)`", r.split("|")[1])}
    assert listed == {f"run/{p.name}" for p in (REPO / "run").glob("*.toml")}
    for r in rows:
        script = re.search(r"examples/(\w+\.py)", r).group(1)
        figure = re.search(r"`(figures/[^`]+\.png)`", r).group(1)
        assert (EXAMPLES / script).is_file(), script
        assert (EXAMPLES / figure).is_file(), figure


def test_the_scene_script_makes_its_figure(tmp_path):
    p = _run([EXAMPLES / "scene_figure.py", REPO / "run" / "pull.toml", "--quick", "--out", tmp_path / "runs",
              "--figures", tmp_path / "figs"], tmp_path)
    png = tmp_path / "figs" / "pull_quick.png"
    assert png.is_file() and png.stat().st_size > 20_000 and str(png) in p.stdout


def test_the_v0_sweep_script_makes_its_figure(tmp_path):
    p = _run([EXAMPLES / "v0_sweep.py", "--quick", "--out", tmp_path / "runs", "--figures", tmp_path / "figs"],
             tmp_path)
    assert (tmp_path / "figs" / "v0_sweep_quick.png").is_file()
    assert p.stdout.count("mean speed") >= 6          # three runs, their first fronts


def test_the_notebook_runs_as_written(tmp_path):
    """Each code cell of examples/tour.ipynb, in order, in one namespace (as a kernel would run them)."""
    nb = json.loads((EXAMPLES / "tour.ipynb").read_text())
    code = [("".join(c["source"])) for c in nb["cells"] if c["cell_type"] == "code"]
    assert len(code) >= 4
    script = tmp_path / "notebook.py"
    script.write_text("\n\n".join(code) + "\nprint('status', run.status)\n")
    p = _run([script], tmp_path)
    assert "status complete" in p.stdout and (tmp_path / "out" / "tour.png").is_file()
