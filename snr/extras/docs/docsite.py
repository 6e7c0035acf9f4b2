"""Build SNR's documentation and read it offline: ``python -m snr docs``.

Two parts, built into one folder (``docs/api/`` in a checkout, a cache
folder when SNR was installed with pip):

* the API reference, generated from the docstrings by pdoc (thesis 7.6). Its
  start page, ``snr.html``, lists what ``from snr import *`` gives by topic
  (`TOPICS`), each name with its summary and a link to its full entry;
* the guide (concepts, tutorial, ...) as HTML, with the links between its
  pages kept working. Its Markdown is ``docs/*.md`` in a checkout; the
  package ships a copy as ``snr/guide/`` (see `find_guide`).

A build reports every problem instead of hiding it: an annotation pdoc cannot
resolve, a docstring that names something that does not exist (a misspelt
class name in single backticks), a link in a page to a file that is not
there, a name of ``snr.__all__`` that no topic of the start page lists.
``--build-only`` (CI, ``nox -s docs``) fails when there is any.

Example::

    python -m snr docs                # build if needed, then open it in a browser
    python -m snr docs --serve        # or serve it on http://127.0.0.1:8765
    python -m snr docs --build-only   # rebuild docs/api; exit 1 on any warning
"""

from __future__ import annotations

import argparse
import builtins
import functools
import html
import http.server
import importlib
import importlib.util
import inspect
import os
import pkgutil
import posixpath
import re
import sys
import textwrap
import warnings
import webbrowser
from pathlib import Path
from types import ModuleType
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple

import snr
from snr import prelude
from snr.extras.docs.api_topics import PAGE_MODULES, TOPICS, check_topics, full_entry, summary
from snr.prelude import SNRError
from snr.prelude.install import install_hint

__all__ = [
    "API_MODULES",
    "DEFAULT_PORT",
    "DocsBuildError",
    "add_arguments",
    "build",
    "check_docstring_references",
    "default_output_dir",
    "find_guide",
    "is_stale",
    "make_server",
    "render_api_start_page",
    "render_guide",
    "run",
    "serve",
]

API_MODULES: Tuple[str, ...] = PAGE_MODULES
"""The pages pdoc writes in full: each layer, and the names kept from 2021.

``snr`` itself is not among them: it re-exports all of these, and pdoc would
repeat every entry on one 4 MB page. Its page, the start page of the
reference, is written by `render_api_start_page` instead."""

DEFAULT_PORT = 8765
"""The port ``--serve`` uses unless told otherwise."""

GUIDE_FOLDER = "guide"
STAMP_FILE = ".snr-docs-stamp"
_PACKAGE_DIR = Path(snr.__file__).resolve().parent
_MARKDOWN_LINK = re.compile(r"(\]\()([^)\s]+)(\))")
_LABELLED_LINK = re.compile(r"\[([^\]\n]*)\]\(([^)\s]+)\)")
# `Name` or `Name.attr` in single backticks: a reference the reader may follow.
_DOC_REFERENCE = re.compile(r"(?<![`\w])`([A-Z]\w*(?:\.\w+)*)`(?![`\w])")


class DocsBuildError(SNRError):
    """The documentation cannot be built at all (e.g. pdoc is not installed).

    Example::

        try:
            build(Path("docs/api"))
        except DocsBuildError as e:
            print(e)
    """


def find_guide(package_dir: Path = _PACKAGE_DIR) -> Optional[Path]:
    """The folder of the guide's Markdown pages, or None if there is none.

    In a checkout it is ``docs/`` next to the ``snr`` package (next to
    ``pyproject.toml``); a wheel ships a copy as ``snr/guide/`` (see
    ``pyproject.toml``), which is what a plain ``pip install`` leaves.

    Example::

        find_guide()   # PosixPath('/home/me/SNR/docs'), or .../site-packages/snr/guide
    """
    checkout = package_dir.parent
    if (checkout / "pyproject.toml").is_file() and (checkout / "docs" / "index.md").is_file():
        return checkout / "docs"
    shipped = package_dir / "guide"
    return shipped if (shipped / "index.md").is_file() else None


