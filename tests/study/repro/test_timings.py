"""crfstudy.repro.timings: the notebooks' slowest cells, read from papermill's per-cell durations."""
import json

import pytest

from crfstudy.repro.timings import slowest_cells, slowest_cells_table


def _notebook(path, durations):
    cells = [{"cell_type": "markdown", "metadata": {}, "source": "# title"}]
    for k, seconds in enumerate(durations):
        meta = {} if seconds is None else {"papermill": {"duration": seconds}}
        cells.append({"cell_type": "code", "metadata": meta, "source": [f"step_{k}()\n", "more()\n"]})
    path.write_text(json.dumps({"cells": cells, "metadata": {}}))


def test_slowest_cells_per_notebook_slowest_first(tmp_path):
    _notebook(tmp_path / "01_a.ipynb", [0.5, 3.0, None, 1.0, 9.0, 0.1, 2.0])
    _notebook(tmp_path / "02_b.ipynb", [4.0])
    rows = slowest_cells(tmp_path, n=3)
    assert rows == [("01_a", 5, 9.0, "step_4()"), ("01_a", 2, 3.0, "step_1()"), ("01_a", 7, 2.0, "step_6()"),
                    ("02_b", 1, 4.0, "step_0()")]
    table = slowest_cells_table(tmp_path, n=1)
    assert table.splitlines()[2] == "| 01_a | 5 | 9.0 | `step_4()` |" and len(table.splitlines()) == 4


def test_a_file_that_is_not_a_notebook_is_named(tmp_path):
    (tmp_path / "03_c.ipynb").write_text("{not json")
    with pytest.raises(ValueError, match="03_c.ipynb: not an executed notebook"):
        slowest_cells(tmp_path)
