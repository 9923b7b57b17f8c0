"""Render the reproduction report from its template and the generated figures and tables.

The template ``paper/paper.md`` holds the prose; placeholders pull in what the notebooks made,
so a number in the report is always the one the code produced:

- ``{{table:NAME}}``: the Markdown table ``paper/generated/NAME.md``;
- ``{{figure:NAME|caption}}``: the image ``figures/NAME.png``; ``{{figure:NAME|caption|width=60%}}``
  gives its width on the page (a one-panel figure need not fill the text width);
- ``{{number:NAME.key.subkey|fmt}}``: a value from ``paper/generated/NAME.json`` (``fmt`` e.g. ``.4f``);
- ``{{missed:NAME}}``: the rows of the generated table ``NAME`` (with "value" and "goal" columns)
  whose value misses its goal (:func:`missed_goals`), as prose;
- ``{{build:KEY.subkey|fmt}}``: a fact about the build itself (package versions, hardware, data
  checksums, seeds, the last run's wall clock), read when the paper is built (:mod:`crfstudy.repro.buildinfo`).

HTML comments (``<!-- ... -->``) are notes for the authors: they are removed before anything is filled,
so a placeholder or a TODO inside one never reaches the report.

The result is ``paper/generated/paper.md``. The paper is built only from full default runs, complete: with
``strict`` (the default, and what the workflow's paper rule runs) a result made by a quick run or with non-default
parameters (:func:`crfstudy.repro.provenance.problem`) stops the build with one line naming the file, a placeholder
whose number, table, figure or build fact was not generated stops it with one line naming each missing item
(:class:`ReportIncomplete`: a report with a hole is not a report), and so does a main text longer than
:data:`WORD_LIMIT` words (:func:`main_text_words`). A draft (``strict=False``) renders each missing item as a
visible "not generated" note and lists them at the end. ``python -m crfstudy.repro.paper`` is the strict build on the
command line (exit status 2 and one stderr line per problem on a refusal).

The speed goals table's ``make reproduce`` row is written by notebook 09 from the record of a run that finished
before it, which a fresh clone does not have; the build replaces it with this run's own time
(:func:`this_run_row`).
"""
from __future__ import annotations

import json
import os
import re
from pathlib import Path
import sys
import time
import argparse

from crfstudy import paths
from crfmap.crf.presets import DEFAULT_PRESET
from crfmap.errors import CrfmapError, InputError, one_line
from crfmap.io.atomic import atomic_path
from crfstudy.repro import provenance
from crfstudy.repro.variables import reproduce_started

COMMENT = re.compile(r"<!--.*?-->\n?", re.S)
PLACEHOLDER = re.compile(r"\{\{(table|figure|number|build|missed):([^}|]+)(?:\|([^}]*))?\}\}")


def _relative(target: Path, start: Path) -> str:
    return Path(os.path.relpath(target, start)).as_posix()


WORD_LIMIT = 8000  # words of the main text (everything before the appendix), the report's own limit
APPENDIX = re.compile(r"^## Appendix", re.M)
_RAW_BLOCK = re.compile(r"^```.*?^```\s*$", re.M | re.S)  # raw Typst and code blocks: layout, not text
_IMAGE = re.compile(r"!\[([^\]]*)\]\([^)]*\)(\{[^}]*\})?")  # an image counts by its caption
_TABLE_RULE = re.compile(r"^\|?[\s:|-]+\|[\s:|-]*$", re.M)  # a table's |---|---| line


class ReportIncomplete(CrfmapError):
    """The strict build met placeholders whose results were not generated; ``missing`` names each."""

    def __init__(self, missing):
        self.missing = list(missing)
        super().__init__("; ".join(self.missing))


def main_text_words(markdown: str) -> int:
    r"""Words of a report's main text: everything before its first "## Appendix" heading, as a reader counts them.

    Prose, headings, table cells and figure captions count (a word is a run of characters between spaces, the
    way ``wc -w`` counts the PDF's text); raw Typst and code blocks, image paths, HTML comments and the "|"
    and "---" of tables do not.

    >>> main_text_words("# Title\n\nTwo words. ![A cap](f.png){width=5%}\n\n| a | b c |\n|---|---|\n"
    ...                 "<!-- not counted -->\n```{=typst}\n#set text(size: 8pt)\n```\n## Appendix A\nmore words")
    8
    """
    text = APPENDIX.split(COMMENT.sub("", markdown), maxsplit=1)[0]
    text = _TABLE_RULE.sub(" ", _IMAGE.sub(r"\1", _RAW_BLOCK.sub(" ", text)))
    return len([w for w in text.replace("|", " ").split() if w.strip("#*-_>")])


