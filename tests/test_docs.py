"""The documentation site builds with warnings as errors, works offline, and its API reference is
the public API.

The sources (``docs/``, ``examples/`` and the ``mjcf`` package, whose README the truck page
includes and whose models the gallery simulates) are copied into a temporary folder first, so the
build starts from a clean state and writes nothing into the repository (sphinx-gallery generates
files beside the sources). The site is built once for the tests of this module: with -W a broken
page, a bad cross-reference, a docstring autodoc cannot parse or a gallery example that fails,
fails the suite; a page that loads a script, a stylesheet, a font or an image from outside the
site (a CDN), or links to a page outside it, fails it too: on an offline lab PC every page and
equation must render. The API page lists the names a lab's script uses (tests/test_docs_examples.py
runs their Examples)."""

from __future__ import annotations

import html.parser
import importlib
import inspect
import pathlib
import re
import shutil
import subprocess
import sys
import urllib.parse

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
API_PAGE = ROOT / "docs" / "api" / "index.rst"
GENERATED = ("_build", "auto_examples", "generated", "sg_execution_times.rst", "__pycache__")
#: Tags and attributes through which a page loads a resource (not a link the reader follows).
LOADS = {"script": "src", "link": "href", "img": "src", "iframe": "src", "source": "src", "video": "src",
         "audio": "src", "embed": "src", "object": "data", "track": "src", "input": "src"}
CSS_URL = re.compile(r"""(?:url\(\s*['"]?|@import\s+['"])([^'")\s]+)""")
#: An absolute URL in an inline <style> or <script>, which can load what it names.
ABSOLUTE_URL = re.compile(r"""(?:https?:)?//[\w.-]+\.[a-z]{2,}[^\s'"<>)]*""", re.I)


def api_entries() -> list[str]:
    """The dotted names the API page documents (its autofunction/autoclass/autoexception entries)."""
    return re.findall(r"^\.\. auto(?:function|class|exception):: (\S+)$", API_PAGE.read_text(), re.M)


