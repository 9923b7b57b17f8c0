"""``crfmap metrics PRED TRUTH``: MSE, precision, recall, accuracy and AUC of a grid."""
from __future__ import annotations

import argparse
import json
import math

import numpy as np

from crfmap.errors import InputError


def add_parser(sub):
    p = sub.add_parser("metrics", help="compare a grid with ground truth",
                       description="MSE over all cells; precision/recall/accuracy over cells not exactly 0.5 "
                       "(occupied = P > 0.5); ROC AUC.")
    p.add_argument("prediction", help="map_server YAML or .npy")
    p.add_argument("truth", help="map_server YAML or .npy (occupied where P > 0.5)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def run(args: argparse.Namespace) -> int:
    from crfmap.io.grid_files import load_grid
    from crfmap.assess.metrics import evaluate

    pred = load_grid(args.prediction)
    truth = load_grid(args.truth)
    values = truth.probability
    if not np.all((values == 0) | (values == 1) | (values == 0.5)):
        odd = values[(values != 0) & (values != 1) & (values != 0.5)]
        raise InputError(args.truth, f"a truth holds 0 (empty), 1 (occupied) or 0.5 (unknown) only; "
                                     f"{odd.size} cells hold other values (e.g. {float(odd[0]):g})")
    if pred.shape != truth.shape:
        raise InputError(args.prediction, f"shape {pred.shape} does not match {args.truth}'s {truth.shape}")
    r = evaluate(pred, truth)
    if args.json:
        d = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in r.as_dict().items()}
        print(json.dumps(d))
    else:
        print(f"mse {r.mse:.6f}  precision {r.precision:.4f}  recall {r.recall:.4f}  "
              f"accuracy {r.accuracy:.4f}  auc {r.auc:.4f}  (tp {r.tp} fp {r.fp} fn {r.fn} tn {r.tn}, "
              f"{r.unknown} unknown cells left out)")
    return 0
