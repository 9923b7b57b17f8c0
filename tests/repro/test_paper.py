"""The report pulls its numbers, tables and figures from generated files."""
import importlib

import pytest


@pytest.fixture
def out(tmp_path, monkeypatch):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    import crfmap.paths

    importlib.reload(crfmap.paths)
    import crfmap.repro.paper
    import crfmap.repro.report

    importlib.reload(crfmap.repro.report)
    importlib.reload(crfmap.repro.paper)
    yield tmp_path
    monkeypatch.delenv("CRFMAP_OUTPUT_ROOT")
    importlib.reload(crfmap.paths)
    importlib.reload(crfmap.repro.report)
    importlib.reload(crfmap.repro.paper)


def test_placeholders_are_filled_from_generated_files(out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crfmap.repro import paper; from crfmap.repro import report

    report.save_numbers("demo", {"mse": 0.01234, "nested": {"k": [1, 2.5]}})
    report.save_table("table_demo", ["a", "b"], [[1, 0.5], ["x", float("nan")]])
    fig, ax = plt.subplots()
    report.save_figure(fig, "fig_demo")
    plt.close(fig)
    template = out / "t.md"
    template.write_text("MSE {{number:demo.mse|.3f}}, k {{number:demo.nested.k.1}}\n{{table:table_demo}}\n"
                        "{{figure:fig_demo|A demo}}\n{{number:absent.x}}\n")
    result = paper.build_paper(template, out / "paper" / "generated" / "paper.md").read_text()
    assert "MSE 0.012, k 2.5" in result
    assert "| a | b |" in result and "| x | n/a |" in result
    assert "![A demo](../../figures/fig_demo.png)" in result
    assert "number absent.x not generated" in result and "Not generated when this report was built" in result
