"""The report pulls its numbers, tables and figures from generated files."""
import importlib
import json

import pytest


@pytest.fixture
def out(tmp_path, monkeypatch):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    import crfstudy.paths

    importlib.reload(crfstudy.paths)
    import crfstudy.repro.paper
    import crfstudy.repro.report

    importlib.reload(crfstudy.repro.report)
    importlib.reload(crfstudy.repro.paper)
    yield tmp_path
    monkeypatch.delenv("CRFMAP_OUTPUT_ROOT")
    importlib.reload(crfstudy.paths)
    importlib.reload(crfstudy.repro.report)
    importlib.reload(crfstudy.repro.paper)


@pytest.fixture
def default_run(monkeypatch):
    """Results saved as the workflow's default run of notebook 04 would save them."""
    monkeypatch.setenv("CRFMAP_RUN", json.dumps({"notebook": "04_denoising.ipynb", "parameters": {}}))


def test_placeholders_are_filled_from_generated_files(out, default_run):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crfstudy.repro import paper; from crfstudy.repro import report

    report.save_numbers("demo", {"mse": 0.01234, "nested": {"k": [1, 2.5]}})
    report.save_table("table_demo", ["a", "b"], [[1, 0.5], ["x", float("nan")]])
    fig, ax = plt.subplots()
    report.save_figure(fig, "fig_demo")
    plt.close(fig)
    template = out / "t.md"
    template.write_text("MSE {{number:demo.mse|.3f}}, k {{number:demo.nested.k.1}}\n{{table:table_demo}}\n"
                        "{{figure:fig_demo|A demo}}\n{{number:absent.x}}\n")
    result = paper.build_paper(template, out / "paper" / "generated" / "paper.md", strict=False).read_text()  # a draft
    assert "MSE 0.012, k 2.5" in result
    assert "| a | b |" in result and "| x | n/a |" in result
    assert "![A demo](../../figures/fig_demo.png)" in result
    assert "number absent.x not generated" in result and "Not generated when this report was built" in result


def _table(report, name="table14_denoising"):
    report.save_table(name, ["sigma", "MSE"], [[0.42, 0.083]])


