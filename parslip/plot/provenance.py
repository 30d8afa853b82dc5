"""What a figure or a table of numbers came from: the resolved scene(s) and the commit.

Every picture parslip draws carries two PNG text chunks (and the same in a PDF's
Subject and Keywords), so a figure in the docs or a paper says where its numbers
came from without a side file:

  parslip:commit   the git commit(s) the runs record (``git_commit``), space-separated
  parslip:scene    the resolved scene(s) as JSON, flat dotted keys: one object, or a list of them

``source`` is a run (``parslip.open``), a list of runs, a sweep table (a dict of columns with
``scene`` and ``commit``, as ``parslip sweep`` writes them) or a dict {"scene": ..., "commit": ...}.

    from parslip.plot.provenance import read_png
    read_png("docs/studies/img/push_spacetime.png")   # {"commit": [...], "scenes": [{...}]}
"""
from __future__ import annotations

import json

COMMIT, SCENE = "parslip:commit", "parslip:scene"


def of(source) -> dict:
    """{"commit": [..], "scenes": [..]} of ``source`` (see the module docstring); empty for None."""
    if source is None:
        return {"commit": [], "scenes": []}
    if isinstance(source, dict) and "scene" in source and "commit" in source:
        scenes, commits = source["scene"], source["commit"]
        if isinstance(scenes, (list, tuple)) and not isinstance(commits, str):     # a sweep table's columns
            scenes = [json.loads(s) if isinstance(s, str) and s else s for s in scenes]
            return {"commit": sorted({str(c) for c in commits if c}), "scenes": [s for s in scenes if s]}
        return {"commit": [str(commits)] if commits else [], "scenes": [scenes] if scenes else []}
    runs = source if isinstance(source, (list, tuple)) else [source]
    commits, scenes = [], []
    for run in runs:
        c = str(run.attrs.get("git_commit", ""))
        if c and c not in commits:
            commits.append(c)
        scenes.append(dict(run.scene))
    return {"commit": commits, "scenes": scenes}


def png_text(source) -> dict:
    """The PNG text chunks for ``source``: {"parslip:commit": ..., "parslip:scene": ...}."""
    p = of(source)
    scenes = p["scenes"][0] if len(p["scenes"]) == 1 else p["scenes"]
    return {COMMIT: " ".join(p["commit"]), SCENE: json.dumps(scenes, sort_keys=True, default=str)}


def savefig_metadata(fmt: str, source) -> dict:
    """Matplotlib's ``savefig(metadata=...)`` for ``fmt`` ("png" or "pdf")."""
    text = png_text(source)
    if fmt == "pdf":
        return {"Subject": f"{COMMIT} {text[COMMIT]}", "Keywords": f"{SCENE} {text[SCENE]}"}
    return text


def stamp_png(path: str, source) -> None:
    """Write the chunks into an existing PNG (e.g. a pyvista screenshot), keeping its pixels."""
    from PIL import Image, PngImagePlugin
    info = PngImagePlugin.PngInfo()
    for k, v in png_text(source).items():
        info.add_itxt(k, v)
    with Image.open(path) as im:
        im.load()
        im.save(path, pnginfo=info)


def read_png(path: str) -> dict:
    """{"commit": [...], "scenes": [...]} from a PNG's chunks; empty lists when it has none."""
    from PIL import Image
    with Image.open(path) as im:
        text = dict(getattr(im, "text", {}) or {})
    commits = text.get(COMMIT, "").split()
    raw = text.get(SCENE)
    scenes = json.loads(raw) if raw else []
    return {"commit": commits, "scenes": scenes if isinstance(scenes, list) else [scenes]}