_REPRODUCE_ROW = "make reproduce, previous run"


def this_run_row(cells: list, seconds: float | None, what: str) -> list:
    """A speed goals row (measurement, grid, value, goal) of ``make reproduce`` with this run's ``seconds``.

    Rows of other measurements, and any row when ``seconds`` is None, come back unchanged.

    >>> this_run_row(["make reproduce, previous run, notebooks summed [s]", "", None, "<= 300"], 251.4,
    ...              "from its start to this report")
    ['make reproduce, this run, from its start to this report [s]', '', 251, '<= 300']
    >>> this_run_row(["kernel [Mcell/s]", "512^2", 1394, ">= 1000"], 251.4, "x")[2]
    1394
    """
    if seconds is None or not str(cells[0]).startswith(_REPRODUCE_ROW):
        return cells
    return [f"make reproduce, this run, {what} [s]", cells[1], round(seconds), *cells[3:]]


def this_run_seconds(notebook_seconds: float | None = None) -> tuple:
    """(seconds, what) of this reproduction when the paper is built: the time since ``make reproduce`` started
    (``$CRFMAP_REPRODUCE_STARTED``, set by make), else the executed notebooks' summed run times, else (None, "")."""
    started = reproduce_started()
    if started is not None:
        return time.time() - started, "from its start to this report (venv, warm-up, notebooks)"
    if notebook_seconds:
        return float(notebook_seconds), "notebooks summed"
    return None, ""


_PREVIOUS_RUN_CAPTION = "row is read from the previous run's record"  # notebook 09's caption, true until replaced


def _this_run_table(text: str, seconds, what) -> str:
    """The speed goals Markdown table with its ``make reproduce`` row set to this run's time, and its caption
    saying so (notebook 09 wrote that the row is the previous run's).

    >>> print(_this_run_table("Goals (the make reproduce row is read from the previous run's record).\\n\\n"
    ...                       "| make reproduce, previous run, notebooks summed [s] |  | n/a | <= 300 |", 251.4, "x"))
    Goals (the make reproduce row is this run's own time, read when this report was built).
    <BLANKLINE>
    | make reproduce, this run, x [s] |  | 251 | <= 300 |
    """
    if seconds is None:
        return text
    lines = text.split("\n")
    replaced = False
    for i, line in enumerate(lines):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0].startswith(_REPRODUCE_ROW):
            lines[i] = "| " + " | ".join(str(c) for c in this_run_row(cells, seconds, what)) + " |"
            replaced = True
    text = "\n".join(lines)
    return text.replace(_PREVIOUS_RUN_CAPTION, "row is this run's own time, read when this report was built") \
        if replaced else text


def _check(path: Path, strict: bool) -> None:
    why = provenance.problem(path) if strict else None
    if why:
        raise InputError(path, why.split(": ", 1)[1])


# The short method and recording labels of the "beyond the thesis" results, and their names in the report.
METHOD_NAMES = {
    "raw": "raw grid", "logodds": "log-odds grid", "mean3x3": "3x3 mean", "median3x3": "3x3 median",
    "closing3x3": "3x3 closing", "thesis": "thesis tables", "graphcut": "graph cut",
    "certainty": "certainty preset", "certainty-MAP": "certainty preset, MAP",
    "certainty-T": "certainty preset, temperature", "gated": "gated preset",
    DEFAULT_PRESET: f"{DEFAULT_PRESET} preset (default)",
    "best-table": "oracle table", "table-from-training": "Intel's table",
    "hilbert": "Bayesian Hilbert map", "octomap": "OctoMap",
    "intel": "Intel", "aces": "ACES", "ros2": "ROS 2 bag", "ros1": "ROS 1 bag", "csail": "MIT CSAIL",
    "fr101": "Freiburg 101",
}


def _format_value(value, fmt=None) -> str:
    """A generated value as prose: ``fmt`` for numbers, lists as "a, b" ("none" when empty), None as "n/a".

    A list's labels are printed under their names in the report (:data:`METHOD_NAMES`).

    >>> _format_value(0.12345, ".3f"), _format_value(["best-table", "thesis"]), _format_value([])
    ('0.123', 'oracle table, thesis tables', 'none')
    """
    if value is None:
        return "n/a"
    if isinstance(value, list):
        return ", ".join(METHOD_NAMES.get(v, v) if isinstance(v, str) else _format_value(v, fmt)
                         for v in value) if value else "none"
    return format(value, fmt) if fmt else str(value)


