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


# ---- the background notebook's loops and figures (notebook 01) -------------------------------------------------------
# The thesis's small examples, each a figure the notebook saves; the loops over seeds and grids live here so the
# notebook shows the calls and parameters, not the bookkeeping.

CRITICAL_COUPLING = float(np.log(1 + np.sqrt(2)) / 2)  # Onsager's critical coupling of the square lattice


def labelled_grid_figure(grid, title: str):
    """``grid`` drawn as every grid is (``show_grid``), each cell labelled with its P(occupied) to one decimal."""
    import matplotlib.pyplot as plt

    from crfstudy.plotting import show_grid

    fig, ax = plt.subplots(figsize=(8, 3.2))
    show_grid(ax, grid, title, cells=True, colorbar=True)
    for (y, x), p in np.ndenumerate(grid.probability):
        ax.text(x, y, f"{p:.1f}", ha="center", va="center", color="white" if p > 0.5 else "black")
    return fig


def student_joint(p_i, p_d, p_g_given_id, p_s_given_i, p_l_given_g) -> np.ndarray:
    """The student network's joint by its chain rule (thesis eq. 2), as a table [i, d, g, s, l].

    P(I, D, G, S, L) = P(I) P(D) P(G | I, D) P(S | I) P(L | G); every CPD must sum to 1 over its
    last axis (the child's states), else the product is no distribution.

    >>> j = student_joint([0.7, 0.3], [0.6, 0.4], np.full((2, 2, 3), 1 / 3), [[0.5, 0.5]] * 2, [[0.5, 0.5]] * 3)
    >>> j.shape, round(float(j.sum()), 12)
    ((2, 2, 3, 2, 2), 1.0)
    """
    cpds = {"P(I)": p_i, "P(D)": p_d, "P(G|I,D)": p_g_given_id, "P(S|I)": p_s_given_i, "P(L|G)": p_l_given_g}
    cpds = {name: np.asarray(cpd, dtype=float) for name, cpd in cpds.items()}
    for name, cpd in cpds.items():
        if not np.allclose(cpd.sum(axis=-1), 1.0):
            raise InputError(name, "each distribution over the child's states must sum to 1")
    return np.einsum("i,d,idg,is,gl->idgsl", *cpds.values())


STUDENT_NODES = {"Difficulty": (0.0, 2.0), "Intelligence": (2.0, 2.0), "Grade": (1.0, 1.0), "SAT": (3.0, 1.0),
                 "Letter": (1.0, 0.0)}
STUDENT_EDGES = [("Difficulty", "Grade"), ("Intelligence", "Grade"), ("Intelligence", "SAT"), ("Grade", "Letter")]


def student_network_figure():
    """Fig. 3: the student network's five nodes and four arrows."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.2))
    for a, b in STUDENT_EDGES:
        ax.annotate("", xy=STUDENT_NODES[b], xytext=STUDENT_NODES[a],
                    arrowprops=dict(arrowstyle="-|>", shrinkA=22, shrinkB=22, color="0.2"))
    for name, (x, y) in STUDENT_NODES.items():
        ax.text(x, y, name, ha="center", va="center", bbox=dict(boxstyle="round,pad=0.4", fc="white", ec="0.2"))
    ax.set_xlim(-0.7, 3.7)
    ax.set_ylim(-0.5, 2.5)
    ax.set_axis_off()
    ax.set_title("Fig. 3: the student Bayesian network")
    return fig


def neighbour_correlation(chains) -> float:
    """E[s_i s_(i+1)] over every bond of a set of 1-D chains (``chains[k, i]``): tanh J for a free chain."""
    chains = np.asarray(chains)
    return float(np.mean(chains[:, :-1] * chains[:, 1:]))


def chains_figure(chains: dict):
    """Fig. 5: one 1-D chain per coupling (``chains``: J -> spins), spins as arrows, red up and blue down."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(chains), 1, figsize=(9, 3.6), sharex=True)
    for ax, (coupling, spins) in zip(axes, chains.items()):
        x = np.arange(len(spins))
        ax.quiver(x, -0.4 * spins, np.zeros(len(spins)), 0.8 * spins, angles="xy", scale_units="xy", scale=1,
                  color=["C3" if s > 0 else "C0" for s in spins], width=0.004)
        ax.set_ylim(-0.6, 0.6)
        ax.set_yticks([])
        ax.set_ylabel(f"J = {coupling:g}", rotation=0, ha="right", va="center")
    axes[0].set_title("Fig. 5: Gibbs samples of a 1-D Ising chain (red up, blue down)")
    axes[-1].set_xlabel("site")
    return fig


