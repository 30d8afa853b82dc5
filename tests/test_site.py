"""The built site read in a browser, from disk, with no network: formulas typeset, pictures there, nothing fetched.

The site is the session's ``mkdocs build --strict`` (``docs_site`` in conftest.py).  Headless Chromium
(Debian's, which ``tests/install.sh`` installs with apt-get) opens pages as file:// URLs with host
resolution switched off, runs their scripts (``--virtual-time-budget``) and dumps the DOM; its net log
records every request it tried.  Checked:

  * the model page holds at least 5 typeset formulas (MathJax's ``mjx-container``), every formula of it
    typeset, and the model picture; a screenshot of it is saved in the test's tmp_path
  * the tour notebook page shows its figures (``img`` elements with PNG data)
  * no page has a broken image (every ``img`` is a file of the site or inline data) or an unrendered
    ``$...$``, ``\\(...\\)`` or ``\\[...\\]`` in its text
  * no page loads anything from the network (static: every script, stylesheet, image and frame is local;
    in the browser: the net log holds no http(s) request but Chromium's own service pings)
"""
from __future__ import annotations

import base64
import html
import json
import re
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no chromium on PATH: tests/install.sh installs Debian's with apt-get "
                             "(where apt-get exists); elsewhere install Chromium to run the browser test")

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-default-apps", "--disable-extensions", "--no-pings", "--disable-dev-shm-usage",
         "--host-resolver-rules=MAP * ~NOTFOUND", "--virtual-time-budget=15000", "--hide-scrollbars"]
# What Chromium asks its own services for, whatever the page (update checks, accounts, time): not the site's.
BROWSER_OWN = re.compile(r"^https?://([a-z0-9-]+\.)*(google\.com|googleapis\.com)(/|$)|^https?://~notfound")
MIN_FORMULAS = 5
UNRENDERED = re.compile(r"\$[^$\s][^$]*\$|\\\(|\\\)|\\\[|\\\]")


class _Page(HTMLParser):
    """The page's resources (tag, attribute, URL), its img sources and its visible text outside code."""

    SKIP = {"script", "style", "code", "pre", "mjx-container", "mjx-assistive-mml", "svg", "textarea"}
    VOID = {"img", "link", "meta", "br", "hr", "input", "source", "wbr", "col", "area", "base", "embed", "param",
            "track"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.resources, self.images, self.text, self.skip = [], [], [], 0
        self.formulas = self.arithmatex = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "mjx-container":
            self.formulas += 1
        if "arithmatex" in (a.get("class") or "").split():
            self.arithmatex += 1
        if tag == "img":
            self.images.append(a.get("src") or "")
        for attr, tags in (("src", ("script", "img", "iframe", "source", "audio", "video", "embed")),
                           ("href", ("link",))):
            if tag in tags and a.get(attr) and (tag != "link" or a.get("rel") in ("stylesheet", "preload",
                                                                                  "icon", "modulepreload")):
                self.resources.append((tag, attr, a[attr]))
        if tag in self.SKIP and tag not in self.VOID:
            self.skip += 1

    def handle_endtag(self, tag):
        if tag in self.SKIP and self.skip:
            self.skip -= 1

    def handle_data(self, data):
        if not self.skip:
            self.text.append(data)


def _parse(text: str) -> _Page:
    p = _Page()
    p.feed(text)
    return p


def _pages(site: Path) -> list[Path]:
    return sorted(p for p in site.rglob("*.html") if p.name != "404.html")


def _broken_images(page: Path, images: list[str], site: Path) -> list[str]:
    bad = []
    for src in images:
        if src.startswith("data:image/"):
            head, _, data = src.partition(",")
            try:
                ok = ";base64" not in head or len(base64.b64decode(data[:4000] + "=" * (-len(data[:4000]) % 4))) > 0
            except ValueError:
                ok = False
        else:
            u = urlparse(src)
            if u.scheme == "file":
                target = Path(unquote(u.path))
            elif u.scheme:
                bad.append(f"{src} (not a file of the site)")
                continue
            else:
                target = (page.parent / unquote(u.path)).resolve()
            ok = target.is_file() and target.stat().st_size > 0 and site.resolve() in target.parents
        if not ok:
            bad.append(src[:80])
    return bad


def _chromium(url: str, work: Path, *extra: str) -> tuple[str, list[str]]:
    """(the DOM after the page's scripts ran, the http(s) URLs of the net log that are not Chromium's own)."""
    work.mkdir(parents=True, exist_ok=True)
    netlog = work / "net.json"
    r = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={work / 'profile'}", f"--log-net-log={netlog}",
                        *extra, url], capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, f"chromium failed on {url} (exit {r.returncode}):\n{r.stderr[-2000:]}"
    urls = set()
    if netlog.is_file():
        text = netlog.read_text(errors="replace")
        try:
            events = json.loads(text if text.rstrip().endswith("}") else text.rstrip().rstrip(",") + "]}")
            for e in events.get("events", []):
                u = (e.get("params") or {}).get("url")
                if u:
                    urls.add(u)
        except ValueError:
            urls.update(re.findall(r'"url":"([^"]+)"', text))
    leaving = sorted(u for u in urls if u.startswith(("http:", "https:", "ws:", "wss:")) and not BROWSER_OWN.match(u))
    return r.stdout, leaving


