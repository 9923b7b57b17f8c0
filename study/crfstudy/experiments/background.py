"""Ising models for the background chapter (thesis sec. 2.5, Fig. 5 and 6): samples and exact laws.

Spins ``s_i`` in {-1, +1} sit on a 1-D chain or a 2-D lattice with free boundaries and
nearest-neighbour bonds. The thesis writes the energy ``U(w) = -J sum_<ij> s_i s_j - mH sum_i s_i``;
with the temperature folded into the two constants (``coupling = J / kT``, ``field = mH / kT``) the
law is

    P(s) = exp(-U(s)) / Z,   U(s) = -coupling * sum_<ij> s_i s_j - field * sum_i s_i.

:func:`gibbs_ising` samples it by Gibbs sampling with checkerboard updates: cells of one colour
(even or odd index sum) share no bond, so given the other colour they are independent and can
all be redrawn at once from their exact conditionals -- a valid Gibbs sweep in two vectorised
steps. :func:`ising_exact` enumerates the law of a tiny model (the reference the sampler is
tested against). A positive coupling makes neighbours agree (ferromagnet; the 2-D lattice orders
above ``coupling ~ 0.4407``, Onsager's critical value), a negative one makes them disagree.

>>> s = gibbs_ising(8, coupling=0.5, sweeps=10, seed=0)
>>> s.shape, set(s.tolist()) <= {-1, 1}
((8,), True)
"""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.checks import check_number
from crfmap.errors import InputError

MAX_EXACT_SITES = 20  # ising_exact enumerates 2**sites states


def _check_shape(shape) -> tuple:
    if isinstance(shape, (int, np.integer)) and not isinstance(shape, bool):
        shape = (int(shape),)
    try:
        shape = tuple(int(n) for n in shape)
    except (TypeError, ValueError):
        raise InputError("shape", f"expected an int or a tuple of 1 or 2 ints, got {shape!r}") from None
    if len(shape) not in (1, 2) or min(shape) < 1:
        raise InputError("shape", f"expected a 1-D or 2-D lattice of at least one site, got {shape!r}")
    return shape


def _neighbour_sum(spins: np.ndarray, ndim: int, dtype=np.float64) -> np.ndarray:
    """Sum of each site's lattice neighbours over the last ``ndim`` axes (free boundaries)."""
    total = np.zeros(spins.shape, dtype=dtype)
    for axis in range(spins.ndim - ndim, spins.ndim):
        n = spins.shape[axis]
        if n < 2:
            continue
        head = [slice(None)] * spins.ndim
        tail = [slice(None)] * spins.ndim
        head[axis], tail[axis] = slice(1, n), slice(0, n - 1)
        head, tail = tuple(head), tuple(tail)
        total[head] += spins[tail]  # the neighbour below / to the left
        total[tail] += spins[head]  # the neighbour above / to the right
    return total


def ising_energy(spins, coupling=1.0, field=0.0) -> float:
    """The thesis's energy ``U = -coupling * sum_<ij> s_i s_j - field * sum_i s_i`` of one configuration.

    >>> ising_energy([1, 1, -1], coupling=1.0, field=0.5)
    -0.5
    """
    s = np.asarray(spins)
    if s.ndim not in (1, 2) or s.size == 0 or not np.isin(s, (-1, 1)).all():
        raise InputError("spins", "expected a non-empty 1-D or 2-D array of -1/+1 spins")
    s = s.astype(np.float64)
    bonds = float((s * _neighbour_sum(s, s.ndim)).sum()) / 2.0  # each bond counted from both ends
    return -check_number("coupling", coupling) * bonds - check_number("field", field) * float(s.sum())


def ising_exact(shape, coupling=1.0, field=0.0):
    """Every configuration of a tiny Ising model and its exact probability.

    Returns
    -------
    states : int8 array (2**sites, *shape) of -1/+1
    probability : float64 array (2**sites,), summing to 1

    >>> states, p = ising_exact(2, coupling=0.0)
    >>> p.round(2).tolist()
    [0.25, 0.25, 0.25, 0.25]
    """
    shape = _check_shape(shape)
    coupling = check_number("coupling", coupling)
    field = check_number("field", field)
    n = int(np.prod(shape))
    if n > MAX_EXACT_SITES:
        raise InputError("shape", f"{n} sites is too many to enumerate (at most {MAX_EXACT_SITES})")
    bits = (np.arange(2**n)[:, None] >> np.arange(n)[None, :]) & 1
    states = (2 * bits - 1).astype(np.int8).reshape((2**n,) + shape)
    s = states.astype(np.float64)
    axes = tuple(range(1, s.ndim))
    bonds = (s * _neighbour_sum(s, len(shape))).sum(axis=axes) / 2.0
    log_w = coupling * bonds + field * s.sum(axis=axes)  # = -U
    w = np.exp(log_w - log_w.max())
    return states, w / w.sum()


