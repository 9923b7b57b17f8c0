"""Optional benchmark rows from two independent libraries: PGMax (LBP) and PyMaxflow (graph cut).

Neither is a dependency of crfmap; the rows run only when the library imports. Both solve the
model :mod:`crfstudy.bench.suite` times: a binary hidden lattice, 4-neighbour edges with the table
``DEFAULT_HIDDEN`` ([[10, 1], [1, 10]], state 0 = occupied), each cell's unary
``link_unary(observed, DEFAULT_LINK)`` floored to [MESSAGE_FLOOR, 1 - MESSAGE_FLOOR] as
:func:`crfmap.crf.inference.lbp.infer` does, on ``bench_grid(size)``.

- ``pgmax-bp``: PGMax's belief propagation (JAX, CPU, float32, synchronous "flooding"
  schedule, ``temperature=1`` = sum-product). Timed with damping 0.5; ``pgmax-compile`` is the
  first (tracing + XLA compiling) call. Two agreement numbers against crfmap's flooding LBP:

  * ``max_belief_difference``: both undamped, the same ``iterations`` from uniform messages:
    the same arithmetic, so only float32 rounding separates them (``crfmap_float32_vs_float64``,
    crfmap's own float32 run against its float64 one, shows that scale). (Damped runs cannot be
    compared step by step: PGMax damps log-messages, crfmap damps probabilities.)
  * ``fixed_point_max_belief_difference``: crfmap's damped flooding run to convergence; PGMax
    warm-started from its messages and run ``iterations`` damped iterations moves nothing.
    (Two runs from uniform messages are not compared: with this coupling LBP has many fixed
    points, and the two damping rules can end in different ones.)

- ``pymaxflow-map``: the exact MAP labelling by a graph cut (Boykov-Kolmogorov), possible
  because the symmetric table is attractive (submodular energy), compared with crfmap's
  converged checkerboard LBP labels (belief > 0.5) by agreement and by CRF energy, on the
  uniform grid and on the noisy office floor. On the uniform grid the coupling orders the
  field into large domains and the two labellings differ in many cells (the LBP labels have
  higher energy); on the office floor they agree almost everywhere.

Install: ``pip install PyMaxflow 'jax<0.8' 'jaxlib<0.8'`` then ``pip install --no-deps pgmax``.
PGMax 0.6.1 calls ``jax.lib.xla_bridge.get_backend``, removed in jax 0.8; its package metadata
also requires TensorFlow, cvxpy, Sphinx and Jupyter, none of which its BP imports.
"""
from __future__ import annotations

import functools
import importlib
import time
import warnings

import numpy as np

from crfmap.assess.mincut import floored_unary, graph_cut_map
from crfstudy.bench.common import median_time, bench_grid, record
from crfstudy.references import crf_energy
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import Flooding
from crfmap.crf.model.potentials import check_table, DEFAULT_HIDDEN, DEFAULT_LINK

LIBRARIES = {"pgmax": "pgmax", "pymaxflow": "maxflow"}  # name in records -> module
INSTALL = {"pgmax": "pip install 'jax<0.8' 'jaxlib<0.8' && pip install --no-deps pgmax",
           "pymaxflow": "pip install PyMaxflow"}
METHODS = {"pgmax": "pgmax-bp", "pymaxflow": "pymaxflow-map"}
PGMAX_MAX_SIZE = 1024  # its graph is built in Python lists: at 1024 x 1024, 15 s and 6 GB peak
MAXFLOW_MAX_SIZE = 2048  # one cut of 4096 x 4096 takes over a minute
ITERATIONS, QUICK_ITERATIONS = 100, 20
DAMPING = 0.5  # flooding with [[10, 1], [1, 10]] oscillates undamped and converges with 0.5
FIXED_POINT_TOL = 1e-6  # crfmap's flooding run to this largest message change
FIXED_POINT_MAX_ITER = 20000


def available() -> dict:
    """{"pgmax": version or None, "pymaxflow": version or None}; never raises.

    >>> sorted(available())
    ['pgmax', 'pymaxflow']
    """
    out = {}
    for name, module in LIBRARIES.items():
        try:
            mod = importlib.import_module(module)
            out[name] = str(getattr(mod, "__version__", None) or _dist_version(name))
        except Exception:  # noqa: BLE001 - a broken optional install counts as absent
            out[name] = None
    return out


def _dist_version(name):
    from importlib.metadata import version

    return version({"pymaxflow": "PyMaxflow"}.get(name, name))