@pytest.mark.parametrize("run, why", [
    ({"notebook": "04_denoising.ipynb", "parameters": {"quick": True}}, "quick run of 04_denoising.ipynb"),
    ({"notebook": "04_denoising.ipynb", "parameters": {"noise": 0.5}}, "non-default parameters noise=0.5 (default 0.42)"),
    ({"notebook": None, "parameters": {}}, "made outside a known notebook"),
])
def test_paper_refuses_a_quick_or_non_default_result_naming_the_file(out, monkeypatch, capsys, run, why):
    from crfstudy.repro import paper, report

    monkeypatch.setenv("CRFMAP_RUN", json.dumps({"notebook": "04_denoising.ipynb", "parameters": {}}))
    report.save_numbers("denoising", {"mse": 0.01})
    monkeypatch.setenv("CRFMAP_RUN", json.dumps(run))
    _table(report)
    template = out / "t.md"
    template.write_text("{{number:denoising.mse}}\n{{table:table14_denoising}}\n")
    target = out / "paper" / "generated" / "paper.md"
    assert paper.main(["--template", str(template), "--output", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "table14_denoising.md" in err[0] and why in err[0], err
    assert not target.exists()  # nothing written
    # the same file from a default run is accepted
    monkeypatch.setenv("CRFMAP_RUN", json.dumps({"notebook": "04_denoising.ipynb", "parameters": {}}))
    _table(report)
    assert paper.main(["--template", str(template), "--output", str(target)]) == 0
    assert "| 0.42 | 0.083 |" in target.read_text() and "provenance" not in target.read_text()


def test_a_result_without_a_run_record_is_refused(out):
    from crfmap.errors import InputError
    from crfstudy.repro import paper

    legacy = out / "paper" / "generated" / "old.md"
    legacy.parent.mkdir(parents=True)
    legacy.write_text("| a |\n|---|\n| 1 |\n")
    template = out / "t.md"
    template.write_text("{{table:old}}\n")
    with pytest.raises(InputError, match=r"old.md: records no run parameters"):
        paper.build_paper(template, out / "p.md")
    assert paper.build_paper(template, out / "p.md", strict=False).read_text().startswith("| a |")


def test_build_facts_fill_their_placeholders_and_comments_never_reach_the_report(out, monkeypatch):
    from crfstudy.repro import buildinfo, paper

    monkeypatch.setattr(buildinfo, "describe", lambda data=True: {"python": "3.11.7", "wall": "it took a while"})
    template = out / "t.md"
    template.write_text("Python {{build:python}}; {{build:wall}}.\n<!-- TODO(lead): {{table:absent}} -->\n"
                        "{{build:nothing.here}}\n")
    result = paper.build_paper(template, out / "p.md", publish=False, strict=False).read_text()
    assert result.startswith("Python 3.11.7; it took a while.\n")
    assert "TODO" not in result and "table absent" not in result  # the comment's placeholder was not filled
    assert "build fact nothing.here not known" in result and "Not generated when this report was built" in result


def test_build_facts_describe_this_environment(tmp_path):
    import platform

    from crfstudy.repro import buildinfo

    facts = buildinfo.describe(data=False)
    assert facts["python"] == platform.python_version() and facts["cores"] >= 1
    assert "numpy " in facts["versions"] and "10_beyond: seed = " in facts["seeds"]
    (tmp_path / "carmen").mkdir()
    (tmp_path / "carmen" / "intel-corrected.log.gz").write_bytes(b"abc")
    rows = {r[0]: r for r in buildinfo.data_files(tmp_path)}
    assert rows["carmen/intel-corrected.log.gz"][2] == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    assert rows["carmen/intel-corrected.log.gz"][1] == 0.003  # kB; a small file is not "0"
    assert rows["carmen/aces-corrected.log.gz"][2] == "missing"


def test_missed_goals_are_listed_from_the_generated_table(out, default_run):
    from crfstudy.repro import paper, report

    report.save_table("goals_demo", ["measurement", "value", "goal"],
                      [["kernel [Mcell/s]", 162, ">= 1000"], ["start [s]", 0.4, "<= 2"], ["redraw [s]", 0.5, "<= 0.3"]])
    template = out / "t.md"
    template.write_text("Missed: {{missed:goals_demo}}.\n")
    result = paper.build_paper(template, out / "p.md", publish=False).read_text()
    assert result == "Missed: kernel [Mcell/s]: 162, goal >= 1000; redraw [s]: 0.5, goal <= 0.3.\n"


def test_a_full_build_refuses_every_missing_item_one_line_each(out, default_run, capsys):
    from crfstudy.repro import paper, report

    report.save_numbers("demo", {"mse": 0.5})
    template = out / "t.md"
    template.write_text("{{number:demo.mse}} {{number:demo.absent}} {{number:nofile.x}}\n{{table:no_table}}\n"
                        "{{figure:no_figure|A missing figure}}\n{{missed:no_goals}}\n")
    target = out / "paper" / "generated" / "paper.md"
    assert paper.main(["--template", str(template), "--output", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["paper: refused: not generated: number demo.absent", "paper: refused: not generated: number nofile.x",
                   "paper: refused: not generated: table no_table", "paper: refused: not generated: figure no_figure",
                   "paper: refused: not generated: goals of no_goals"], err
    assert not target.exists()  # nothing written
    with pytest.raises(paper.ReportIncomplete) as refused:
        paper.build_paper(template, target, publish=False)
    assert refused.value.missing == ["number demo.absent", "number nofile.x", "table no_table", "figure no_figure",
                                     "goals of no_goals"]
    template.write_text("{{number:demo.mse}}\n")  # complete: built
    assert paper.main(["--template", str(template), "--output", str(target)]) == 0
    assert target.read_text().startswith("0.5\n")


def test_main_text_words_count_before_the_appendix_only():
    from crfstudy.repro.paper import main_text_words

    body = "one two three\n\n| cell a | cell b |\n|---|:---:|\n\n![Caption words here](x/y.png){width=50%}\n"
    assert main_text_words(body) == 3 + 4 + 3
    assert main_text_words(body + "## Appendix A: more\nnot counted at all\n") == 10
    assert main_text_words("<!-- a b c -->\n```{=typst}\n#set par(spacing: 1em)\n```\nword\n") == 1
    assert main_text_words("## Heading here\n- a list item\n") == 5


def test_a_full_build_refuses_a_main_text_over_the_word_limit(out):
    from crfmap.errors import InputError
    from crfstudy.repro import paper

    template = out / "t.md"
    template.write_text("word " * 30 + "\n\n## Appendix A\n" + "more " * 100 + "\n")
    with pytest.raises(InputError, match=r"main text \(before the appendix\) has 30 words, over the limit of 25"):
        paper.build_paper(template, out / "p.md", publish=False, word_limit=25)
    assert not (out / "p.md").exists()
    assert paper.build_paper(template, out / "p.md", publish=False, word_limit=30).exists()  # the appendix is free


def test_the_template_main_text_is_within_the_word_limit():
    """The report's prose before the appendix, each placeholder one word, leaves room for its generated tables."""
    import re
    from pathlib import Path

    from crfstudy.repro import paper

    text = (Path(__file__).resolve().parents[3] / "paper" / "paper.md").read_text()
    tables = len(re.findall(r"\{\{table:", paper.APPENDIX.split(text, 1)[0]))
    prose = paper.PLACEHOLDER.sub("x", text)
    # each main-text table is given 250 words (the largest there, Table 26 on common cells, has about 200)
    assert paper.main_text_words(prose) + 250 * tables <= paper.WORD_LIMIT, (paper.main_text_words(prose), tables)


def test_the_make_reproduce_row_is_this_run_not_the_previous_one(out, monkeypatch):
    from crfstudy.repro import paper, report

    monkeypatch.setenv("CRFMAP_RUN", json.dumps({"notebook": "09_speed.ipynb", "parameters": {}}))
    monkeypatch.delenv("CRFMAP_REPRODUCE_STARTED", raising=False)
    report.save_table("speed_goals", ["measurement", "grid", "value", "goal"],
                      [["kernel [Mcell/s]", "512^2", 1394, ">= 1000"],
                       ["make reproduce, previous run, notebooks summed [s]", "", None, "<= 300"]])
    executed = []
    for name, seconds in (("01_a.ipynb", 120.4), ("02_b.ipynb", 230.2)):
        nb = out / name
        nb.write_text(json.dumps({"metadata": {"papermill": {"duration": seconds}}}))
        executed.append(str(nb))
    template = out / "t.md"
    template.write_text("{{table:speed_goals}}\n\nMissed: {{missed:speed_goals}}.\n")
    target = out / "paper" / "generated" / "paper.md"
    assert paper.main(["--template", str(template), "--output", str(target), "--executed", *executed]) == 0
    text = target.read_text()
    assert "| make reproduce, this run, notebooks summed [s] |  | 351 | <= 300 |" in text and "n/a" not in text
    assert "Missed: make reproduce, this run, notebooks summed [s]: 351, goal <= 300." in text
    monkeypatch.setenv("CRFMAP_REPRODUCE_STARTED", "1000")  # make said when it started: the time since then
    seconds, what = paper.this_run_seconds(351)
    assert seconds > 1e9 and what.startswith("from its start to this report")