def magnetisation_curve(couplings, side: int, sweeps: int, chains: int, seed: int = 0) -> list:
    """Mean |magnetisation| of ``chains`` side x side lattices per coupling, each started ordered.

    Starting from all spins up, the chains sample the ordered phase's equilibrium |m| instead of
    waiting for a disordered start to pick a sign; coupling k gets the seed ``seed + k``.
    """
    ordered = np.ones((side, side), dtype=np.int8)
    curve = []
    for k, coupling in enumerate(couplings):
        spins = gibbs_ising((side, side), coupling, sweeps=sweeps, chains=chains, initial=ordered, seed=seed + k)
        curve.append(float(np.abs(spins.mean(axis=(1, 2))).mean()))
    return curve


def onsager_magnetisation(coupling) -> np.ndarray:
    """Onsager's spontaneous magnetisation of the infinite square lattice: 0 below the critical coupling."""
    coupling = np.asarray(coupling, dtype=float)
    above = np.maximum(coupling, CRITICAL_COUPLING + 1e-12)  # the power is only evaluated where it is defined
    return np.where(coupling > CRITICAL_COUPLING, np.abs(1 - np.sinh(2 * above) ** -4) ** 0.125, 0.0)


def lattices_figure(lattices: dict, curve_couplings, magnetisation, curve_side: int):
    """Fig. 6: 2-D samples (``lattices``: J -> spins) and the magnetisation curve against Onsager's."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(lattices) + 1, figsize=(15, 4.2), layout="constrained")
    for ax, (coupling, spins) in zip(axes, lattices.items()):
        ax.imshow(spins, cmap="coolwarm", vmin=-1, vmax=1, origin="lower", interpolation="nearest")
        critical = round(CRITICAL_COUPLING, 4) == coupling
        ax.set_title(f"J = {coupling:g}" + (" (critical)" if critical else ""))
        ax.set_xticks([])
        ax.set_yticks([])
    fine = np.linspace(0.2, 0.8, 400)
    ax = axes[-1]
    ax.plot(fine, onsager_magnetisation(fine), color="0.3", label="Onsager (infinite lattice)")
    ax.plot(curve_couplings, magnetisation, "o", color="C3", label=f"Gibbs, {curve_side}x{curve_side}, free edges")
    ax.axvline(CRITICAL_COUPLING, color="0.7", linestyle=":")
    ax.set_xlabel("coupling J")
    ax.set_ylabel("mean |magnetisation|")
    ax.legend(fontsize="small", loc="lower right")
    fig.suptitle("Fig. 6: Gibbs samples of a 2-D Ising lattice (red up, blue down), and its ordering")
    return fig


def lbp_against_exact(couplings: dict, shapes, variants: dict, n_grids: int, seed: int = 0):
    """LBP's marginals beside the exact ones on small random grids (Fig. 9).

    For every hidden table in ``couplings`` (name -> 2x2 table), every grid shape and ``n_grids``
    observation sets drawn uniform in [0, 1] (one seeded stream, in that order), each LBP variant
    (name -> ``infer`` options) is run and its beliefs kept beside brute-force exact marginals.
    Returns ``pairs[(coupling, variant)] = (exact arrays, LBP arrays)`` and, per coupling, how many
    runs of the variant named "converged" did not converge.
    """
    from crfmap.crf import infer
    from crfstudy.references import exact_marginals

    rng = np.random.default_rng(seed)
    pairs = {(c, v): ([], []) for c in couplings for v in variants}
    not_converged = {c: 0 for c in couplings}
    for cname, table in couplings.items():
        for shape in shapes:
            for _ in range(n_grids):
                observed = rng.uniform(0.0, 1.0, shape)
                exact = exact_marginals(observed, table)
                for vname, options in variants.items():
                    result = infer(observed, table, **options)
                    if vname == "converged" and not result.converged:
                        not_converged[cname] += 1
                    pairs[cname, vname][0].append(exact.ravel())
                    pairs[cname, vname][1].append(result.beliefs.probability.ravel())
    return pairs, not_converged


def lbp_exact_errors(pairs: dict) -> list:
    """Rows [hidden table, variant, grids, max |LBP - exact|, mean |LBP - exact|] of :func:`lbp_against_exact`'s pairs."""
    rows = []
    for (cname, vname), (exact, approx) in pairs.items():
        error = np.abs(np.concatenate(approx) - np.concatenate(exact))
        rows.append([cname, vname, len(exact), error.max(), error.mean()])
    return rows


