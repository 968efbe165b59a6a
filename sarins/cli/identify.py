"""``sarins identify``: train and apply the RBF drift identifier from CSV files.

::

    sarins identify train --data records.csv \\
        --inputs lat_error_deg[,temp_c,temp_change_c] --target drift_dph \\
        --spread 2 --goal 9e-8 [--max-neurons N] --out model.json [--fmu-model model.bin]
    sarins identify predict --model model.json --data tests.csv [--out predictions.csv]

The ``sarins`` command adds these through :func:`register`.

Latitude reading or error
    Seed 000 feeds the network the latitude *reading* after 4 h alignment and
    12 h navigation (its Table 2 lists readings such as 28.2274°). The
    portable input is the latitude *error*, reading minus the site latitude.
    If ``lat_error_deg`` is asked for and the CSV only has ``lat_deg``, it is
    computed as ``lat_deg - local_lat_deg`` (``--local-lat-deg``, default
    28.222°, the paper's site; and the other way round for ``lat_deg``).
    With the default input standardisation a constant offset does not
    change the network, so at one site both choices give the same drifts.

Goal
    ``--goal`` is the mean squared training error in the target's unit
    squared, as MATLAB's ``newrb``. Seed 000 states a training error of
    0.0003 °/h; read as an RMS that is a goal of 9e-8 (°/h)², the default.

``--fmu-model`` also writes the binary model file that the RBFIdentifier FMU
reads as its ``model_file`` (the inputs must be among lat_error_deg, lat_deg,
temp_c, temp_change_c and the target in deg/h).

The model file (JSON) stores the input column names, the target name, the
site latitude and the range of each training input; ``predict`` requires the
same inputs and refuses (exit 2, naming the CSV line) a row whose input lies
beyond the training range by more than 10 % of its width: the network does
not extrapolate (older model files: the range bounded from the stored
scaling, see :meth:`RBFNetwork.outside_training_range`). Predictions are written
as the input table plus a column ``<target>_pred``. A bad CSV, model file or
option gives a one-line error on stderr and exit status 2 (the ``sarins``
convention).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from sarins_fmu.files import DISK_FULL_ERRNOS, check_output_path
from sarins_fmu.identify.axial import site_latitude_deg
from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.rbf import RANGE_MARGIN, RBFNetwork
from sarins_fmu.identify.tables import SEED000_SITE_LAT_DEG, TableError, numeric_column, read_table, write_table

__all__ = ["register", "run", "DEFAULT_GOAL", "DEFAULT_SPREAD"]

DEFAULT_SPREAD = 2.0  # seed 000's SPREAD (standardised units here)
DEFAULT_GOAL = 0.0003**2  # (deg/h)^2: seed 000's 0.0003 deg/h training error as an RMS

_PROG = "sarins identify"


class _UsageError(Exception):
    """A problem with the user's files or options (one-line message, exit 2)."""