def gibbs_ising(shape, coupling=1.0, field=0.0, *, sweeps=100, chains=None, seed=0, initial=None,
                progress=False) -> np.ndarray:
    """Sample an Ising model by Gibbs sampling with checkerboard (two-colour) sweeps.

    Parameters
    ----------
    shape : int or (height, width)
        A chain of ``shape`` sites, or a 2-D lattice indexed [y, x].
    coupling, field : float
        ``J / kT`` and ``mH / kT`` of the thesis's energy (see the module docstring).
    sweeps : int
        Full sweeps (every site redrawn once per sweep).
    chains : int or None
        Run this many independent chains at once (result gets a leading axis of that length).
    seed : int
        For ``np.random.default_rng``; the start is uniformly random unless ``initial`` is given.
    initial : array of -1/+1 or None
        Starting configuration, shape ``shape`` (or (chains, *shape)).
    progress : bool
        Show a tqdm bar over the sweeps.

    Returns
    -------
    int8 array of -1/+1, shape ``shape`` or ``(chains, *shape)``: the configuration after the last sweep.

    Examples
    --------
    >>> s = gibbs_ising((16, 16), coupling=1.0, sweeps=200, seed=1)
    >>> bool(np.mean(s[:, 1:] == s[:, :-1]) > 0.9)  # far below the critical temperature neighbours agree
    True
    """
    shape = _check_shape(shape)
    coupling = check_number("coupling", coupling)
    field = check_number("field", field)
    if not (isinstance(sweeps, (int, np.integer)) and sweeps >= 0):
        raise InputError("sweeps", f"must be a non-negative integer, got {sweeps!r}")
    if chains is not None and not (isinstance(chains, (int, np.integer)) and chains >= 1):
        raise InputError("chains", f"must be a positive integer or None, got {chains!r}")
    full = shape if chains is None else (int(chains),) + shape
    rng = np.random.default_rng(seed)
    if initial is None:
        spins = np.where(rng.random(full) < 0.5, 1, -1).astype(np.int8)
    else:
        spins = np.asarray(initial)
        if spins.shape == shape and chains is not None:
            spins = np.broadcast_to(spins, full)
        if spins.shape != full or not np.isin(spins, (-1, 1)).all():
            raise InputError("initial", f"expected -1/+1 spins of shape {full}, got shape {spins.shape}")
        spins = spins.astype(np.int8, copy=True)
    # P(s_i = +1 | neighbours) = e^local / (e^local + e^-local), local = J * (neighbour sum) + h: the sum takes
    # only the 4 * ndim + 1 values -2 ndim .. 2 ndim, so the probabilities are a table (no tanh per site)
    reach = 2 * len(shape)
    p_up = 0.5 * (1.0 + np.tanh(coupling * np.arange(-reach, reach + 1, dtype=np.float64) + field))
    lattice = spins.reshape((-1,) + ((1,) if len(shape) == 1 else ()) + shape)  # (chains, height, width), a view
    from tqdm.auto import tqdm

    for _ in tqdm(range(sweeps), desc="Gibbs sweeps", disable=not progress, leave=False):
        for colour in (0, 1):
            # one uniform per site, every site (the other colour's are drawn and unused): the stream of draws,
            # and so every sample for a seed, stays what the vectorised sampler this kernel replaced drew
            uniform = rng.random(full).reshape(lattice.shape)
            _redraw_colour(lattice, uniform, p_up, colour)
    return spins


@njit(cache=True, nogil=True)
def _redraw_colour(spins, uniform, p_up, colour):
    """Redraw, in place, every site of one colour ((y + x) % 2) of (chains, height, width) spins from its conditional:
    +1 where its uniform is below p_up[neighbour sum + reach]. The other colour's sites, its only neighbours, stay."""
    chains, h, w = spins.shape
    reach = (len(p_up) - 1) // 2
    for c in range(chains):
        for y in range(h):
            for x in range((y + colour) % 2, w, 2):
                level = reach
                if y > 0:
                    level += spins[c, y - 1, x]
                if y + 1 < h:
                    level += spins[c, y + 1, x]
                if x > 0:
                    level += spins[c, y, x - 1]
                if x + 1 < w:
                    level += spins[c, y, x + 1]
                spins[c, y, x] = 1 if uniform[c, y, x] < p_up[level] else -1