def bench_maxflow(size, repeats, seed=0, kinds=("uniform", "office")) -> list:
    """PyMaxflow's exact MAP against crfmap's converged checkerboard LBP, one record per grid kind.

    ``"uniform"`` is ``bench_grid(size, seed)`` (what the throughput rows use); ``"office"`` the
    noisy office floor of the convergence rows, a map-like input.
    """
    import maxflow  # noqa: F401 - fail early if absent

    out = []
    for kind in kinds:
        observed = bench_grid(size, seed, kind=kind)
        seconds = median_time(lambda: graph_cut_map(observed), repeats)  # noqa: B023 (called at once)
        labels, _ = graph_cut_map(observed)
        lbp = infer(observed, tol=FIXED_POINT_TOL, max_iter=FIXED_POINT_MAX_ITER)
        lbp_labels = lbp.beliefs.probability > 0.5
        out.append(record("pymaxflow-map", size, np.float64, 1, None, grid=kind, seconds=seconds,
                          agreement_with_lbp=float(np.mean(labels == lbp_labels)),
                          energy_map=crf_energy(labels, observed), energy_lbp_labels=crf_energy(lbp_labels, observed),
                          occupied_map=float(labels.mean()), occupied_lbp=float(lbp_labels.mean()),
                          lbp_iterations=lbp.iterations, lbp_converged=lbp.converged,
                          note="exact MAP by graph cut (seconds: graph building + max-flow); LBP labels: "
                          f"crfmap checkerboard beliefs > 0.5 at tol {FIXED_POINT_TOL:g}"))
    return out


# --- PGMax: the same flooding LBP in JAX ----------------------------------------------------------------


class PgmaxLattice:
    """The crfmap CRF as a PGMax factor graph: one NDVarArray (state 0 = occupied), pairwise factors.

    Factors: every (y, x)-(y, x+1) edge, then every (y, x)-(y+1, x) edge, the west / south cell
    first, with log-potential ``log(hidden)`` (crfmap's "oriented" pairing).
    """

    def __init__(self, observed, hidden=DEFAULT_HIDDEN, link=DEFAULT_LINK):
        from pgmax import fgraph, fgroup, infer as pinfer, vgroup

        self.observed = np.asarray(observed, np.float64)
        self.hidden = check_table(hidden, "hidden")
        h, w = self.shape = self.observed.shape
        self.vars = vgroup.NDVarArray(num_states=2, shape=(h, w))
        graph = fgraph.FactorGraph(variable_groups=self.vars)
        v = self.vars
        pairs = [list(p) for p in zip(v[:, :-1], v[:, 1:])] + [list(p) for p in zip(v[:-1, :], v[1:, :])]
        with np.errstate(divide="ignore"):
            log_table = np.log(self.hidden)
        graph.add_factors(fgroup.PairwiseFactorGroup(variables_for_factors=pairs, log_potential_matrix=log_table))
        with warnings.catch_warnings():  # PGMax 0.6.1 on jax 0.6 warns of its own jax.lib.xla_bridge call
            warnings.simplefilter("ignore", DeprecationWarning)
            self.bp = pinfer.build_inferer(graph.bp_state, backend="bp")
        self._infer = pinfer
        u = floored_unary(self.observed, link)
        self.arrays = self.bp.init(evidence_updates={self.vars: np.log(np.stack([u, 1.0 - u], axis=-1))})

    def runner(self, iterations, temperature=1.0):
        """A jitted ``(arrays, damping) -> (arrays, message changes)`` of ``iterations`` iterations."""
        import jax

        run = functools.partial(self.bp.run_with_diffs, num_iters=iterations, temperature=temperature)
        return jax.jit(lambda arrays, damping: run(arrays, damping=damping))

    def marginals(self, arrays) -> np.ndarray:
        """P(occupied) of every cell, float64 [y, x]."""
        beliefs = self._infer.get_marginals(self.bp.get_beliefs(arrays))[self.vars]
        return np.asarray(beliefs, dtype=np.float64)[..., 0]

    def with_messages(self, messages):
        """The initial arrays with crfmap's messages (4, H, W) of P(receiver occupied) as PGMax's."""
        from pgmax.factor import EnumFactor

        h, w = self.shape
        flat = np.arange(h * w).reshape(h, w)
        # per factor (a, b): the message to a, then the one to b (crfmap slots: see _lbp_kernels)
        to_a = np.concatenate([messages[1][:, :-1].ravel(), messages[3][:-1, :].ravel()])
        to_b = np.concatenate([messages[0][:, 1:].ravel(), messages[2][1:, :].ravel()])
        a = np.concatenate([flat[:, :-1].ravel(), flat[:-1, :].ravel()])
        b = np.concatenate([flat[:, 1:].ravel(), flat[1:, :].ravel()])
        wiring = self.bp.to_bp_state(self.arrays).fg_state.wiring[EnumFactor].var_states_for_edges[:, 0]
        expected = np.stack([2 * a, 2 * a + 1, 2 * b, 2 * b + 1], axis=1).ravel()
        if not np.array_equal(wiring, expected):  # PGMax's message layout is not documented API
            raise RuntimeError("unexpected PGMax message layout; cannot warm-start from crfmap's messages")
        m = np.clip(np.stack([to_a, to_b], axis=1), MESSAGE_FLOOR, 1.0 - MESSAGE_FLOOR)
        log_msgs = np.log(np.stack([m, 1.0 - m], axis=-1)).ravel()
        return self.bp.update(self.arrays, ftov_msgs_updates={EnumFactor: log_msgs})


