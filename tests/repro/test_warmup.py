"""The numba cache warm-up: knows when the cache is cold, and when it has nothing to do."""
from crfmap.repro import warmup


def test_an_empty_cache_is_cold_and_a_fresh_stamp_is_warm(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    assert warmup.is_cold() and not warmup.is_warm()
    (tmp_path / "cache").mkdir()
    (tmp_path / "cache" / "crfmap-warmed.stamp").touch()
    assert warmup.is_warm()  # newer than every source crfmap infer runs
    for relative in warmup.KERNEL_MODULES:  # an index newer than its source: that module is cached
        (tmp_path / "cache" / f"{relative.split('/')[-1][:-3]}.kernel-1.py311.nbi").touch()
    assert not warmup.is_cold()
