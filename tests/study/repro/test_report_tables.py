"""Generated Markdown tables keep one cell per column: a "|" inside a cell is escaped, never raw."""
import re

import pytest

from crfstudy.repro.report import escape_cell, markdown_table

RAW_BAR = re.compile(r"(?<!\\)\|")


def cells_per_row(table_text: str) -> list:
    """The number of cells of each table row (raw bars counted, escaped ones not)."""
    return [len(RAW_BAR.findall(line)) - 1 for line in table_text.splitlines() if line.startswith("|")]


def test_a_bar_inside_a_cell_is_escaped():
    text = markdown_table(["P(C = occ | N)", "x"], [["a | b", 0.5], ["already \\| escaped", "line\nbreak"]])
    assert cells_per_row(text) == [2, 2, 2, 2]
    assert "P(C = occ \\| N)" in text and "already \\| escaped" in text and "line break" in text
    assert escape_cell("no bar") == "no bar"


def test_pandoc_reads_an_escaped_bar_as_text():
    pypandoc = pytest.importorskip("pypandoc")
    html = pypandoc.convert_text(markdown_table(["P(a | b)", "x"], [["1 | 2", 3]]), "html", format="markdown")
    assert html.count("<th>") == 2 and html.count("<td>") == 2 and "1 | 2" in html


def test_every_generated_table_has_one_cell_per_column():
    """After `make reproduce`: no table in paper/generated splits a row with a raw "|"."""
    from crfstudy import paths

    tables = sorted(p for p in paths.GENERATED.glob("*.md") if p.name != "paper.md")
    if not tables:
        pytest.skip("no generated tables here (run make reproduce)")
    bad = [p.name for p in tables if len(set(cells_per_row(p.read_text()))) > 1]
    assert not bad, f"tables whose rows differ in cell count (a raw '|' in a cell?): {bad}"


def test_pandoc_reads_a_lone_backslash_as_text():
    pypandoc = pytest.importorskip("pypandoc")
    text = markdown_table(["learned on \\ scored on", "x"], [["a \\| b", 1]])
    html = pypandoc.convert_text(text, "html", format="markdown")
    assert "learned on \\ scored on" in html and html.count("<td>") == 2