def _check_number(name: str, value, *, low=None, high=None, positive=False) -> None:
    """Refuse a non-finite or out-of-range option value (one line naming the option)."""
    if value is None:
        return
    ok = np.isfinite(value) and (not positive or value > 0)
    ok = ok and (low is None or value >= low) and (high is None or value <= high)
    if not ok:
        limits = "positive and finite" if positive else "finite"
        if low is not None or high is not None:
            limits += f", within [{low if low is not None else '-inf'}, {high if high is not None else 'inf'}]"
        raise _UsageError(f"{name} must be {limits}, got {value!r}")


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``identify`` command (with ``train`` and ``predict``) to a CLI.

    Parameters
    ----------
    subparsers : argparse sub-parsers action
        From ``parser.add_subparsers()`` of the calling program.

    Returns
    -------
    argparse.ArgumentParser
        The ``identify`` parser; its default ``func`` is :func:`run`.
    """
    parser = subparsers.add_parser(
        "identify",
        help="train / apply the RBF gyro-drift identifier (seed 000)",
        description="Train and apply the RBF network that identifies the axial gyro drift "
        "from the latitude error (and temperatures) after alignment + navigation.",
    )
    sub = parser.add_subparsers(dest="identify_command", metavar="{train,predict}")
    sub.required = True

    train = sub.add_parser(
        "train",
        help="train an RBF network on a CSV table",
        description="Grow an RBF network (newrb-style, orthogonal least squares) on CSV columns. "
        "Seed 000 feeds the latitude reading after 4 h alignment + 12 h navigation; this command "
        "takes the latitude error (lat_error_deg) and, if the CSV only has the reading (lat_deg), "
        "computes it as lat_deg - local_lat_deg. With standardised inputs both give the same network.",
    )
    train.add_argument("--data", required=True, type=Path, help="training CSV with a header row")
    train.add_argument(
        "--inputs",
        default="lat_error_deg",
        help="comma-separated input columns (default: lat_error_deg; "
        "e.g. lat_error_deg,temp_c,temp_change_c for a cold start)",
    )
    train.add_argument("--target", default="drift_dph", help="target column (default: drift_dph)")
    train.add_argument(
        "--spread", type=float, default=DEFAULT_SPREAD,
        help=f"distance (standardised units) where a neuron answers 0.5 (default: {DEFAULT_SPREAD:g})",
    )
    train.add_argument(
        "--goal", type=float, default=DEFAULT_GOAL,
        help="mean squared training error that stops growth, target unit squared "
        f"(default: {DEFAULT_GOAL:g} = (0.0003 deg/h)^2)",
    )
    train.add_argument("--max-neurons", type=int, default=None, help="most neurons (default: samples)")
    train.add_argument(
        "--selection", choices=("ols", "residual"), default="ols",
        help="centre selection: orthogonal least squares (default) or largest residual",
    )
    train.add_argument(
        "--no-standardize", action="store_true",
        help="do not standardise inputs (SPREAD then in the inputs' units, as MATLAB)",
    )
    train.add_argument(
        "--local-lat-deg", type=float, default=SEED000_SITE_LAT_DEG,
        help=f"site latitude, deg, to turn lat_deg into lat_error_deg (default: {SEED000_SITE_LAT_DEG})",
    )
    train.add_argument("--curve", type=Path, default=None, help="also write the training curve CSV")
    train.add_argument("--out", required=True, type=Path, help="model file to write (JSON, or .npz)")
    train.add_argument("--fmu-model", type=Path, default=None, metavar="PATH",
                       help="also write the binary model file the RBFIdentifier FMU reads (its model_file)")

    predict = sub.add_parser(
        "predict",
        help="apply a trained network to a CSV table",
        description="Predict the target for every row of a CSV table with a trained model.",
    )
    predict.add_argument("--model", required=True, type=Path, help="model file from 'identify train'")
    predict.add_argument("--data", required=True, type=Path, help="CSV with the model's input columns")
    predict.add_argument(
        "--local-lat-deg", type=float, default=None,
        help="site latitude, deg, for lat_deg <-> lat_error_deg (default: the model's)",
    )
    predict.add_argument("--out", type=Path, default=None, help="predictions CSV (default: stdout)")

    parser.set_defaults(func=run)
    return parser


def _input_matrix(
    table: dict[str, np.ndarray], names: list[str], local_lat_deg: float, path: Path
) -> np.ndarray:
    """Columns ``names`` as an (n, d) array, converting latitude reading/error."""
    cols = []
    for name in names:
        if name in table:
            cols.append(numeric_column(table, name, path))
        elif name == "lat_error_deg" and "lat_deg" in table:
            cols.append(numeric_column(table, "lat_deg", path) - local_lat_deg)
        elif name == "lat_deg" and "lat_error_deg" in table:
            cols.append(numeric_column(table, "lat_error_deg", path) + local_lat_deg)
        else:
            raise TableError(f"{path}: no column '{name}' (columns: {', '.join(table)})")
    return np.column_stack(cols)


def _train(args: argparse.Namespace) -> None:
    names = [n.strip() for n in args.inputs.split(",")]
    if not all(names) or len(set(names)) != len(names):
        raise _UsageError(f"--inputs must be distinct comma-separated column names, got {args.inputs!r}")
    if not np.isfinite(args.local_lat_deg) or abs(args.local_lat_deg) > 90.0:
        raise _UsageError(f"--local-lat-deg must be within [-90, 90], got {args.local_lat_deg}")
    # spread: standardised units; beyond 1e6 every basis function is flat to double precision
    _check_number("--spread", args.spread, low=1e-6, high=1e6)
    _check_number("--goal", args.goal, low=0.0, high=1e300)
    if args.max_neurons is not None and not 1 <= args.max_neurons <= 100_000:
        raise _UsageError(f"--max-neurons must be in 1 .. 100000, got {args.max_neurons}")
    check_output_path(args.out, "--out")
    if args.fmu_model is not None:
        check_output_path(args.fmu_model, "--fmu-model")
    if args.curve is not None:
        check_output_path(args.curve, "--curve")
    table = read_table(args.data)
    x = _input_matrix(table, names, args.local_lat_deg, args.data)
    y = numeric_column(table, args.target, args.data)
    if x.shape[0] < 2:
        raise _UsageError(f"{args.data}: training needs at least 2 rows, got {x.shape[0]}")
    net = RBFNetwork(
        spread=args.spread,
        goal=args.goal,
        max_neurons=args.max_neurons,
        standardize=not args.no_standardize,
        selection=args.selection,
    )
    net.fit(x, y, input_names=names, target_name=args.target)
    net.metadata = {
        "local_lat_deg": args.local_lat_deg,
        "training_data": str(args.data),
        "n_samples": int(x.shape[0]),
    }
    net.save(args.out)
    if args.fmu_model is not None:
        from sarins_fmu.identify.axial import export_identifier

        try:
            export_identifier(args.out, args.fmu_model)
        except ModelFileError as exc:
            raise _UsageError(f"--fmu-model: {exc.reason}") from None
    if args.curve is not None:
        write_table(args.curve, {
            "neurons": np.arange(len(net.training_curve_), dtype=float),
            "mse": net.training_curve_,
        })
    reached = "reached" if net.training_mse_ <= args.goal else "NOT reached"
    print(
        f"trained RBF on {x.shape[0]} samples, inputs {','.join(names)} -> {args.target}: "
        f"{net.n_neurons} neurons, training MSE {net.training_mse_:.4g} "
        f"(RMS {np.sqrt(net.training_mse_):.4g}), goal {args.goal:g} {reached} "
        f"[stop: {net.stop_reason_}]; model written to {args.out}",
        file=sys.stdout,
    )


def _refuse_outside_training_range(net: RBFNetwork, x: np.ndarray, data: Path, model: Path) -> None:
    """Refuse (exit 2) the first row with an input beyond the model's training range
    (widened by ``RANGE_MARGIN`` of its width): an RBF network does not extrapolate."""
    outside = net.outside_training_range(x)
    if not outside.any():
        return
    row = int(np.argmax(outside))
    lo, hi = net.input_range_
    width = hi - lo
    col = int(np.argmax((x[row] < lo - RANGE_MARGIN * width) | (x[row] > hi + RANGE_MARGIN * width)))
    name = net.input_names[col]
    kind = "trained on" if net.input_range_exact_ else "bounded from its scaling statistics to"
    raise _UsageError(
        f"{data}: line {row + 2}: {name} = {x[row, col]:.6g} is outside the range the model {model} was "
        f"{kind}, [{lo[col]:.6g}, {hi[col]:.6g}] (+-{RANGE_MARGIN:.0%} of its width accepted); "
        f"{int(outside.sum())} of {len(outside)} rows lie outside: an RBF network does not extrapolate"
    )


def _predict(args: argparse.Namespace) -> None:
    if args.out is not None:
        check_output_path(args.out, "--out")
    net = RBFNetwork.load(args.model)
    if net.input_names is None:
        raise _UsageError(
            f"{args.model}: model file has no input column names; retrain with 'identify train'"
        )
    lat = args.local_lat_deg
    if lat is None:
        lat = site_latitude_deg(net.metadata, args.model)
    elif not np.isfinite(lat) or abs(lat) > 90.0:
        raise _UsageError(f"--local-lat-deg must be within [-90, 90], got {lat}")
    table = read_table(args.data)
    converts = any(n in ("lat_deg", "lat_error_deg") and n not in table for n in net.input_names)
    if args.local_lat_deg is not None and not converts:
        raise _UsageError(f"--local-lat-deg does not apply: {args.data} has the model's inputs "
                          f"({', '.join(net.input_names)}) as they are, no latitude to convert")
    x = _input_matrix(table, list(net.input_names), lat, args.data)
    _refuse_outside_training_range(net, x, args.data, args.model)
    pred = net.predict(x)
    target = net.target_name or "prediction"
    result = dict(table)
    result[f"{target}_pred"] = pred
    summary = f"predicted {target} for {len(pred)} rows with {args.model}"
    if target in table and table[target].dtype.kind == "f" and np.all(np.isfinite(table[target])):
        err = pred - table[target]
        rms, worst = np.sqrt(np.mean(err**2)), np.abs(err).max()
        summary += f"; error vs '{target}': RMS {rms:.4g}, max |err| {worst:.4g}"
    if args.out is None:
        write_table(sys.stdout, result)
        print(summary, file=sys.stderr)
    else:
        write_table(args.out, result)
        print(summary + f"; written to {args.out}", file=sys.stdout)


def run(args: argparse.Namespace) -> int:
    """Run ``identify train`` or ``identify predict`` from parsed arguments.

    Parameters
    ----------
    args : argparse.Namespace
        As parsed by the parser :func:`register` built.

    Returns
    -------
    int
        Exit status: 0 on success, 2 on a bad file, column or option, 1 when
        a write fails for want of room (with a one-line message on stderr
        naming the file).
    """
    command = getattr(args, "identify_command", None)
    try:
        if command == "train":
            _train(args)
        elif command == "predict":
            _predict(args)
        else:
            raise _UsageError("choose 'train' or 'predict'")
    except BrokenPipeError:
        # the reader of stdout went away (e.g. `| head`): stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (_UsageError, TableError, ModelFileError, ValueError, OSError, RecursionError) as exc:
        message = " ".join(str(exc).split())
        where = f"{_PROG} {command}" if command else _PROG
        if isinstance(exc, OSError) and exc.errno in DISK_FULL_ERRNOS:  # no room: the run failed
            print(f"{where}: failed: {message}", file=sys.stderr)
            return 1
        print(f"{where}: error: {message}", file=sys.stderr)
        return 2
    return 0
