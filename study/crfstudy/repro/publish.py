"""Publish the rendered report as a PDF and a standalone HTML page, with tools from PyPI alone.

:func:`publish` takes the rendered Markdown (``paper/generated/paper.md``, made by
:func:`crfstudy.repro.paper.build_paper`) and writes, beside it:

- ``paper.html``: one self-contained page (figures embedded as data URIs), by pandoc;
- ``paper.typ`` and ``paper.pdf``: pandoc writes Typst, the ``typst`` package compiles it.

Why these tools: pandoc ships inside the ``pypandoc-binary`` wheel and Typst inside the ``typst``
wheel, so a plain ``pip install`` brings everything -- no LaTeX, no system library, nothing
fetched at install or run time (the Typst source imports no package, pandoc embeds only local
files, and Typst uses the fonts inside its wheel: :data:`TYPST_OPTIONS`).

>>> sorted(TYPST_OPTIONS)
['ignore_system_fonts']
"""
from __future__ import annotations

import os
import re
from concurrent.futures import ThreadPoolExecutor, wait
from pathlib import Path

from crfstudy import paths
from crfmap.errors import InputError
from crfmap.io.atomic import atomic_path

TITLE = "Conditional Random Fields for occupancy grid inference: a reproduction with crfmap"
# The fonts inside the typst wheel only: the PDF looks the same on every machine.
TYPST_OPTIONS = {"ignore_system_fonts": True}

# Typst set-up placed before the body: A4, small type for the wide tables, figures numbered by their
# own captions (the thesis's numbers), not by Typst's counter.
TYPST_HEADER = """\
#let horizontalrule = line(start: (25%, 0%), end: (75%, 0%))
#show terms.item: it => block(breakable: false)[#text(weight: "bold")[#it.term] #it.description]
#set page(paper: "a4", margin: (x: 1.6cm, y: 1.8cm), numbering: "1")
#set text(size: 9.5pt)
#set par(justify: true)
#set figure(numbering: none)
#show figure.caption: set text(size: 8.5pt)
// Images float to the top of a page instead of leaving the rest of a page blank, but not past the next section's
// heading (pending floats are placed first) nor above their own (each section's content is a block:
// section_blocks). Top only: a float placed at a page's bottom sat under the headings that followed it on that
// page (the closed-loop figure inside the Conclusion). A table has its caption above it, stuck to its first rows
// (a caption never ends a page alone). A table of up to 25 rows is kept whole and, while
// `float-tables` holds, floats like an image: kept in the text's order it left a third of a page blank whenever it
// did not fit below the text before it. A longer table stays in the text and continues on the next page, its header
// repeated. The appendix turns floating off (mostly figures and tables, in the text's order).
#let float-tables = state("float-tables", true)
#show figure.where(kind: image): set figure(placement: top)
#show heading.where(level: 2): it => { place.flush(); it }
#show heading.where(level: 3): it => { place.flush(); it }
#show figure.where(kind: table): set figure.caption(position: top)
#show figure.where(kind: table): set block(breakable: true)
#show figure.caption.where(kind: table): it => block(sticky: true, width: 100%, it)
#show figure.where(kind: table): it => context {
  let t = it.body.at("body", default: none)
  let rows = if t != none and t.func() == table {
    let columns = if type(t.columns) == array { t.columns.len() } else { t.columns }
    t.children.len() / calc.max(columns, 1)
  } else { 0 }
  if rows > 25 { it }
  else if float-tables.get() { place(top, float: true, clearance: 1.2em, block(breakable: false, it)) }
  else { block(breakable: false, it) }
}
#show table: set text(size: 6.5pt)
#show table.cell: set par(justify: false)
#set table(inset: 3pt)
#show heading.where(level: 1): set text(size: 15pt)
#show heading.where(level: 2): set text(size: 12pt)
"""

HTML_STYLE = """\
body { max-width: 60rem; margin: 2rem auto; padding: 0 1rem; font-family: sans-serif; line-height: 1.45; }
table { border-collapse: collapse; font-size: 0.8rem; display: block; overflow-x: auto; margin: 0.5rem 0; }
th, td { border: 1px solid #bbb; padding: 0.15rem 0.4rem; }
figure { margin: 1rem 0; } figure img { max-width: 100%; }
figcaption { font-size: 0.9rem; color: #333; }
"""


def _pandoc(source: Path, to: str, extra: list) -> str:
    import pypandoc  # pypandoc-binary: pandoc inside the wheel

    return pypandoc.convert_file(str(source), to, format="markdown", extra_args=extra)