def _whole_cells(table_text: str, names: dict) -> str:
    """A Markdown table with every cell whose whole text is a key of ``names`` replaced by its value."""
    def row(line):
        if not line.startswith("|"):
            return line
        cells = line.split("|")
        return "|".join(f" {names[c.strip()]} " if c.strip() in names else c for c in cells)

    return "\n".join(row(line) for line in table_text.split("\n"))


def method_names(table_text: str) -> str:
    """A "beyond the thesis" or navigation table with its method and recording labels (whole cells) under their
    report names.

    >>> method_names("| recording | method |\\n|---|---|\\n| intel | best-table |")
    '| recording | method |\\n|---|---|\\n| Intel | oracle table |'
    """
    return _whole_cells(table_text, METHOD_NAMES)


# Whole cells that any generated table may hold, as the report prints them: a metric a notebook computed as NaN is
# undefined (precision when nothing is called occupied), printed "n/a" as the tables' other undefined values are; and
# the metric column's code names.
CELL_WORDS = {"nan": "n/a", "nan [nan, nan]": "n/a", "mse": "MSE", "recall_seen": "recall (seen cells)"}


def cell_words(table_text: str) -> str:
    """A generated table with its undefined values and metric code names in the report's words (:data:`CELL_WORDS`).

    >>> cell_words("| method | metric | precision |\\n|---|---|---|\\n| all free | recall_seen | nan [nan, nan] |")
    '| method | metric | precision |\\n|---|---|---|\\n| all free | recall (seen cells) | n/a |'
    """
    return _literal_dashes(_whole_cells(table_text, CELL_WORDS))


def _literal_dashes(table_text: str) -> str:
    """Table rows with "--" escaped: pandoc's typography printed a command's "--no-deps" with an en dash.

    >>> _literal_dashes("| note |\\n|---|\\n| pip install --no-deps x |")
    '| note |\\n|---|\\n| pip install \\\\-\\\\-no-deps x |'
    """
    return "\n".join(line if not line.startswith("|") or _TABLE_RULE.fullmatch(line) else line.replace("--", r"\-\-")
                     for line in table_text.split("\n"))


def attach_caption(table_text: str) -> str:
    """A saved table with its caption paragraph turned into the table's own caption (pandoc's "Table:" line).

    A caption written as a paragraph before the table can end a page with its table on the next; a
    table caption stays with its table (PDF: a table figure; HTML: ``<caption>``).

    >>> attach_caption("Table 1: the joint table.\\n\\n| a |\\n|---|\\n| 1 |\\n")
    '| a |\\n|---|\\n| 1 |\\n\\nTable: Table 1: the joint table.'
    """
    lines = table_text.strip("\n").splitlines()
    first_row = next((i for i, line in enumerate(lines) if line.startswith("|")), None)
    if not first_row:
        return "\n".join(lines)
    caption = " ".join(" ".join(lines[:first_row]).split())
    body = [line for line in lines[first_row:] if line.startswith("|")]
    rest = [line for line in lines[first_row:] if not line.startswith("|")]
    text = "\n".join(body) + f"\n\nTable: {caption}"
    return text + ("\n\n" + "\n".join(rest).strip() if any(r.strip() for r in rest) else "")


# Code names that generated tables carry (notebook labels, parameter names), and the plain words the report
# prints instead: a reader of the PDF should not need the library's identifiers. Longer names first.
PLAIN_WORDS = (
    ("crfmap.assess.learning.learn_thesis, ", ""),
    ("LBP crfstudy.references.reference_lbp", "LBP (crfmap's reference implementation)"),
    ("reference_lbp", "reference LBP"),
    ("learn_pseudolikelihood", "pseudo-likelihood learner"),
    ("learn_gradient", "gradient learner"),
    ("learn_thesis", "thesis learner"),
    ("schedule 'thesis', max_iter=1", "the thesis's schedule, one iteration"),
    ("the 'thesis' schedule", "the thesis's schedule"),
    ("p_hit = ", "P(hit) = "),
    ("p_miss = ", "P(miss) = "),
    ("logodds_limit = ", "log-odds limit = "),
    ("occupied_first", "occupied, first hit"),
    ("occupied_further", "occupied, further hits"),
    ("free_first", "free, first pass"),
    ("free_further", "free, further passes"),
    ("equal to build_grid cell for cell", "equal to the offline grid builder's, cell for cell"),
    ("noisy_image sigma", "noisy image, sigma"),
    ("(crfstudy.bench.goals; ", "("),
    (", crfmap.crf.inference.lbp.message", ", by crfmap's message function"),
    # the report's words for the tables' jargon (the glossary at the report's start)
    (" with the thesis's pairing (receiver) and the proper pairwise one (oriented)",
     " with the thesis's pairing and the proper pairwise one"),
    ("(receiver pairing)", "(thesis pairing)"),
    ("(oriented pairing)", "(pairwise pairing)"),
    (", oriented pairing", ", pairwise pairing"),
    ("search+gradient", "coarse search, then gradient"),
    ("(search + gradient, extra)", "(coarse search, then gradient; extra)"),
    ("(near known)", "(near observations)"),
    # notebook 12 names the tracker's issue; the reader knows the goals by the report's name for them
    ("Issue 38's goals for the default preset", "The navigation goals for the default preset"),
)