def _is_shipped_copy(guide_dir: Path) -> bool:
    """True if ``guide_dir`` is the guide inside an installed package (``snr/guide``)."""
    return (guide_dir.parent / "__init__.py").is_file()


_GUIDE_DIR = find_guide()


def default_output_dir() -> Path:
    """``docs/api`` in a checkout; a cache folder when SNR was installed from a wheel.

    Example::

        default_output_dir()   # PosixPath('/home/me/SNR/docs/api')
    """
    guide = _GUIDE_DIR
    if guide is not None and not _is_shipped_copy(guide) and os.access(guide, os.W_OK):
        return guide / "api"
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "snr" / f"docs-{snr.__version__}"


# ---------------------------------------------------------------------------
# Staleness: rebuild only when a source or a page changed.
# ---------------------------------------------------------------------------


def _inputs(guide_dir: Optional[Path]) -> Iterator[Path]:
    yield from _PACKAGE_DIR.rglob("*.py")
    if guide_dir is not None and guide_dir.is_dir():
        yield from guide_dir.rglob("*.md")


def _fingerprint(guide_dir: Optional[Path]) -> str:
    newest = max((p.stat().st_mtime_ns for p in _inputs(guide_dir)), default=0)
    return f"snr {snr.__version__} newest {newest}"


def is_stale(output_dir: Path, guide_dir: Optional[Path] = _GUIDE_DIR) -> bool:
    """True unless ``output_dir`` holds a clean build of the current sources.

    Example::

        if is_stale(Path("docs/api")):
            build(Path("docs/api"))
    """
    stamp = output_dir / STAMP_FILE
    try:
        return stamp.read_text(encoding="utf-8") != _fingerprint(guide_dir)
    except OSError:
        return True


# ---------------------------------------------------------------------------
# Checks pdoc does not make.
# ---------------------------------------------------------------------------


def _documented_objects(module: ModuleType) -> Iterator[Any]:
    yield module
    for obj in vars(module).values():
        if getattr(obj, "__module__", None) != module.__name__:
            continue
        if inspect.isfunction(obj):
            yield obj
        elif inspect.isclass(obj):
            yield obj
            for member in vars(obj).values():
                if inspect.isfunction(member) or isinstance(member, property):
                    yield member


def _resolves(reference: str, namespace: Dict[str, Any]) -> bool:
    head, *rest = reference.split(".")
    if head not in namespace:
        return False
    target = namespace[head]
    for attribute in rest:
        if not hasattr(target, attribute):
            return False
        target = getattr(target, attribute)
    return True


def check_docstring_references(modules: Iterable[ModuleType]) -> List[str]:
    """One warning per name in single backticks, in a docstring, that names nothing.

    A name counts as found if the docstring's module, a package it is in
    (``snr.std_mods.io`` for ``snr.std_mods.io.console``), ``snr``, the
    prelude (whose types and errors every layer uses) or the builtins define
    it (``Name.attr`` must then have ``attr``). Double backticks
    (``literal``) are code samples and are not checked.

    Example::

        check_docstring_references([snr.core.node])   # [] when all is well
    """
    problems: List[str] = []
    # getattr, not vars(snr): snr binds some exports only on first use (PEP 562).
    exports = {name: getattr(snr, name) for name in snr.__all__}
    for module in modules:
        namespace: Dict[str, Any] = {**vars(builtins), **vars(prelude), **vars(snr), **exports}
        for package in _packages_of(module.__name__):
            namespace.update(vars(importlib.import_module(package)))
        namespace.update(vars(module))
        for obj in _documented_objects(module):
            doc = inspect.getdoc(obj) or ""
            for reference in _DOC_REFERENCE.findall(doc):
                if not _resolves(reference, namespace):
                    owner = getattr(obj, "__qualname__", None) or module.__name__
                    if isinstance(obj, property) and obj.fget is not None:
                        owner = obj.fget.__qualname__
                    problems.append(
                        f"{module.__name__}: the docstring of {owner} refers to "
                        f"`{reference}`, which is not defined there, in snr or in "
                        "builtins. Fix the name, or use ``double backticks`` for code."
                    )
    return problems


