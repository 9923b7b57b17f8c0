"""The paper's prose quotes no typed numbers, and its PDF and HTML are built with every figure, offline."""
import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
TEMPLATE = ROOT / "paper" / "paper.md"

# Numbers the prose may type: the thesis's own, quoted as the thesis's (its tables, its worked example,
# its node numbering and its learning constants) ...
THESIS_NUMBERS = {"0.8", "0.74", "0.004608", "7", "0.26", "0.24", "0.77", "0.505", "4", "5", "8", "0.0825", "0.0219",
                  "0.0197", "0.112", "0.0623", "0.055", "0.35", "0.024", "0.0007", "0.00005", "0.8436", "0.6229",
                  "0.977", "0.01",
                  "0.9727", "0.9519", "0.9442", "0.9526", "0.9653", "0.9383", "0.2"}  # Table 14 (= Table 20), sec. 3.4.2
# ... and the definitions the method is made of: the default tables and their ratios, P = 0.5 unknown,
# 0.25 / 0.75 for one hit under eq. 16, table entries a of [[a, 1], [1, a]] that the text names, the square
# lattice's critical coupling 0.44 (a constant of physics), LBP's Bethe point atanh(1/3) = 0.347 on it, and the 95 %
# of a confidence interval.
DEFINITIONS = {"0", "1", "2", "3", "9", "10", "0.9", "0.1", "0.5", "0.25", "0.75", "1.5", "0.44", "0.347", "95"}
# "Fig. 27-35", "Tables 10-14", "eq. 12 and 13", "sec. 3.4.2", "notebook 05": references, not quantities.
REFERENCE = re.compile(r"\b(?:Figs?\.|Tables?|eqs?\.|sec\.|Listing|notebooks?)\s+\d+(?:\.\d+)*"
                       r"(?:\s*(?:-|,|and)\s*\d+(?:\.\d+)*)*", re.IGNORECASE)
PLACEHOLDER = re.compile(r"\{\{[^}]*\}\}")
NAMES = re.compile(r"\b(?:Freiburg building 101|ROS [12])\b")  # names of data sets, not quantities
CITATION = re.compile(r"\[\d+(?:\s*,\s*\d+)*\]")  # "[6]", "[12, 13]": numbered references
REFERENCE_LIST = re.compile(r"^## References\n.*?(?=^## |^```|\Z)", re.M | re.S)  # years and pages of the cited works
FENCED = re.compile(r"^```.*?^```", re.M | re.S)  # commands and raw Typst
NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?(?![\w])")


def typed_numbers(text: str) -> list:
    """(number, context) for every number in ``text`` that is neither a placeholder nor allowed."""
    text = re.sub(r"<!--.*?-->", " ", text, flags=re.S)
    text = FENCED.sub(" ", text)
    text = REFERENCE_LIST.sub(" ", text)
    text = re.sub(r"`[^`]*`", " ", text)  # code: names and commands
    text = PLACEHOLDER.sub(" ", text)
    text = REFERENCE.sub(" ", text)
    text = NAMES.sub(" ", text)
    text = CITATION.sub(" ", text)
    found = []
    for m in NUMBER.finditer(text):
        value = m.group(0)
        if value not in THESIS_NUMBERS | DEFINITIONS:
            found.append((value, text[max(0, m.start() - 40):m.end() + 20].replace("\n", " ")))
    return found


def test_the_check_finds_typed_numbers():
    assert [v for v, _ in typed_numbers("recall fell to 0.051 in Fig. 29")] == ["0.051"]
    assert typed_numbers("MSE {{number:x.mse|.4f}} (thesis 0.0623), Tables 15-20, sec. 3.4.2") == []
    assert typed_numbers("as Onsager showed [6, 12].\n\n## References\n\n[6] L. Onsager. 65:117-149, 1944.\n") == []
    assert [v for v, _ in typed_numbers("```bash\nmake -j 4\n```\nit took 42 s")] == ["42"]


def test_prose_quotes_no_typed_numbers():
    found = typed_numbers(TEMPLATE.read_text())
    assert not found, "numbers typed into paper/paper.md (make them {{number:...}} placeholders):\n" + "\n".join(
        f"  {value!r} in ...{context}..." for value, context in found)


def test_paper_has_the_parts_a_reader_needs():
    text = TEMPLATE.read_text()
    for part in ("**Abstract.**", "## Summary of verdicts", "## Conclusion", "## Beyond the thesis: a refinement that makes real maps better",
                 "## Reproducibility", "## References"):
        assert part in text, part
    figures = re.findall(r"\{\{figure:([^}|]+)\|([^}]*)\}\}", text)
    assert figures and all(len(caption.split()) >= 4 for _, caption in figures), "every figure needs a real caption"
    for section in text.split("\n## "):  # the thesis's figures in the thesis's order within each section
        numbered = [int(m) for m in re.findall(r"\{\{figure:fig(\d\d)", section)]
        assert numbered == sorted(numbered), f"thesis figures out of order in '{section.splitlines()[0]}': {numbered}"