def plain_words(text: str) -> str:
    """A generated table with the library's code names replaced by the words the report uses.

    >>> plain_words("| After LBP (learn_thesis, converged) | 0.02 |")
    '| After LBP (thesis learner, converged) | 0.02 |'
    """
    for code, words in PLAIN_WORDS:
        text = text.replace(code, words)
    return text


_GOAL = re.compile(r"^\s*(>=|<=)\s*([0-9.eE+-]+)")


def missed_goals(header, rows) -> str:
    """The rows whose value misses its goal ("<= x" or ">= x"), as "what (grid): value, goal ..." clauses.

    Rows without a goal or a number are left out; "none" when every goal was met.

    >>> missed_goals(["measurement", "grid", "value", "goal"],
    ...              [["kernel [Mcell/s]", "512^2", 162, ">= 1000"], ["start [s]", "", 0.4, "<= 2"], ["x", "", None, "<= 1"]])
    'kernel [Mcell/s] (512^2): 162, goal >= 1000'
    """
    value_at, goal_at = header.index("value"), header.index("goal")
    label_at = [i for i in range(len(header)) if i not in (value_at, goal_at)]
    missed = []
    for row in rows:
        goal = _GOAL.match(str(row[goal_at] or ""))
        if not goal or not isinstance(row[value_at], (int, float)):
            continue
        value, bound = float(row[value_at]), float(goal.group(2))
        if (value < bound) if goal.group(1) == ">=" else (value > bound):
            label = " ".join(str(row[label_at[0]]).split())
            extra = ", ".join(str(row[i]) for i in label_at[1:] if row[i])
            missed.append(f"{label}{f' ({extra})' if extra else ''}: {row[value_at]:g}, goal {row[goal_at]}")
    return "; ".join(missed) or "none"


_SIZE = re.compile(r"^\s*width=\d+%\s*$")


def _split_size(text: str) -> tuple:
    """A figure placeholder's "caption|width=N%" as (caption, "width=N%"); no size: (caption, "").

    >>> _split_size("Fig. 20: the X.|width=45%"), _split_size("Fig. 2: a grid")
    (('Fig. 20: the X.', 'width=45%'), ('Fig. 2: a grid', ''))
    """
    caption, _, size = text.rpartition("|")
    return (caption, size.strip()) if caption and _SIZE.match(size) else (text, "")


def render(template: str, out_dir: Path, missing: list, strict: bool = False, run_seconds=None) -> str:
    """Fill the placeholders of ``template``; ``strict`` refuses results of quick or non-default runs.

    ``run_seconds``: this run's executed notebooks' summed time, for the speed goals' ``make reproduce`` row
    when make did not say when it started (:func:`this_run_seconds`).
    """
    build_facts: dict = {}
    this_run = this_run_seconds(run_seconds)

    def replace(match):
        kind, name, extra = match.group(1), match.group(2).strip(), match.group(3)
        if kind == "missed":
            f = paths.GENERATED / f"{name}.json"
            try:
                table = json.loads(f.read_text())
                rows = [this_run_row(row, *this_run) for row in table["rows"]]
                text = missed_goals(table["header"], rows)
            except (OSError, KeyError, ValueError):
                missing.append(f"goals of {name}")
                return f"*(goals of {name} not generated)*"
            _check(f, strict)
            return text
        if kind == "build":
            if not build_facts:
                from crfstudy.repro import buildinfo

                build_facts.update(buildinfo.describe())
            value = build_facts
            try:
                for k in name.split("."):
                    value = value[k]
            except (KeyError, TypeError):
                missing.append(f"build fact {name}")
                return f"*(build fact {name} not known)*"
            return _format_value(value, extra)
        if kind == "table":
            f = paths.GENERATED / f"{name}.md"
            if not f.exists():
                missing.append(f"table {name}")
                return f"*(table {name} not generated)*"
            _check(f, strict)
            text = cell_words(_this_run_table(plain_words(provenance.strip(f.read_text())), *this_run))
            return attach_caption(method_names(text) if name.startswith(("beyond", "navigation")) else text)
        if kind == "figure":
            f = paths.FIGURES / f"{name}.png"
            if not f.exists():
                missing.append(f"figure {name}")
                return f"*(figure {name} not generated)*"
            _check(f, strict)
            caption, size = _split_size(extra or name)
            return f"![{caption}]({_relative(f, out_dir)})" + (f"{{{size}}}" if size else "")
        file_name, *keys = name.split(".")
        f = paths.GENERATED / f"{file_name}.json"
        try:
            value = json.loads(f.read_text())
            for k in keys:
                value = value[int(k)] if isinstance(value, list) else value[k]
        except (OSError, KeyError, IndexError, ValueError):
            missing.append(f"number {name}")
            return f"*(number {name} not generated)*"
        _check(f, strict)
        if isinstance(value, dict):  # a mapping is a table, not a number: it must not reach the prose
            missing.append(f"number {name} (a mapping, not a value)")
            return f"*(number {name} is not a single value)*"
        return _format_value(value, extra)

    return PLACEHOLDER.sub(replace, COMMENT.sub("", template))


