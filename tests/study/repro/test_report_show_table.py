from crfstudy import paths
from crfstudy.repro.report import save_table, show_table


def test_show_table_renders_the_saved_markdown(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "GENERATED", tmp_path)
    path = save_table("t", ["setting", "MSE"], [["plain", 0.021912345], ["learned", 0.0197]], caption="A caption.")
    shown = show_table("t")
    assert type(shown).__name__ == "Markdown" and hasattr(shown, "_repr_markdown_")
    assert shown.data == path.read_text()
    assert "A caption.\n\n| setting | MSE |" in shown.data and "| plain | 0.0219 |" in shown.data
    assert show_table(path).data == shown.data
