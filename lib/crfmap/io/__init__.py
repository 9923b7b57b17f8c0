"""Files in and out: ROS 1/2 bags, CARMEN logs, map_server maps, exact .npy grids, atomic writes.

Public API (imported on first use, so ``import crfmap.io`` stays cheap):

- :mod:`crfmap.io.bag_reader`: ``read_bag``
- :mod:`crfmap.io.bag_writer`: ``write_bag`` (the files as rosbag and each distro's rosbag2 lay them out:
  :mod:`crfmap.io.rosbag1_files`, :mod:`crfmap.io.rosbag2_files`)
- :mod:`crfmap.io.carmen`: ``read_carmen``
- :mod:`crfmap.io.recordings`: ``load_recording`` (a CARMEN log or a bag, told apart by the suffix)
- :mod:`crfmap.io.map_server`: ``load_map``, ``save_map``, ``read_map_yaml``, ``map_yaml_text``
- :mod:`crfmap.io.grid_files`: ``load_grid``, ``save_grid`` (by suffix)
- :mod:`crfmap.io.nav2_loader`: nav2's per-pixel map loading rules (Humble, Jazzy+)
- :mod:`crfmap.io.nav2_costmap`: ``nav2_counts``, ``static_layer_costs`` (what nav2's costmap makes of a map)
- :mod:`crfmap.io.npy_grid`: ``load_npy``, ``save_npy``, ``npy_sidecar_path``
- :mod:`crfmap.io.atomic`: ``atomic_path``, ``atomic_dir``
- ``read_yaml``: a small YAML file read as strictly as a map YAML (no aliases, bounded nesting and size)
"""
from __future__ import annotations

from crfmap.lazy import attach

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
