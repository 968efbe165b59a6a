"""``sarins allan``: overlapping Allan deviation of a preset's static data or of a recorded log.

::

    sarins allan --imu mems [--hours 28] [--rate-hz 1] [--seed 0] [--plot allan.png] [--json]
    sarins allan --log static.csv.gz [--axes frd] [--rate-hz 100] [--plot allan.png] [--json]
                 [--write-preset unit.json]

With ``--log`` the data, their length (and, when the log has time stamps, their rate) are the
log's: ``--imu``, ``--hours`` and ``--seed`` describe simulated data and are refused beside it
(exit 2 naming the option), not ignored; ``--rate-hz`` then gives the rate of a log without time.

Prints, per channel, the IEEE Std 952 / 1293 read-outs (quantisation Q, random walk N, bias
instability B, rate random walk K, rate ramp R), each with its 95 % interval and the averaging
time it was read at, or "not resolved" with the bound the record sets; next to the preset's spec
for simulated data; warnings for a record that is short or not static.  ``--write-preset`` fits
the log's noise model and writes it as an IMU preset file (``.json``, which ``--imu`` accepts) or
as the IMUThermal FMU's SSP parameter set (``.ssv``).
"""

from __future__ import annotations

import json
import math
import warnings

from sarins_fmu.files import check_output_path

from . import UsageError, finite, given, refuse_unless
from .log_options import add_log_options, imu_choice, read_options
from .navigate import seed_value