_SCOPED = re.compile(r"^#(?:set|show|let|import|include|pagebreak|float-tables)\b", re.M)  # rules for what follows


def section_blocks(body: str, level: int = 2) -> str:
    """Pandoc's Typst body with each section's content (after its heading) inside a breakable block: level-2
    sections, and within them level-3 ones.

    Why: a top float goes to the top of its region, and the page is the region of content that is not inside a
    block: a figure of a section starting mid-page then sat above that section's heading, in the section before.
    Inside the block its region starts below the heading. A section holding set, show or page-break rules for the
    rest of the document (the references, which open the appendix) stays unwrapped: a block would scope them.

    >>> print(section_blocks("= T\\n\\n== A\\n<a>\\ntext\\n=== A1\\nsub\\n== B\\n#set text(size: 8pt)\\nrefs\\n"))
    = T
    <BLANKLINE>
    == A
    <a>
    #block(width: 100%, breakable: true)[
    text
    === A1
    #block(width: 100%, breakable: true)[
    sub
    ]
    ]
    == B
    #set text(size: 8pt)
    refs
    <BLANKLINE>
    """
    heading = re.compile(rf"^({'=' * level} .*\n(?:<[^>\n]*>\n)?)", re.M)  # a heading and its label line
    parts = heading.split(body)  # [before the first heading, heading, content, heading, content, ...]
    out = [parts[0]]
    for head, content in zip(parts[1::2], parts[2::2]):
        if level < 3:
            content = section_blocks(content, level + 1)
        wrap = content.strip() and not _SCOPED.search(content)
        out.append(head + (f"#block(width: 100%, breakable: true)[\n{content.rstrip()}\n]\n" if wrap else content))
    return "".join(out)


def to_typst(markdown_path: Path) -> str:
    """The Typst source of a rendered report (images referenced by path, relative to it)."""
    markdown_path = Path(markdown_path)
    body = _pandoc(markdown_path, "typst", ["--wrap=none", "--columns=10000"])  # tables: natural widths
    return TYPST_HEADER + "\n" + section_blocks(body)


def to_html(markdown_path: Path, css_path: Path) -> str:
    """One standalone HTML page: figures and style embedded, nothing loaded from elsewhere."""
    markdown_path = Path(markdown_path)
    return _pandoc(markdown_path, "html5", [
        "--standalone", "--embed-resources", f"--css={css_path}", "--wrap=none", "--columns=10000",
        f"--resource-path={markdown_path.parent}", f"--metadata=pagetitle:{TITLE}"])


def _respect_umask(*files):
    """Give files the permissions a plain open() would (a temporary file is created 0600)."""
    mask = os.umask(0)
    os.umask(mask)
    for f in files:
        os.chmod(f, 0o666 & ~mask)


def publish(paper_md_path, pdf_path=None, html_path=None) -> tuple:
    """Build ``paper.pdf`` and ``paper.html`` from a rendered report; returns (pdf, html) paths.

    Both default to the Markdown file's folder. Images must lie under
    :data:`crfstudy.paths.OUTPUT_ROOT` (where :func:`crfstudy.repro.report.save_figure` puts them),
    the root Typst may read from.
    """
    import typst

    source = Path(paper_md_path)
    if not source.is_file():
        raise InputError(str(source), "no rendered report here; run crfstudy.repro.paper.build_paper first")
    pdf_path = Path(pdf_path or source.with_suffix(".pdf"))
    html_path = Path(html_path or source.with_suffix(".html"))
    typ_path = source.with_suffix(".typ")  # beside the Markdown, so relative image paths still hold
    css = source.parent / "paper.css"
    css.write_text(HTML_STYLE)
    # pandoc makes the HTML page in its own process while Typst compiles the PDF here: the two overlap
    with ThreadPoolExecutor(max_workers=1) as pool:
        html = pool.submit(to_html, source, css)
        try:
            with atomic_path(typ_path) as tmp:
                Path(tmp).write_text(to_typst(source))
            root = Path(paths.OUTPUT_ROOT).resolve()
            if root not in typ_path.resolve().parents:
                root = typ_path.resolve().parent.parent.parent
            with atomic_path(pdf_path) as tmp:
                Path(tmp).write_bytes(typst.compile(str(typ_path), root=str(root), **TYPST_OPTIONS))
            with atomic_path(html_path) as tmp:
                Path(tmp).write_text(html.result())
        finally:
            html.cancel()
            wait([html])  # pandoc has finished reading the style sheet before it goes
            css.unlink()
    _respect_umask(typ_path, pdf_path, html_path)
    return pdf_path, html_path