def _packages_of(module_name: str) -> List[str]:
    """The packages ``module_name`` is in, below ``snr``: ``snr.std_mods``, ``snr.std_mods.io``."""
    parts = module_name.split(".")
    return [".".join(parts[:end]) for end in range(2, len(parts))]


def _snr_modules() -> List[ModuleType]:
    names = [info.name for info in pkgutil.walk_packages(snr.__path__, "snr.")]
    return [snr] + [importlib.import_module(n) for n in names if not n.endswith("__main__")]


# ---------------------------------------------------------------------------
# The guide: docs/*.md as HTML.
# ---------------------------------------------------------------------------

_PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title} · SNR</title>
<style>
body {{ font: 16px/1.55 system-ui, sans-serif; max-width: 52rem; margin: 0 auto;
       padding: 1rem 1.5rem 4rem; color: #1d1d1f; }}
nav {{ border-bottom: 1px solid #ddd; padding-bottom: .5rem; margin-bottom: 1rem; }}
nav a {{ margin-right: 1rem; }}
pre {{ background: #f6f8fa; padding: .8rem; overflow-x: auto; border-radius: 4px; }}
code {{ font: 0.9em ui-monospace, monospace; }}
table {{ border-collapse: collapse; }} td, th {{ border: 1px solid #ddd; padding: .3rem .6rem; }}
{highlight}
</style></head>
<body><nav><a href="{home}">Guide</a><a href="{api}">API reference</a></nav>
{body}
</body></html>
"""


def _markdown_to_html(text: str) -> str:
    from pdoc.render_helpers import to_html  # pdoc's own Markdown settings

    return to_html(text)


def _highlight_css() -> str:
    try:
        import pdoc
    except ImportError:  # pragma: no cover - build() checks first
        return ""
    css = Path(pdoc.__file__).parent / "templates" / "syntax-highlighting.css"
    return css.read_text(encoding="utf-8") if css.is_file() else ""


def _shown(page: Path, guide_dir: Path) -> str:
    return page.relative_to(guide_dir.parent).as_posix()


def _rewrite_link(
    target: str, page: Path, guide_dir: Path, output_dir: Path, problems: List[str]
) -> str:
    """The link ``target`` of ``page`` as it must read in the built HTML."""
    if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
        return target  # a web address, mailto:, or a place on the same page
    path_part, _, fragment = target.partition("#")
    anchor = f"#{fragment}" if fragment else ""
    resolved = (page.parent / path_part).resolve()
    html_dir = output_dir / GUIDE_FOLDER / page.parent.relative_to(guide_dir)
    api_dir = (guide_dir / "api").resolve()
    if resolved == api_dir or api_dir in resolved.parents:
        # A link into the API reference (docs/api/...), wherever it is built.
        built = output_dir / resolved.relative_to(api_dir)
        if not (built.exists() or _is_module_page(resolved.relative_to(api_dir))):
            problems.append(
                f"{_shown(page, guide_dir)}: the link to '{target}' is not a page "
                "of the API reference."
            )
        return Path(os.path.relpath(built, html_dir)).as_posix() + anchor
    if not resolved.exists():
        problems.append(
            f"{_shown(page, guide_dir)}: the link to '{target}' points to a file that does "
            "not exist."
        )
        return target
    if resolved.suffix == ".md" and guide_dir.resolve() in resolved.parents:
        built = output_dir / GUIDE_FOLDER / resolved.relative_to(guide_dir.resolve())
        return Path(os.path.relpath(built.with_suffix(".html"), html_dir)).as_posix() + anchor
    # An example or a source file: link to it where it is (works from file://).
    return Path(os.path.relpath(resolved, html_dir)).as_posix() + anchor


def _is_module_page(relative: Path) -> bool:
    """True if ``relative`` (e.g. ``snr/core/node.html``) is the page of an SNR module.

    pdoc writes one page per module, so this holds even when a partial build
    (as in the tests) did not write that page.
    """
    if (
        relative.suffix != ".html"
        or not relative.parts
        or relative.parts[0] not in ("snr", "snr.html")
    ):
        return False
    module = ".".join(relative.with_suffix("").parts)
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def _unlink_source_files(text: str, page: Path, guide_dir: Path) -> str:
    """``text`` with its links to files of SNR's source that are not installed as plain text.

    The guide links to the examples (``../examples/...``); the installed copy
    in ``snr/guide`` has no examples next to it. Such a link becomes its text
    and where the file is in SNR's source. (The build of the checkout's
    ``docs/`` checks these links.)
    """
    page_dir = page.parent.relative_to(guide_dir).as_posix()

    def unlink(match: re.Match[str]) -> str:
        label, target = match.group(1), match.group(2)
        path_part = target.partition("#")[0]
        resolved = (page.parent / path_part).resolve()
        if (
            re.match(r"^[a-z][a-z0-9+.-]*:", target)
            or not path_part
            or resolved.exists()
            or guide_dir.resolve() in resolved.parents
        ):
            return match.group(0)
        source = posixpath.normpath(posixpath.join("docs", page_dir, path_part))
        source += "/" if path_part.endswith("/") else ""
        return label if source in label else f"{label} (`{source}` in SNR's source)"

    return _LABELLED_LINK.sub(unlink, text)


def _rewrite_links(page: Path, guide_dir: Path, output_dir: Path, problems: List[str]) -> str:
    """The text of ``page`` with every Markdown link rewritten for the built site."""

    def rewrite(match: re.Match[str]) -> str:
        target = _rewrite_link(match.group(2), page, guide_dir, output_dir, problems)
        return match.group(1) + target + match.group(3)

    text = page.read_text(encoding="utf-8")
    if _is_shipped_copy(guide_dir):
        text = _unlink_source_files(text, page, guide_dir)
    return _MARKDOWN_LINK.sub(rewrite, text)


def render_guide(guide_dir: Path, output_dir: Path) -> List[str]:
    """Write every ``*.md`` under ``guide_dir`` as HTML; returns link problems.

    Example::

        render_guide(Path("docs"), Path("docs/api"))   # docs/index.md -> guide/index.html
    """
    problems: List[str] = []
    highlight = _highlight_css()
    for page in sorted(guide_dir.rglob("*.md")):
        if (guide_dir / "api") in page.parents:
            continue
        text = _rewrite_links(page, guide_dir, output_dir, problems)
        relative = page.relative_to(guide_dir).with_suffix(".html")
        destination = output_dir / GUIDE_FOLDER / relative
        destination.parent.mkdir(parents=True, exist_ok=True)
        up = os.path.relpath(output_dir / GUIDE_FOLDER, destination.parent)
        title_match = re.search(r"^#\s+(.+)$", text, re.MULTILINE)
        title = title_match.group(1) if title_match else page.stem
        destination.write_text(
            _PAGE.format(
                title=html.escape(title),
                home=Path(up, "index.html").as_posix(),
                api=Path(up, "..", "snr.html").as_posix(),
                body=_markdown_to_html(text),
                highlight=highlight,
            ),
            encoding="utf-8",
        )
    return problems


# ---------------------------------------------------------------------------
# The start page of the API reference: snr's exports by topic.
# ---------------------------------------------------------------------------

_REDIRECT = """<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta http-equiv="refresh" content="0; url=snr.html"><title>SNR API reference</title></head>
<body><a href="snr.html">The SNR API reference</a></body></html>
"""


def _start_page_markdown(output_dir: Path, problems: List[str]) -> str:
    guide = output_dir / GUIDE_FOLDER
    contents = " · ".join(f"[{t.title}](#{_slug(t.title)})" for t in TOPICS)
    parts = [
        "# The SNR API",
        literal_blocks_to_fences(inspect.getdoc(snr) or ""),
        "## What `from snr import *` gives, by topic",
        f"{contents} · [Each layer in full](#each-layer-in-full)",
    ]
    built_pages: Dict[Path, str] = {}
    for topic in TOPICS:
        parts.append(f'<h3 id="{_slug(topic.title)}">{html.escape(topic.title)}</h3>')
        pages = [s for s in topic.guide if (guide / f"{s}.html").is_file()]
        if (guide / "index.html").is_file():
            problems += [
                f"snr.extras.docs.api_topics: topic {topic.title!r} names the guide page {s!r}, "
                "which the guide does not have."
                for s in sorted(set(topic.guide) - set(pages))
            ]
        reading = ", ".join(f"[{s}](guide/{s}.html)" for s in pages)
        parts.append(topic.about + (f" In the guide: {reading}." if reading else ""))
        lines = []
        for name in topic.names:
            entry = full_entry(name)
            if entry is None:
                problems.append(
                    f"snr.{name} is on the start page but on no page of the API "
                    f"reference: export it from one of {', '.join(PAGE_MODULES)}."
                )
                continue
            _check_anchor(output_dir, entry, built_pages, problems)
            lines.append(f"* [`{name}`]({entry}): {summary(name)}")
        parts.append("\n".join(lines))
    parts.append('<h2 id="each-layer-in-full">Each layer in full</h2>')
    parts.append(
        "\n".join(
            f"* [`{name}`]({name.replace('.', '/')}.html): {_first_line(name)}"
            for name in PAGE_MODULES
        )
    )
    return "\n\n".join(parts)


def _slug(title: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def _first_line(module_name: str) -> str:
    doc = inspect.getdoc(importlib.import_module(module_name)) or ""
    return doc.split("\n")[0]


def _check_anchor(
    output_dir: Path, entry: str, built_pages: Dict[Path, str], problems: List[str]
) -> None:
    """Report a link of the start page to a place that a page built here lacks."""
    page_name, _, anchor = entry.partition("#")
    page = output_dir / page_name
    if not anchor or not page.is_file():
        return  # a page this (partial) build did not write
    if page not in built_pages:
        built_pages[page] = page.read_text(encoding="utf-8")
    if f'id="{anchor}"' not in built_pages[page]:
        problems.append(f"The start page links to {entry}, which that page does not have.")


def render_api_start_page(output_dir: Path) -> List[str]:
    """Write ``snr.html``, the API reference's start page (`TOPICS`); returns problems.

    A problem is an export of ``snr`` in no topic, or a link to an entry that
    a page built here does not have. ``index.html`` leads to the same page.

    Example::

        render_api_start_page(Path("docs/api"))   # [] when every export is listed
    """
    problems = check_topics()
    body = _markdown_to_html(_start_page_markdown(output_dir, problems))
    guide_home = output_dir / GUIDE_FOLDER / "index.html"
    output_dir.mkdir(parents=True, exist_ok=True)
    (output_dir / "snr.html").write_text(
        _PAGE.format(
            title="API reference",
            home=f"{GUIDE_FOLDER}/index.html" if guide_home.is_file() else "snr.html",
            api="snr.html",
            body=body,
            highlight=_highlight_css(),
        ),
        encoding="utf-8",
    )
    (output_dir / "index.html").write_text(_REDIRECT, encoding="utf-8")
    return problems


# ---------------------------------------------------------------------------
# Build, open, serve.
# ---------------------------------------------------------------------------


def build(
    output_dir: Path,
    guide_dir: Optional[Path] = _GUIDE_DIR,
    show_source: bool = True,
    modules: Sequence[str] = API_MODULES,
) -> List[str]:
    """Build the API reference and the guide into ``output_dir``; returns warnings.

    ``modules`` limits the pdoc pages written (the tests build one small page
    to save time); the docstring reference check always covers all of SNR.

    An empty list means a clean build (and it is stamped, so `is_stale` is
    False until a source changes). ``guide_dir`` None builds the API only.

    Raises:
        DocsBuildError: pdoc is not installed.

    Example::

        problems = build(Path("docs/api"))
        if problems:
            print("\\n".join(problems))
    """
    try:
        import pdoc
        import pdoc.render
    except ImportError as error:
        raise DocsBuildError(
            "Building the docs needs pdoc, which is not installed. Install it with "
            f"`{install_hint('docs')}` (or `pip install -e '.[dev]'` in a checkout)."
        ) from error
    output_dir.mkdir(parents=True, exist_ok=True)
    (output_dir / STAMP_FILE).unlink(missing_ok=True)
    problems: List[str] = []
    import pdoc.docstrings

    read_rst = pdoc.docstrings.rst
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # Examples are written "Example::" + an indented block (readable in
        # help()); on the web page they become highlighted Python.
        pdoc.docstrings.rst = lambda text, source: read_rst(  # type: ignore[assignment]
            literal_blocks_to_fences(text), source
        )
        pdoc.docstrings.convert.cache_clear()
        pdoc.render.configure(
            docformat="google",
            show_source=show_source,
            footer_text=f"SNR {snr.__version__}",
        )
        try:
            pdoc.pdoc(*modules, output_directory=output_dir)
        finally:
            pdoc.docstrings.rst = read_rst
            pdoc.docstrings.convert.cache_clear()
    problems += [f"pdoc: {w.message}" for w in caught if not _extra_not_installed(w.message)]
    problems += check_docstring_references(_snr_modules())
    if guide_dir is not None and guide_dir.is_dir():
        problems += render_guide(guide_dir, output_dir)
    problems += render_api_start_page(output_dir)
    if not problems:
        (output_dir / STAMP_FILE).write_text(_fingerprint(guide_dir), encoding="utf-8")
    return problems


# A reStructuredText literal block: a line ending in "::", a blank line, then
# lines indented more than it (SNR's docstrings write examples this way).
_LITERAL_BLOCK = re.compile(
    r"^(?P<indent>[ \t]*)(?P<lead>[^\n]*?)::[ \t]*\n"
    r"(?P<gap>(?:[ \t]*\n)+)"
    r"(?P<block>(?:(?P=indent)[ \t]+[^\n]*(?:\n|$)|[ \t]*\n)+)",
    re.MULTILINE,
)


def literal_blocks_to_fences(docstring: str) -> str:
    """Turn reStructuredText ``Example::`` blocks into fenced Python code.

    pdoc's Google-style reading leaves "Example::" as text; as Markdown the
    block after it becomes a fenced code block with Python highlighting.

    Example::

        literal_blocks_to_fences("Example::\n\n    node.loop()\n")
        # 'Example:\n\n```python\nnode.loop()\n```\n\n'
    """

    def fence(match: re.Match[str]) -> str:
        indent, lead = match["indent"], match["lead"].rstrip()
        lines = match["block"].rstrip("\n").split("\n")
        body = "\n".join(line[len(indent) :] for line in lines)
        code = textwrap.dedent(body).strip("\n")
        heading = f"{indent}{lead}:\n\n" if lead else ""
        fenced = "\n".join(f"{indent}{line}" if line else "" for line in code.split("\n"))
        return f"{heading}{indent}```python\n{fenced}\n{indent}```\n\n"

    return _LITERAL_BLOCK.sub(fence, docstring)


# Packages only an extra brings: without them, pdoc cannot run a module's
# `if TYPE_CHECKING:` imports, which is expected after a plain install.
_EXTRAS_PACKAGES = ("zenoh", "websockets", "mcap", "serial", "pygame", "orjson")
_TYPE_CHECKING_FAILED = re.compile(
    r"Failed to run TYPE_CHECKING code .*No module named '(?P<package>[\w.]+)'"
)


def _extra_not_installed(message: Any) -> bool:
    """True for pdoc's warning that a module's type-only import of an extra failed."""
    found = _TYPE_CHECKING_FAILED.search(str(message))
    return found is not None and found["package"].split(".")[0] in _EXTRAS_PACKAGES


def _start_page(output_dir: Path) -> Path:
    guide = output_dir / GUIDE_FOLDER / "index.html"
    return guide if guide.is_file() else output_dir / "snr.html"


def make_server(output_dir: Path, port: int = DEFAULT_PORT) -> http.server.ThreadingHTTPServer:
    """An HTTP server for ``output_dir`` on 127.0.0.1 only (``port`` 0: any free one).

    Example::

        with make_server(Path("docs/api"), 0) as server:
            print(server.server_address)      # ('127.0.0.1', 41234)
    """
    handler = functools.partial(_QuietHandler, directory=str(output_dir))
    return http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)


def serve(output_dir: Path, port: int = DEFAULT_PORT) -> None:
    """Serve ``output_dir`` on http://127.0.0.1:``port`` until Ctrl-C.

    Example::

        serve(Path("docs/api"))
    """
    try:
        server = make_server(output_dir, port)
    except OSError as error:
        raise DocsBuildError(
            f"Cannot serve the docs on port {port}: {error.strerror}. Another program "
            "(or another `python -m snr docs --serve`) may be using it: pick another "
            "with --port, or open the files directly without --serve."
        ) from error
    with server:
        start = _start_page(output_dir).relative_to(output_dir).as_posix()
        print(f"Serving the SNR docs on http://127.0.0.1:{port}/{start} (Ctrl-C stops)")
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            print("Stopped serving the docs.")


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        pass  # one line per file fetched is noise in a student's terminal


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``python -m snr docs`` (used by ``snr/__main__.py``).

    Example::

        add_arguments(argparse.ArgumentParser())
    """
    parser.description = (
        "Build SNR's documentation, the guide and the API reference, as HTML "
        "(only if a page or the code changed since the last build), then open it in a "
        "browser, to read offline; --serve serves it on http://127.0.0.1 instead."
    )
    parser.add_argument(
        "--build-only",
        action="store_true",
        help="rebuild and stop; exit 1 if there was any warning (for CI)",
    )
    parser.add_argument("--rebuild", action="store_true", help="rebuild even if up to date")
    parser.add_argument("--serve", action="store_true", help="serve over http on 127.0.0.1")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help="port for --serve")
    parser.add_argument("--no-open", action="store_true", help="only print where the docs are")
    parser.add_argument("--no-source", action="store_true", help="leave out source listings")
    parser.add_argument("--output", type=Path, default=None, help="where to build")


def run(args: argparse.Namespace) -> int:
    """Do what ``python -m snr docs`` was asked; returns the exit code.

    Example::

        parser = argparse.ArgumentParser(); add_arguments(parser)
        run(parser.parse_args(["--build-only"]))
    """
    output_dir: Path = args.output or default_output_dir()
    if args.build_only or args.rebuild or is_stale(output_dir):
        print(f"Building the SNR docs into {output_dir} ...", flush=True)
        if _GUIDE_DIR is None:
            print(
                "snr docs: the guide's pages are not here (neither docs/ in a copy of "
                "SNR's source nor snr/guide/ in the installed package); building the "
                "API reference only. Reinstall SNR with pip to get them.",
                file=sys.stderr,
            )
        try:
            problems = build(output_dir, show_source=not args.no_source)
        except DocsBuildError as error:
            print(f"snr docs: {error}", file=sys.stderr)
            return 2
        for problem in problems:
            print(f"warning: {problem}", file=sys.stderr)
        if problems:
            print(f"The docs built with {len(problems)} warning(s).", file=sys.stderr)
            if args.build_only:
                return 1
    if args.build_only:
        print("The docs built with no warnings.")
        return 0
    if args.serve:
        try:
            serve(output_dir, args.port)
        except DocsBuildError as error:
            print(f"snr docs: {error}", file=sys.stderr)
            return 2
        return 0
    start = _start_page(output_dir).resolve()
    print(f"The SNR docs: {start.as_uri()}")
    if not args.no_open and not webbrowser.open(start.as_uri()):
        print("(No browser could be started here: open that address in one.)")
    return 0


def _main(argv: Optional[Sequence[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m snr docs", description=__doc__)
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(_main())