def lbp_exact_figure(pairs: dict, n_grids: int):
    """Fig. 9: one scatter panel per hidden table, LBP against exact P(occupied), one colour per variant."""
    import matplotlib.pyplot as plt

    couplings = list(dict.fromkeys(c for c, _ in pairs))
    variants = list(dict.fromkeys(v for _, v in pairs))
    styles = [dict(s=6, color="C0", alpha=0.5), dict(s=8, color="C1", alpha=0.5, marker="x")]
    fig, axes = plt.subplots(1, len(couplings), figsize=(16, 4.4), sharex=True, sharey=True, layout="constrained")
    for ax, cname in zip(np.atleast_1d(axes), couplings):
        for vname, style in zip(variants, styles):
            exact, approx = (np.concatenate(part) for part in pairs[cname, vname])
            ax.scatter(exact, approx, label=f"LBP {vname}", **style)
        ax.plot([0, 1], [0, 1], color="0.5", linewidth=1)
        ax.set_title(f"hidden {cname}", fontsize="medium")
        ax.set_xlabel("exact P(occupied)")
        ax.set_aspect("equal")
    first = np.atleast_1d(axes)[0]
    first.set_ylabel("LBP P(occupied)")
    first.legend(loc="upper left", fontsize="small")
    fig.suptitle(f"Fig. 9: LBP vs exact marginals on 4x4 and 3x5 grids ({n_grids} random observation sets each)",
                 y=1.06)  # above the panel titles (equal-aspect panels sit lower than constrained layout assumes)
    return fig


def coin_likelihood_figure(theta, likelihood, theta_hat: float):
    """Fig. 10: the coin's likelihood curve, 2/7 and the grid-search maximum marked."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.5))
    ax.plot(theta, likelihood)
    ax.axvline(2 / 7, color="C3", linestyle=":", label=f"2/7 = {2 / 7:.5f}")
    ax.plot(theta_hat, np.max(likelihood), "o", color="C1", label=f"grid-search maximum {theta_hat:.5f}")
    ax.set_xlabel("theta = P(heads)")
    ax.set_ylabel("L(theta : T,T,H,T,H,T,T)")
    ax.set_title("Fig. 10: likelihood (1 - theta)^5 theta^2")
    ax.legend(fontsize="small")
    return fig


def roc_example_figure(truth, noisy, cleaned, curves: dict):
    """Fig. 12: truth, noisy and cleaned grids beside their ROC curves (``curves``: label -> (fpr, tpr, auc))."""
    import matplotlib.pyplot as plt

    from crfstudy.plotting import plot_roc, show_grid

    fig, axes = plt.subplots(1, 4, figsize=(15, 3.8), layout="constrained")
    show_grid(axes[0], truth, "truth", cells=True)
    show_grid(axes[1], noisy, "noisy (sigma 0.4)", cells=True)
    show_grid(axes[2], cleaned, "after LBP", cells=True)
    plot_roc(axes[3], curves, title="Fig. 12: ROC, occupied = positive")
    return fig
