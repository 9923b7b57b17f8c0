"""crfstudy.repro.reproduce: which notebooks need which shared data, and a clear stop when it is missing."""
from crfmap.data import data_root
from crfstudy.repro.dependencies import data_needed, notebooks
from crfstudy.repro.reproduce import main


def test_data_needed_lists_the_files_a_notebook_reads():
    (office,) = notebooks(["07"])
    assert data_needed(office) == ["carmen/intel-corrected.log.gz"]
    (denoising,) = notebooks(["04"])
    assert data_needed(denoising) == []


def test_missing_data_stops_before_anything_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path / "no-data"))
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path / "out"))
    assert main(["--quick", "--only", "03", "07", "--no-paper"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert any("intel-corrected.log.gz" in line and "03_simulator.ipynb, 07_office.ipynb" in line for line in err)
    assert any("macfirst_floor_take_2" in line and "download" in line for line in err)
    assert err[-1] == "reproduce: see data/README.md; nothing was run"
    assert not list((tmp_path / "out").rglob("*.ipynb"))
    assert data_root() == tmp_path / "no-data"
