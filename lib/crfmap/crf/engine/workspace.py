"""Reusable buffers for :func:`crfmap.crf.inference.lbp.infer` on large grids: no fresh memory per call.

Fresh memory costs a page fault per page: on large grids ``infer`` spent longer faulting its buffers in than
iterating. So the whole-grid fast path takes its planes and beliefs from here: the last call's buffers of that shape
and dtype when nothing else holds them (by reference count: a result kept, even through a view, keeps its buffers),
else new ones, kept until :func:`release_workspace`. Grids under :data:`WORKSPACE_MIN_CELLS` always get new ones.

>>> a = beliefs_buffer((2048, 1024)); b = beliefs_buffer((2048, 1024))
>>> a is b  # the first is still held (by ``a``)
False
>>> del a, b
>>> beliefs_buffer((2048, 1024)).shape
(2048, 1024)
>>> release_workspace()
"""
from __future__ import annotations

import sys

import numpy as np

WORKSPACE_MIN_CELLS = 1 << 20  # smaller grids allocate afresh (cheap, and no memory kept)
_CACHE: dict = {}  # name -> array of the last large grid
_FREE_REFCOUNT = 3  # sys.getrefcount(old) of an array only _CACHE holds (the dict, ``old``, the argument)


def _buffer(name, shape, dtype) -> np.ndarray:
    shape, dtype = tuple(int(n) for n in shape), np.dtype(dtype)
    if int(np.prod(shape)) < WORKSPACE_MIN_CELLS:
        return np.empty(shape, dtype)
    old = _CACHE.get(name)
    if old is not None and old.shape == shape and old.dtype == dtype and sys.getrefcount(old) == _FREE_REFCOUNT:
        return old
    _CACHE[name] = np.empty(shape, dtype)  # a buffer still held elsewhere stays with its holder
    return _CACHE[name]


def beliefs_buffer(shape) -> np.ndarray:
    """A float64 array of ``shape`` (contents undefined) for beliefs, reused when free."""
    return _buffer("beliefs", shape, np.float64)


def packed_arrays(msg_shape, un_shape, dtype):
    """(msg, un) planes for :class:`crfmap.crf.engine.packed.PackedBlock` (contents undefined), reused when free."""
    return _buffer("msg", msg_shape, dtype), _buffer("un", un_shape, dtype)


def release_workspace() -> None:
    """Drop the kept buffers (their memory is freed once no result holds them)."""
    _CACHE.clear()
