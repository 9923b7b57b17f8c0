"""crfmap: clean and complete robot occupancy grids with Conditional Random Fields.

An occupancy grid becomes a CRF (a hidden 4-connected lattice of binary cells plus an
observed layer holding the grid's P(occupied)); loopy belief propagation infers each
cell's occupancy from its neighbours; the potentials can be learned.
"""
from crfmap import _numba_cache  # noqa: F401  (first: a read-only install caches kernels in a user folder)
from crfmap.environment import check_numba_threads_at_numba_import, quiet_openmp_threads
from crfmap.errors import CrfmapError, InputError, DataMissingError
from crfmap.grid import OccupancyGrid, UNKNOWN

__all__ = ["CrfmapError", "InputError", "DataMissingError", "OccupancyGrid", "UNKNOWN"]
__version__ = "0.1.0"

check_numba_threads_at_numba_import()  # numba reads NUMBA_NUM_THREADS once, at its import: checked then
quiet_openmp_threads()  # before numba starts OpenMP's threads, which read it then
