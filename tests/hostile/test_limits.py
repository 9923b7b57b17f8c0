"""The size limit is documented, refuses before allocating, and can be raised (crfmap --max-cells, CRFMAP_MAX_CELLS)."""
from pathlib import Path

from crfmap.cli import main
from fixtures import good_map, good_npy, png_header_only


def test_max_cells_option_raises_and_lowers_the_limit(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("CRFMAP_MAX_CELLS", raising=False)
    src = good_map(tmp_path)  # 8 x 6 = 48 cells
    assert main(["--max-cells", "40", "infer", str(src), str(tmp_path / "o.npy")]) == 2
    err = capsys.readouterr().err
    assert "48 cells" in err and "--max-cells" in err and not (tmp_path / "o.npy").exists()
    assert main(["--max-cells", "48", "infer", str(src), str(tmp_path / "o.npy")]) == 0
    assert "CRFMAP_MAX_CELLS" not in __import__("os").environ  # the option does not outlive the run


def test_env_limit_applies_to_npy_headers(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "10")
    src = good_npy(tmp_path)
    assert main(["infer", str(src), str(tmp_path / "o.npy")]) == 2
    assert "exceeds the limit of 10 cells" in capsys.readouterr().err


def test_default_limit_refuses_a_header_only_giant_png(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("CRFMAP_MAX_CELLS", raising=False)
    png_header_only(tmp_path / "big.png", 20000, 20000)
    (tmp_path / "m.yaml").write_text("image: big.png\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    assert main(["infer", str(tmp_path / "m.yaml"), str(tmp_path / "o.npy")]) == 2
    err = capsys.readouterr().err
    assert "20000 x 20000 image (400,000,000 cells) exceeds the limit of 100,000,000 cells" in err
    assert Path(tmp_path / "big.png").name in err