def build_paper(template: Path | None = None, output: Path | None = None, strict: bool = True,
                publish: bool = True, run_seconds: float | None = None, word_limit: int | None = WORD_LIMIT) -> Path:
    """Render the template into ``paper/generated/paper.md``; returns its path.

    With ``strict``, before anything is written: a quick or non-default result raises
    :class:`crfmap.errors.InputError` naming the file; placeholders whose results were not generated raise
    :class:`ReportIncomplete` naming each; a main text over ``word_limit`` words (:func:`main_text_words`; None:
    no limit) raises :class:`crfmap.errors.InputError`. Without it (a draft) missing items are marked in the text
    and listed at its end. ``publish=True`` also builds ``paper.pdf`` and ``paper.html`` beside it
    (:mod:`crfstudy.repro.publish`).
    """
    template = Path(template or paths.PAPER / "paper.md")
    output = Path(output or paths.GENERATED / "paper.md")
    missing: list = []
    text = render(template.read_text(), output.parent, missing, strict=strict, run_seconds=run_seconds)
    if strict and missing:
        raise ReportIncomplete(missing)
    words = main_text_words(text)
    if strict and word_limit is not None and words > word_limit:
        raise InputError(template, f"main text (before the appendix) has {words} words, over the limit of {word_limit}")
    if missing:
        text += "\n\n---\nNot generated when this report was built: " + ", ".join(missing) + "\n"
    with atomic_path(output) as tmp:
        Path(tmp).write_text(text)
    if publish:
        from crfstudy.repro.publish import publish as publish_paper

        publish_paper(output)
    return output


def main(argv=None) -> int:
    """``python -m crfstudy.repro.paper``: build the paper from full default runs (the workflow's paper rule)."""
    parser = argparse.ArgumentParser(prog="python -m crfstudy.repro.paper", description=main.__doc__)
    parser.add_argument("--template", type=Path, help="default: paper/paper.md")
    parser.add_argument("--output", type=Path, help="default: paper/generated/paper.md")
    parser.add_argument("--timings", type=Path, help="also write each notebook's run time here (JSON)")
    parser.add_argument("--executed", type=Path, nargs="*", default=[], help="the executed notebooks")
    args = parser.parse_args(argv)
    timings = notebook_timings(args.executed)
    try:
        out = build_paper(args.template, args.output, run_seconds=timings["total_seconds"] or None)
    except ReportIncomplete as error:
        for item in error.missing:
            print(f"paper: refused: not generated: {one_line(item)}", file=sys.stderr)
        return 2
    except InputError as error:
        print(f"paper: refused: {error}", file=sys.stderr)
        return 2
    if args.timings:
        write_timings(args.executed, args.timings)
    print(f"paper: {out}")
    return 0


def notebook_timings(executed) -> dict:
    """Each executed notebook's run time (papermill's record): ``{"seconds": {...}, "total_seconds": t}``."""
    seconds = {}
    for notebook in executed:
        meta = json.loads(Path(notebook).read_text()).get("metadata", {}).get("papermill", {})
        seconds[Path(notebook).name] = meta.get("duration")
    return {"seconds": seconds, "total_seconds": sum(v for v in seconds.values() if v)}


def write_timings(executed, target) -> dict:
    """Each executed notebook's run time (:func:`notebook_timings`) written to ``target`` as JSON."""
    timings = notebook_timings(executed)
    with atomic_path(Path(target)) as tmp:
        Path(tmp).write_text(json.dumps(timings, indent=2, sort_keys=True) + "\n")
    return timings


if __name__ == "__main__":
    sys.exit(main())