@pytest.fixture(scope="module")
def rendered(docs_site, tmp_path_factory):
    """Every page with formulas or a notebook, and the model page, rendered by Chromium: {page: (dom, urls)}."""
    work = tmp_path_factory.mktemp("chromium")
    pages = [p for p in _pages(docs_site)
             if 'class="arithmatex"' in p.read_text() or p.parent.name == "examples"
             or p.relative_to(docs_site).as_posix() == "model/index.html"]
    with ThreadPoolExecutor(max_workers=3) as pool:
        futures = {p: pool.submit(_chromium, p.as_uri(), work / str(i), "--dump-dom") for i, p in enumerate(pages)}
        return {p: f.result() for p, f in futures.items()}


def test_the_model_page_typesets_its_formulas_and_shows_the_picture(docs_site, rendered, tmp_path):
    page = docs_site / "model" / "index.html"
    dom, leaving = rendered[page]
    p = _parse(dom)
    assert p.formulas >= MIN_FORMULAS, f"{p.formulas} typeset formulas (mjx-container) on the model page"
    static = _parse(page.read_text())
    assert p.formulas >= static.arithmatex, f"{static.arithmatex} formulas in the page, {p.formulas} typeset"
    assert "<mjx-merror" not in dom, "MathJax reports a TeX error on the model page"
    assert any(src.endswith("scene.png") for src in p.images), f"no model picture among {p.images}"
    assert (docs_site / "model" / "scene.png").stat().st_size > 20_000
    assert not leaving, f"the model page asked the network for {leaving}"

    shot = tmp_path / "model.png"
    _chromium(page.as_uri(), tmp_path / "shot", f"--screenshot={shot}", "--window-size=1280,2400")
    assert shot.is_file() and shot.stat().st_size > 50_000, "no screenshot of the model page"


def test_the_tour_notebook_page_shows_its_figures(docs_site, rendered):
    page = docs_site / "examples" / "tour.html"
    assert page in rendered, f"no tour notebook page in the site: {_pages(docs_site)}"
    dom, leaving = rendered[page]
    figures = [s for s in _parse(dom).images if s.startswith("data:image/png")]
    assert figures, "the tour notebook page shows no figure (its stored outputs: examples/tour.ipynb)"
    assert not leaving, f"the notebook page asked the network for {leaving}"


def test_rendered_pages_have_no_raw_math_and_fetch_nothing(docs_site, rendered):
    problems = []
    for page, (dom, leaving) in rendered.items():
        p = _parse(dom)
        name = page.relative_to(docs_site).as_posix()
        raw = UNRENDERED.findall(html.unescape(" ".join(p.text)))
        if raw:
            problems.append(f"{name}: unrendered math {raw[:5]}")
        if p.formulas < _parse(page.read_text()).arithmatex:
            problems.append(f"{name}: {p.formulas} formulas typeset of {_parse(page.read_text()).arithmatex}")
        if "<mjx-merror" in dom:
            problems.append(f"{name}: MathJax reports a TeX error")
        if leaving:
            problems.append(f"{name}: network requests {leaving}")
        bad = _broken_images(page, p.images, docs_site)
        if bad:
            problems.append(f"{name}: broken images {bad}")
    assert not problems, "\n".join(problems)


def test_every_page_has_its_images_no_raw_math_and_only_local_resources(docs_site):
    problems = []
    for page in _pages(docs_site):
        name = page.relative_to(docs_site).as_posix()
        p = _parse(page.read_text())
        bad = _broken_images(page, p.images, docs_site)
        if bad:
            problems.append(f"{name}: broken images {bad}")
        remote = [u for _, _, u in p.resources if urlparse(u).scheme not in ("", "data", "file")]
        if remote:
            problems.append(f"{name}: remote resources {remote}")
        if not p.arithmatex:                    # pages with formulas are checked after MathJax ran
            raw = UNRENDERED.findall(html.unescape(" ".join(p.text)))
            if raw:
                problems.append(f"{name}: unrendered math {raw[:5]}")
    assert not problems, "\n".join(problems)
