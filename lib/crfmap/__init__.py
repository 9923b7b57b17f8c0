"""crfmap: clean and complete robot occupancy grids with Conditional Random Fields.

An occupancy grid becomes a CRF (a hidden 4-connected lattice of binary cells plus an observed layer holding the
grid's P(occupied)); loopy belief propagation infers each cell's occupancy from its neighbours. Importing crfmap
changes nothing in the process; :func:`prepare` (optional) checks the environment variables crfmap and numba read and
readies numba's cache where the install is read-only.
"""
from crfmap.environment import prepare
from crfmap.errors import CrfmapError, InputError, DataMissingError
from crfmap.grid import OccupancyGrid, UNKNOWN

__all__ = ["CrfmapError", "InputError", "DataMissingError", "OccupancyGrid", "UNKNOWN", "prepare"]
__version__ = "0.1.0"
