"""The peers' scan-split rows: the same maps as the mapping functions, on the split's grid."""
import numpy as np
import pytest

from crfmap.assess.peers import OCTOMAP_INTEL, PEERS, peer_rows
from crfmap.assess.scansplit import ScanSplit, scan_split
from crfmap.errors import InputError
from crfmap.mapping.hilbert import hilbert_grid
from crfmap.mapping.octomap import octomap_grid
from crfmap.recording import ScanSet


def _scans(n=6, seed=0):
    rng = np.random.default_rng(seed)
    poses = np.column_stack([rng.uniform(1.8, 2.2, n), rng.uniform(1.8, 2.2, n), rng.uniform(-3, 3, n)])
    return ScanSet(rng.uniform(0.5, 1.5, (n, 30)).astype(np.float32), -np.pi / 2, np.pi / 29, 0.1, 5.0, poses,
                   np.arange(n, dtype=float))


def test_rows_are_the_mapping_functions_on_the_first_half():
    sp = scan_split(_scans(), 0.1)
    rows, seconds = peer_rows(sp)
    assert set(rows) == set(seconds) == set(PEERS) >= {"octomap", "octomap-defaults", "hilbert"}
    assert all(s >= 0 for s in seconds.values())
    np.testing.assert_array_equal(rows["octomap"],
                                  octomap_grid(sp.first_scans, 0.1, bounds=sp.bounds, **OCTOMAP_INTEL).probability)
    # the row is not OctoMap's library defaults (the constants searched on Intel differ from them)
    defaults = octomap_grid(sp.first_scans, 0.1, bounds=sp.bounds).probability
    assert not np.array_equal(rows["octomap"], defaults)
    np.testing.assert_array_equal(rows["octomap-defaults"], defaults)  # the other row: the library's defaults
    np.testing.assert_array_equal(rows["hilbert"], hilbert_grid(sp.first_scans, 0.1, sp.bounds).probability)
    assert all(r.shape == sp.shape for r in rows.values())


def test_errors_name_the_problem():
    sp = scan_split(_scans(), 0.1)
    with pytest.raises(InputError, match="nope"):
        peer_rows(sp, ["nope"])
    bare = ScanSplit(*(np.zeros((3, 3), int) for _ in range(4)))
    with pytest.raises(InputError, match="first half's scans"):
        peer_rows(bare, ["octomap"])


def test_every_peer_row_takes_the_same_arguments():
    import inspect

    from crfmap.assess import peers

    for name, row in peers._ROWS.items():  # peer_rows calls each the same way: (split, progress=...)
        parameters = inspect.signature(row).parameters
        assert list(parameters)[:2] == ["split", "progress"], name
        assert parameters["progress"].default is False, name
