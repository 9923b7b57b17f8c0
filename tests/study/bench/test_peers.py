"""Benchmark rows of the published peers: one record per recording and method, skipped recordings named."""
import numpy as np

from crfstudy.bench import peers as bench_peers_module


def _tiny_log(path, n_scans=8):
    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    lines = []
    for i in range(n_scans):
        yaw = 2 * np.pi * i / n_scans
        a = angles + yaw
        with np.errstate(divide="ignore"):
            tx = np.where(np.cos(a) > 0, 1.45 / np.cos(a), -1.45 / np.cos(a))
            ty = np.where(np.sin(a) > 0, 0.95 / np.sin(a), -0.95 / np.sin(a))
        r = " ".join(f"{v:.3f}" for v in np.minimum(np.abs(tx), np.abs(ty)))
        lines.append(f"FLASER 181 {r} 1.5 1.0 {yaw:.4f} 1.5 1.0 {yaw:.4f} {i:.1f} host {i:.1f}")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


def test_records_per_method_and_skips(tmp_path, monkeypatch):
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))
    _tiny_log(tmp_path / "carmen" / "room.log")
    monkeypatch.setattr(bench_peers_module, "RECORDINGS", {"room": "carmen/room.log", "gone": "carmen/gone.log"})
    records = bench_peers_module.bench_peers(quick=False, resolution=0.1)
    room = [r for r in records if r["method"] == "peers-room"]
    from crfmap.assess.peers import PEERS
    from crfmap.crf.presets import DEFAULT_PRESET

    assert {r["peer"] for r in room} == set(PEERS) | {DEFAULT_PRESET}
    assert all(r["seconds"] >= 0 and r["scans"] == 4 for r in room)
    gone = [r for r in records if r["method"] == "peers-gone"]
    assert len(gone) == 1 and "not found" in gone[0]["note"]