def bench_pgmax(size, repeats, iterations=ITERATIONS, seed=0, damping=DAMPING) -> list:
    """PGMax BP on ``bench_grid(size, seed)``: a compile record and a throughput + agreement record."""
    import jax

    observed = bench_grid(size, seed)
    t0 = time.perf_counter()
    lattice = PgmaxLattice(observed)
    build = time.perf_counter() - t0
    run = lattice.runner(iterations)

    def go(arrays, d):
        out = run(arrays, d)
        jax.block_until_ready(out)
        return out

    t0 = time.perf_counter()
    go(lattice.arrays, damping)
    first = time.perf_counter() - t0
    seconds = median_time(lambda: go(lattice.arrays, damping), repeats) / iterations

    undamped, _ = go(lattice.arrays, 0.0)
    ours = infer(observed, schedule="flooding", max_iter=iterations, tol=0.0, pairing="oriented")
    difference = float(np.abs(lattice.marginals(undamped) - ours.beliefs.probability).max())
    # the scale of float32 rounding here: crfmap's own float32 run against its float64 one
    ours32 = infer(observed, schedule="flooding", max_iter=iterations, tol=0.0, pairing="oriented",
                   dtype=np.float32)
    rounding = float(np.abs(ours32.beliefs.probability - ours.beliefs.probability).max())

    fixed = infer(observed, schedule=Flooding(damping=damping), max_iter=FIXED_POINT_MAX_ITER,
                  tol=FIXED_POINT_TOL, pairing="oriented")
    warm, changes = go(lattice.with_messages(fixed.messages), damping)
    fixed_difference = float(np.abs(lattice.marginals(warm) - fixed.beliefs.probability).max())

    common = dict(jax_version=jax.__version__, backend=jax.default_backend())
    return [
        record("pgmax-compile", size, None, None, None, seconds=first, build_seconds=build,
               iterations=iterations, note="first jitted call (tracing, XLA compilation, one run); "
               "build_seconds: factor graph and inferer", **common),
        record("pgmax-bp", size, np.float32, None, seconds, iterations_timed=iterations, damping=damping,
               temperature=1.0, max_belief_difference=difference, crfmap_float32_vs_float64=rounding,
               fixed_point_max_belief_difference=fixed_difference,
               fixed_point_message_change=float(np.asarray(changes)[-1]),
               fixed_point_crfmap_iterations=fixed.iterations, fixed_point_crfmap_converged=fixed.converged,
               note="threads: JAX decides (XLA CPU); max_belief_difference: undamped, same iterations as "
               "crfmap flooding; fixed point: PGMax warm-started from crfmap's converged damped flooding",
               **common),
    ]


# --- what bench.run calls -------------------------------------------------------------------------------


def run_external(sizes, repeats, quick=False):
    """Yield the PGMax and PyMaxflow records for the libraries that are installed.

    A missing library yields one record (numbers None, ``note="not installed (...)"``); sizes
    above PGMAX_MAX_SIZE / MAXFLOW_MAX_SIZE yield a "skipped" record; a library that imports but
    fails (e.g. PGMax with jax >= 0.8) yields one "failed" record and is not tried again.
    """
    have = available()
    iterations = QUICK_ITERATIONS if quick else ITERATIONS
    jobs = {"pgmax": (PGMAX_MAX_SIZE, lambda s: bench_pgmax(s, repeats, iterations)),
            "pymaxflow": (MAXFLOW_MAX_SIZE, lambda s: bench_maxflow(s, repeats))}
    for name, (largest, bench_one) in jobs.items():
        method = METHODS[name]
        if have[name] is None:
            yield record(method, note=f"not installed ({INSTALL[name]})")
            continue
        for size in sizes:
            if size > largest:
                yield record(method, size, note=f"skipped: larger than {largest} x {largest}")
                continue
            try:
                records = bench_one(size)
            except Exception as error:  # noqa: BLE001 - an optional library's failure is a result
                yield record(method, size, version=have[name],
                             note=f"failed: {type(error).__name__}: {error} ({INSTALL[name]})")
                break
            for rec in records:
                rec.setdefault("version", have[name])
                yield rec