def register(sub) -> None:
    p = sub.add_parser("allan", help="Allan deviation and noise read-outs of an IMU preset or log",
                       description="Overlapping Allan deviation of simulated static data of a preset or of a "
                                   "recorded log, with the IEEE Std 952 read-outs and their intervals.")
    p.add_argument("--imu", type=imu_choice, default="mems", metavar="PRESET",
                   help="IMU preset to simulate: a name or a preset file (.json)")
    p.add_argument("--log", default=None, metavar="PATH",
                   help="analyse this recorded static log instead of a preset (any format of docs/imu-log.md)")
    p.add_argument("--hours", type=finite, default=28.0, help="length of the static record, h (default 28)")
    p.add_argument("--rate-hz", type=finite, default=1.0,
                   help="sample rate, Hz (default 1); with --log: the rate of a log without time_s")
    p.add_argument("--seed", type=seed_value, default=0, help="base random seed of the run (the IMU noise), 0 .. 2**31-1 (default 0)")
    add_log_options(p, rate=False)
    p.add_argument("--write-preset", default=None, metavar="FILE",
                   help="with --log: write the fitted noise model as an IMU preset (.json, for --imu) or as the "
                        "IMUThermal FMU's SSP parameter set (.ssv)")
    p.add_argument("--plot", default=None, help="write the annotated Allan plot to this PNG file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


LOG_ONLY = {"format": "--format", "axes": "--axes", "lat_deg": "--lat-deg", "lon_deg": "--lon-deg",
            "height_m": "--height-m", "topic": "--topic", "accept_units": "--accept-units",
            "write_preset": "--write-preset"}


def run(args) -> int:
    from sarins import allan as app

    if args.rate_hz <= 0:
        raise UsageError(f"--rate-hz must be positive, got {args.rate_hz:g}")
    if args.hours <= 0:
        raise UsageError(f"--hours must be positive, got {args.hours:g}")
    refuse_unless(args, {"imu": "--imu", "hours": "--hours", "seed": "--seed"},
                  not args.log, "describes simulated data and does not apply with --log (the log sets the "
                                "data, its sample rate and its length)")
    refuse_unless(args, LOG_ONLY, bool(args.log), "applies to a recorded log (--log)")
    for option, path in (("--plot", args.plot), ("--write-preset", args.write_preset)):
        if path:
            check_output_path(path, option)
    if args.write_preset and not str(args.write_preset).lower().endswith((".json", ".ssv")):
        raise UsageError(f"--write-preset {args.write_preset}: the file must end in .json (a preset) or .ssv (the "
                         "IMUThermal FMU's parameter set)")
    log = None
    if args.log:
        log = _read(args)
        h = log.step
        channels = [lambda j=j: log.dtheta[:, j] / h for j in range(3)] + [lambda j=j: log.dv[:, j] / h
                                                                         for j in range(3)]
        result = app.analyse(channels, 1.0 / h, f"log {args.log}", means=log.means)
    else:
        result = app.simulate(args.imu, args.hours, args.rate_hz, args.seed)
    for note in result.warnings:
        warnings.warn(note, stacklevel=1)
    preset_info = _write_preset(args, result, log) if args.write_preset else None
    if args.plot:
        app.plot(result, args.plot)
    rows = result.rows()
    if args.json:
        print(json.dumps({"source": result.source, "rate_hz": result.rate_hz, "record_s": result.record_length,
                          "confidence": app.allan_readout.CONFIDENCE, "channels": rows,
                          "warnings": (log.warnings if log is not None else []) + result.warnings,
                          "plot": args.plot, "preset": preset_info}, allow_nan=False))
        return 0
    print(f"Allan read-outs of {result.source}, {result.record_length / 3600:.4g} h at {result.rate_hz:g} Hz "
          f"({100 * app.allan_readout.CONFIDENCE:g} % intervals; n.r.: not resolved, < the bound the record sets)")
    for r in rows:
        print(f"  {r['channel']:8s} " + ";  ".join(_cell(r, term) for term in app.TERMS))
        extra = []
        if "gauss_markov" in r:
            extra.append(f"Gauss-Markov std {r['gauss_markov']:.3g} (spec {r['gauss_markov_spec']:.3g}, "
                         f"T {r['gauss_markov_time_s']:g} s) {r['gauss_markov_unit']}")
        if "resolution" in r:
            extra.append(f"output step {r['resolution']:.4g} {r['resolution_unit']} (its quantisation is white, "
                         "inside N)")
        if extra:
            print("           " + ";  ".join(extra))
    if args.plot:
        print(f"plot: {args.plot}")
    if preset_info:
        print(f"preset: {preset_info['file']} (Allan curve of the fitted model within "
              f"{100 * preset_info['worst_model_deviation']:.3g} % of the log's from {preset_info['fit_from_s']:g} s "
              f"to {preset_info['fit_to_s']:g} s)")
    return 0


def _cell(r: dict, term: str) -> str:
    from sarins.allan import LABELS

    low, high = r[f"{term}_interval"]
    unit = r[f"{term}_unit"]
    spec = f" (spec {r[term + '_spec']:.3g})" if term + "_spec" in r else ""
    if r[term] is None:
        return f"{LABELS[term]} n.r. (< {high:.3g}){spec} {unit}"
    return f"{LABELS[term]} {r[term]:.3g} [{low:.3g}, {high:.3g}]{spec} {unit} at {r[term + '_tau_s']:g} s"


def _read(args):
    from sarins_fmu.imu_log import read_log

    rate = args.rate_hz if given(args, "rate_hz") else None
    return read_log(args.log, read_options(args, rate))


def _write_preset(args, result, log) -> dict:
    """Fit the log's noise model and write it (see the module docstring); returns what was written."""
    import tempfile
    from pathlib import Path

    from sarins.allan import CHANNELS
    from sarins_fmu import allan_preset, imu_preset_file

    fit = allan_preset.fit_preset(result.curves, result.record_length, log.means, log.lat, log.height)
    name = Path(args.log).name.split(".")[0]
    info = {"log": str(args.log), "record_s": result.record_length, "rate_hz": result.rate_hz,
            "flicker_band_s": list(fit.band), "fit_from_s": allan_preset.FIT_FROM,
            "fit_to_s": allan_preset.FIT_TO * result.record_length,
            "worst_model_deviation": {ch: f.worst for ch, f in zip(CHANNELS, fit.channels)},
            "bias_in_run_spread": dict(zip(CHANNELS, fit.spread.tolist())),
            "bias_note": "the record's mean less the Earth rate's vertical part and gravity's magnitude; the "
                         "horizontal parts cannot be told from heading and tilt; bias_in_run_spread is the std of "
                         "the means of the record's tenths (the run-to-run spread needs several records)"}
    source = f"fitted by sarins allan --write-preset to {args.log}"
    target = Path(args.write_preset)
    if target.suffix.lower() == ".ssv":
        with tempfile.TemporaryDirectory() as tmp:
            preset = imu_preset_file.write_preset(Path(tmp) / "preset.json", fit.model, name=name, source=source,
                                                  info=info)
            imu_preset_file.write_ssv(target, preset, name=name)
    else:
        imu_preset_file.write_preset(target, fit.model, name=name, source=source, info=info)
    worst = max(f.worst for f in fit.channels)
    if not math.isfinite(worst):
        worst = float("nan")
    return {"file": str(target), "worst_model_deviation": worst, "fit_from_s": allan_preset.FIT_FROM,
            "fit_to_s": allan_preset.FIT_TO * result.record_length}