@pytest.fixture
def out(tmp_path, monkeypatch):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    import crfstudy.paths

    importlib.reload(crfstudy.paths)
    import crfstudy.repro.paper
    import crfstudy.repro.publish
    import crfstudy.repro.report

    for module in (crfstudy.repro.report, crfstudy.repro.publish, crfstudy.repro.paper):
        importlib.reload(module)
    yield tmp_path
    monkeypatch.delenv("CRFMAP_OUTPUT_ROOT")
    importlib.reload(crfstudy.paths)
    for module in (crfstudy.repro.report, crfstudy.repro.publish, crfstudy.repro.paper):
        importlib.reload(module)


def pdf_image_count(pdf_path) -> int:
    """Image XObjects drawn on the PDF's pages (each figure is one)."""
    from pypdf import PdfReader

    return sum(len(page.images) for page in PdfReader(str(pdf_path)).pages)


def test_publish_builds_pdf_and_html_with_every_figure_and_nothing_remote(out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from crfstudy.plotting import show_grid
    from crfstudy.repro import paper, report

    for k in range(3):
        fig, ax = plt.subplots(figsize=(3, 3))
        show_grid(ax, np.linspace(0, 1, 16).reshape(4, 4) ** (k + 1), f"grid {k}", cells=True)
        report.save_figure(fig, f"fig_demo{k}")
        plt.close(fig)
        assert (out / "figures" / f"fig_demo{k}.pdf").read_bytes().startswith(b"%PDF")  # the vector copy
    report.save_numbers("demo", {"mse": 0.01234})
    report.save_table("table_demo", ["a", "b"], [[1, 0.5]])
    template = out / "t.md"
    template.write_text("# A title\n\nMSE {{number:demo.mse|.3f}}.\n\n{{table:table_demo}}\n\n"
                        + "\n\n".join(f"{{{{figure:fig_demo{k}|Fig. {k}: a demo grid number {k}}}}}" for k in range(3))
                        + "\n\n---\n")
    md = paper.build_paper(template, out / "paper" / "generated" / "paper.md", strict=False)  # demo results come from no notebook
    pdf, html, typ = md.with_suffix(".pdf"), md.with_suffix(".html"), md.with_suffix(".typ")
    assert pdf.read_bytes().startswith(b"%PDF") and pdf_image_count(pdf) == 3
    page = html.read_text()
    assert page.count("data:image/png;base64,") == 3 and "Fig. 2: a demo grid number 2" in page
    assert "<figcaption" in page  # a real caption, not only alt text
    remote = re.findall(r"(?:src|href)=\"(https?://[^\"]+)\"", page)
    assert not remote, remote  # standalone: nothing is loaded from elsewhere
    source = typ.read_text()
    assert "@preview" not in source and "#import" not in source  # Typst would download packages
    assert "0.012" in source


def test_publish_names_a_missing_report(out):
    from crfmap.errors import InputError
    from crfstudy.repro.publish import publish

    with pytest.raises(InputError, match="no rendered report"):
        publish(out / "nothing.md")


def test_the_generated_pdf_contains_every_figure():
    """After `make reproduce`: as many images in paper.pdf as figures the report placed."""
    from crfstudy import paths

    md = paths.GENERATED / "paper.md"
    pdf = md.with_suffix(".pdf")
    if not (md.exists() and pdf.exists()):
        pytest.skip("no generated paper here (run make reproduce)")
    placed = re.findall(r"\]\(([^()\s]+\.png)\)", md.read_text())  # captions may hold brackets themselves
    assert placed and pdf_image_count(pdf) == len(placed)


MAIN_TEXT_PAGES = 15  # issue 23: at most 15 pages of main text, the rest in the appendix of the same PDF


def test_the_generated_main_text_fits_its_page_budget():
    """After `make reproduce`: Appendix A, the first page after the main text, starts on page 16 at the latest."""
    from pypdf import PdfReader

    from crfstudy import paths

    pdf = paths.GENERATED / "paper.pdf"
    if not pdf.exists():
        pytest.skip("no generated paper here (run make reproduce)")
    if pdf.stat().st_mtime < TEMPLATE.stat().st_mtime:
        pytest.skip("paper.pdf is older than paper/paper.md: it shows an earlier text (run make reproduce)")
    assert "## Appendix A" in TEMPLATE.read_text()
    pages = PdfReader(str(pdf)).pages
    first = next((i for i, page in enumerate(pages)
                  if re.search(r"^\s*Appendix A:", page.extract_text() or "", re.M)), None)
    assert first is not None, "no page of paper.pdf starts Appendix A"
    assert first <= MAIN_TEXT_PAGES, f"the main text takes {first} pages (at most {MAIN_TEXT_PAGES})"