def api_object(dotted: str):
    """The object a dotted name of the API page names: the longest importable module, then attributes."""
    parts = dotted.split(".")
    for i in range(len(parts) - 1, 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            obj = getattr(obj, part)
        return obj
    raise ImportError(dotted)


def test_the_api_page_lists_the_public_names_once_each():
    """Every name of the API page is a public function or class (in its module's ``__all__``),
    listed once, and in the summary table as well; every name ``rigsim`` exports is on it as
    ``rigsim.NAME``; no page per object is generated (the internals stay out of the reference)."""
    import rigsim

    text = API_PAGE.read_text()
    entries = api_entries()
    assert len(entries) == len(set(entries)), "an API entry twice"
    table = re.search(r"\.\. autosummary::\n   :nosignatures:\n\n((?:   \S+\n)+)", text)
    assert table and [n.lstrip("~") for n in table[1].split()] == entries, "the summary table and the entries differ"
    assert ":toctree:" not in text
    for dotted in entries:
        obj = api_object(dotted)
        assert inspect.isfunction(obj) or inspect.isclass(obj), dotted
        module, name = dotted.rsplit(".", 1)
        assert name in getattr(importlib.import_module(module), "__all__", ()), f"{dotted} is not public"
    missing = {f"rigsim.{n}" for n in rigsim.__all__ if n != "__version__"} - set(entries)
    assert not missing, "the API page has no entry for " + ", ".join(sorted(missing))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> pathlib.Path:
    """The site built with -W from a copy of the sources: the folder of its HTML."""
    pytest.importorskip("sphinx", reason="the docs stack is not installed (pip install -e '.[docs]')")
    tmp = tmp_path_factory.mktemp("site")
    shutil.copytree(ROOT / "docs", tmp / "docs", ignore=shutil.ignore_patterns(*GENERATED))
    shutil.copytree(ROOT / "examples", tmp / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    # The truck page includes mjcf/README.md (a path relative to docs/): the folder beside it.
    shutil.copytree(ROOT / "mjcf", tmp / "mjcf", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp / "html"
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
                           str(tmp / "docs"), str(out)],
                          cwd=tmp, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    return out


def test_the_site_builds_with_warnings_as_errors(site):
    for page in ("index", "getting_started", "physics", "validation", "formats", "api/index",
                 "auto_examples/index", "guide/correct"):
        assert (site / f"{page}.html").is_file(), page
    assert not (site / "api" / "generated").exists()


class _Refs(html.parser.HTMLParser):
    """A page's resource loads (tag, URL), its links (``<a href>``), its inline CSS and the text of its
    inline styles and scripts."""

    def __init__(self):
        super().__init__()
        self.loads, self.links, self.css, self.inline = [], [], [], []
        self._in = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag in LOADS and attrs.get(LOADS[tag]):
            self.loads.append((tag, attrs[LOADS[tag]]))
        if tag in ("img", "source") and attrs.get("srcset"):
            self.loads += [(tag, part.split()[0]) for part in attrs["srcset"].split(",") if part.strip()]
        if tag == "a" and attrs.get("href"):
            self.links.append(attrs["href"])
        if attrs.get("style"):
            self.css.append(attrs["style"])
        self._in = tag if tag in ("style", "script") else None

    def handle_endtag(self, tag):
        self._in = None

    def handle_data(self, data):
        if self._in:
            self.inline.append((self._in, data))


def _outside(url: str) -> bool:
    """True for a URL that leaves the site: a scheme other than a local one, or //host/..."""
    parts = urllib.parse.urlsplit(url)
    return bool(parts.netloc) or parts.scheme not in ("", "file", "data", "mailto", "javascript")


def site_references(site: pathlib.Path) -> dict:
    """Every page's loads from outside the site, its links to outside pages, and its local loads
    whose file the site lacks; the CSS files' outside URLs. ``pages`` counts the HTML pages."""
    found = {"pages": 0, "outside_loads": [], "outside_links": [], "missing": []}
    for page in sorted(site.rglob("*.html")):
        name = page.relative_to(site).as_posix()
        if name.startswith("_static/"):  # the theme's templates, not pages
            continue
        found["pages"] += 1
        refs = _Refs()
        refs.feed(page.read_text(encoding="utf-8"))
        css_urls = [("css", u) for text in refs.css for u in CSS_URL.findall(text)]
        inline = [(f"inline {tag}", u) for tag, text in refs.inline for u in ABSOLUTE_URL.findall(text)]
        for tag, url in refs.loads + css_urls + inline:
            if _outside(url):
                found["outside_loads"].append(f"{name}: <{tag}> {url}")
            elif not url.startswith(("data:", "#")):
                target = (page.parent / urllib.parse.unquote(urllib.parse.urlsplit(url).path)).resolve()
                if not target.is_file():
                    found["missing"].append(f"{name}: <{tag}> {url}")
        found["outside_links"] += [f"{name}: {url}" for url in refs.links if _outside(url)]
    for css in sorted(site.rglob("*.css")):
        text = css.read_text(encoding="utf-8", errors="replace")
        found["outside_loads"] += [f"{css.relative_to(site).as_posix()}: {u}" for u in CSS_URL.findall(text)
                                   if _outside(u)]
    return found


def test_no_page_loads_anything_from_outside_the_site(site):
    """Scripts, stylesheets, fonts, images: from the site's own files, each present; and no link to
    a page outside the repository's site."""
    found = site_references(site)
    assert found["pages"] > 20, found["pages"]
    assert not found["outside_loads"], "loaded from outside the site:\n" + "\n".join(found["outside_loads"])
    assert not found["missing"], "loaded but not in the site:\n" + "\n".join(found["missing"])
    assert not found["outside_links"], "links outside the site:\n" + "\n".join(found["outside_links"])


def test_equations_render_from_the_sites_own_mathjax(site):
    """A page with math loads MathJax from the site (its TeX input and the fonts of its output
    beside it), and the equations are in the page as TeX for it to typeset."""
    page = (site / "physics.html").read_text(encoding="utf-8")
    assert re.search(r"\\\(|\\\[", page), "physics.html holds no equation"
    scripts = re.findall(r'<script[^>]*src="([^"]*mathjax[^"]*)"', page, re.I)
    assert scripts and all(not _outside(s) for s in scripts), scripts
    mathjax = (site / scripts[0]).resolve()
    assert mathjax.is_file(), scripts[0]
    fonts = list((mathjax.parent / "output" / "chtml" / "fonts").rglob("*.woff"))
    assert fonts, "MathJax's fonts are not in the site"


def test_code_blocks_have_copy_buttons_and_wide_tables_scroll(site):
    page = (site / "getting_started.html").read_text(encoding="utf-8")
    assert "copybutton.js" in page and (site / "_static" / "copybutton.js").is_file()
    validation = (site / "validation.html").read_text(encoding="utf-8")
    assert "tables.css" in validation and (site / "_static" / "tables.css").is_file()
    assert validation.count("<table") == validation.count("pst-scrollable-table-container")
