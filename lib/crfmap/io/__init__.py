"""Files in and out: ROS 1/2 bags, CARMEN logs, map_server maps, exact .npy grids, atomic writes.

The files as rosbag and each distro's rosbag2 lay them out are :mod:`crfmap.io.rosbag1_files` and
:mod:`crfmap.io.rosbag2_files`; nav2's per-pixel map loading rules (Humble, Jazzy+) are :mod:`crfmap.io.nav2_loader`.

Public API (imported on first use, so ``import crfmap.io`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

_API = {
    "read_bag": "bag_reader",
    "write_bag": "bag_writer",
    "read_carmen": "carmen",
    "load_recording": "recordings",
    "load_map": "map_server",
    "save_map": "map_server",
    "load_grid": "grid_files",
    "save_grid": "grid_files",
    "read_map_yaml": "map_server",
    "map_yaml_text": "map_server",
    "load_npy": "npy_grid",
    "save_npy": "npy_grid",
    "npy_sidecar_path": "npy_grid",
    "nav2_counts": "nav2_costmap",
    "static_layer_costs": "nav2_costmap",
    "atomic_path": "atomic",
    "atomic_dir": "atomic",
    "read_yaml": "_yaml",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
__doc__ += api_listing(__name__, _API)
