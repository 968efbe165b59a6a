"""``sarins campaign mems-calibration``: seed 003's dynamic calibration, end to end.

1. Build the Turntable and IMUThermal FMUs (into ``<out>/fmus``).
2. Co-simulate the recordings through the master, as a resumable campaign
   (``<out>/recordings/<id>.npz``): the training run ('dynamic'), the
   held-out run on another table and chamber programme in the same session
   ('heldout') and after another power-up ('repowered'), the tumble and the
   rate test; with ``--ablation``, the training and held-out runs again
   with one time-correlated error term switched off.
3. Fit the traditional model (tumble + rate test) and the RBFNN, GRNN,
   LSTM, GRU (one and three recurrent layers) and the memoryless controls
   (dynamic training set); save them as plain model files
   (``<out>/models``, reused while recordings, options and code are the same).
4. Evaluate on the held-out set; write ``summary.json``, the Markdown
   report and the figures (``<out>`` or ``--report-dir``).

The recurrent models need PyTorch (``pip install 'sarins-fmu[deep]'``);
without it they are skipped with that message and the others still run.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from sarins.cli import bounded_int, seed_value

from .fitting import CONTROLS, RECURRENT, RNN_STREAMS, RNN_WINDOW, model_set, models_key, step_costs
from .progress import Progress

HELP = ("seed 003: MEMS IMU dynamic calibration on a 3-axis thermal rate table (traditional, RBFNN, GRNN, "
        "LSTM, GRU; held-out programme, ablation of the time-correlated errors)")

MODEL_DEFAULTS = {  # per profile: recurrent training steps, GRNN patterns, RBF training samples
    "quick": dict(rnn_steps=400, grnn_patterns=5000, rbf_samples=10000),
    "paper": dict(rnn_steps=4000, grnn_patterns=20000, rbf_samples=50000),
}
# per profile: samples of the third power-up evaluated, from its start; None: as many as the held-out run.
# The quick profile (a smoke run) checks a quarter of its held-out length there; the training run's tail is
# always as long as the held-out run (the report compares the two).
CHECK_SAMPLES = {"quick": 288_000, "paper": None}
DEFAULT_ABLATION_MODELS = "rbf,grnn,lstm,lstm-memoryless"


def _model_names():
    from sarins_fmu.identify import compensators

    return compensators.KINDS + tuple(CONTROLS)


def add_arguments(parser) -> None:
    names = ",".join(_model_names())
    parser.add_argument("--models", default=names, help=f"comma-separated subset of {names} (default: all)")
    parser.add_argument("--rnn-steps", type=bounded_int(1, 1_000_000), default=None,
                        help="recurrent training steps, 1 .. 10**6 (default: quick 400, paper 4000 as the paper)")
    parser.add_argument("--grnn-patterns", type=bounded_int(1, 200_000), default=None,
                        help="GRNN pattern-layer size, evenly spaced training samples, 1 .. 200000 "
                             "(quick 5000, paper 20000)")
    parser.add_argument("--rbf-samples", type=bounded_int(1, 1_000_000), default=None,
                        help="RBF training samples, evenly spaced, 1 .. 10**6 (quick 10000, paper 50000)")
    parser.add_argument("--engine", choices=("cosim", "inprocess"), default="inprocess",
                        help="record in process on the library functions the FMUs run (default: the same numbers, "
                             "tests/test_mems_calibration.py, about 20 times faster at the paper's 200 Hz) or "
                             "through the Turntable and IMUThermal FMUs under the master (cosim)")
    parser.add_argument("--ablation", default="none",
                        help="time-correlated error terms and output dynamics to switch off one at a time, "
                             "comma-separated, from die-lag,gradient,hysteresis,flicker,rate-random-walk,turn-on,"
                             "rate-hysteresis,output-filter,size-effect,all ('all': every term at once), or 'every' "
                             "or 'none' (default)")
    parser.add_argument("--ablation-models", default=DEFAULT_ABLATION_MODELS,
                        help=f"models fitted again for each ablation (default {DEFAULT_ABLATION_MODELS})")
    parser.add_argument("--seed", type=seed_value, default=3,
                        help="base random seed of the campaign: the IMU noise of the recordings, 0 .. 2**31-1 "
                             "(default 3; the held-out runs use seed + 1; the networks' initialisation has its own "
                             "fixed seed)")
    parser.add_argument("--report-dir", default=None, help="write report.md and the PNGs here (default: --out)")
    parser.add_argument("--calibrate", action="store_true",
                        help="also fit one factor on the mems preset's unsourced time-correlated sizes so that the "
                             "traditional model's held-out std reduction is seed 003 Table 3's 4.7 %% (quick-profile "
                             "trials, in process) and run the campaign on that calibrated unit too (report section "
                             "'Calibrated unit'; the headline stays the sourced unit's)")
    parser.add_argument("--device", default="auto",
                        help="where torch trains the recurrent models: auto (default: a CUDA GPU when torch sees "
                             "one, else the CPU), cpu, cuda or cuda:N; the networks are evaluated on the CPU either "
                             "way (docs/mems-calibration.md, 'Training device')")
    parser.add_argument("--refit", action="store_true",
                        help="fit the models again even if <out>/models holds them from a run with the same options")


def _name_list(text: str, allowed, what: str) -> list:
    names = [k.strip() for k in text.split(",") if k.strip()]
    unknown = [k for k in names if k not in allowed]
    if unknown or not names:
        raise ValueError(f"unknown {what}(s) {unknown}; choose from {', '.join(allowed)}")
    return names


def _ablations(text: str) -> list:
    from sarins_fmu.experiments.mems_calibration import ABLATIONS

    if text.strip() in ("none", ""):
        return []
    if text.strip() == "every":
        return list(ABLATIONS)
    return _name_list(text, ABLATIONS, "ablation")


def run(args) -> int:
    from sarins_fmu.identify import recurrent

    kinds = _name_list(args.models, _model_names(), "model")
    ablation_kinds = _name_list(args.ablation_models, [k for k in _model_names() if k != "traditional"],
                                "ablation model")
    ablations = _ablations(args.ablation)
    _refuse_unused(args, kinds, ablation_kinds if ablations else [], bool(ablations))
    if not ablations:
        ablation_kinds = []
    options = dict(MODEL_DEFAULTS[args.profile])
    for key in ("rnn_steps", "grnn_patterns", "rbf_samples"):
        if getattr(args, key) is not None:
            options[key] = getattr(args, key)
    options["device"] = _device(args, kinds + ablation_kinds)
    skipped = []
    if any(k in RECURRENT for k in kinds + ablation_kinds) and not recurrent.torch_available():
        skipped = sorted({k for k in kinds + ablation_kinds if k in RECURRENT})
        kinds = [k for k in kinds if k not in skipped]
        ablation_kinds = [k for k in ablation_kinds if k not in skipped]
        print(f"skipping {', '.join(skipped)}: {recurrent.INSTALL_HINT}", file=sys.stderr)
    calibrated = None
    if getattr(args, "calibrate", False):
        calibrated = run_calibrated(args.profile, Path(args.out), kinds=kinds, workers=args.workers,
                                    scheduler=args.scheduler, progress=not args.no_progress, seed=args.seed,
                                    refit=args.refit, engine=args.engine, check_samples=CHECK_SAMPLES[args.profile],
                                    **options)
    summary = run_mems_calibration(args.profile, Path(args.out), kinds=kinds, workers=args.workers,
                                   scheduler=args.scheduler, progress=not args.no_progress, seed=args.seed,
                                   report_dir=args.report_dir, skipped=skipped, refit=args.refit,
                                   ablations=ablations, ablation_kinds=ablation_kinds, engine=args.engine,
                                   check_samples=CHECK_SAMPLES[args.profile], calibrated=calibrated, **options)
    for name, red in summary["reductions"].items():
        print(f"{name:16s} mean {red['mean']:6.1f} %  std {red['std']:6.1f} %  mean-abs {red['mae']:6.1f} %  "
              f"systematic {red['sys']:6.1f} %")
    if calibrated:
        fit = calibrated["fit"]
        print(f"calibrated unit: k = {fit['k']:.4g} ({len(fit['trials'])} trials, {fit['wall_seconds']:.0f} s): "
              f"traditional std reduction {fit['std_reduction']:.2f} % (target {fit['target_std']} %)")
    print(f"report: {summary['report']}")
    return 0


def calibrated_folder(out: Path, k: float) -> Path:
    """Where the campaign on the unit calibrated with factor ``k`` keeps its recordings, models and report."""
    return Path(out) / f"calibrated-k{k:.4g}"


def run_calibrated(profile_name: str, out: Path, *, kinds, seed=3, progress=True, **campaign) -> dict:
    """Fit the factor on the unsourced time-correlated sizes to seed 003, Table 3 (traditional std
    reduction; :func:`.calibrate.calibrate_traditional`, quick-profile trials in this process) and run
    the campaign on the calibrated unit (``profile_name``, models ``kinds``, no ablation) in
    :func:`calibrated_folder`.

    Returns {'fit': the :class:`.calibrate.TraditionalCalibration` as a dict, 'summary': the calibrated
    campaign's profile, n_test, reductions, order, table3 and report path} (summary key 'calibrated')."""
    from dataclasses import asdict

    from .calibrate import calibrate_traditional

    def log(text):
        if progress:
            print(text, file=sys.stderr)

    fit = calibrate_traditional(seed=seed, log=log)
    folder = calibrated_folder(out, fit.k)
    sub = run_mems_calibration(profile_name, folder, kinds=kinds, seed=seed, progress=progress, scale=fit.k, **campaign)
    keep = ("profile", "n_test", "reductions", "order", "table3", "report", "reductions_repowered", "scale")
    return {"fit": asdict(fit), "summary": {key: sub[key] for key in keep}}


def _device(args, kinds) -> str:
    """The training device of the recurrent models (``--device`` resolved before any fitting process
    forks; 'cpu' when no recurrent model is fitted or torch is missing).  UsageError for a device torch
    lacks, and for ``--device`` given when no recurrent model is fitted."""
    from sarins.cli import UsageError, refuse_unless
    from sarins_fmu.identify import recurrent

    fitted = any(k in RECURRENT for k in kinds)
    refuse_unless(args, {"device": "--device"}, fitted,
                  "applies to the recurrent models, none of which --models (or the ablation models) fits")
    try:
        return recurrent.training_device(getattr(args, "device", "auto")) if fitted else "cpu"
    except (ValueError, ImportError) as exc:
        raise UsageError(f"--device: {exc}") from None


def _refuse_unused(args, kinds, ablation_kinds, ablating: bool) -> None:
    """Refuse (exit 2) a fitting option none of the chosen models reads, and
    ``--ablation-models`` without an ablation: given, they would be ignored."""
    from sarins.cli import refuse_unless

    refuse_unless(args, {"ablation_models": "--ablation-models"}, ablating, "needs --ablation (no ablation is run)")
    fitted = set(kinds) | set(ablation_kinds)
    for dest, option, readers in (("rnn_steps", "--rnn-steps", set(RECURRENT)), ("grnn_patterns", "--grnn-patterns",
                                  {"grnn"}), ("rbf_samples", "--rbf-samples", {"rbf"})):
        refuse_unless(args, {dest: option}, bool(fitted & readers),
                      f"applies to {', '.join(sorted(readers))}, none of which --models (or the ablation models) "
                      "fits")


def record_all(profile_name: str, out: Path, *, workers=None, scheduler=None, progress=True, seed=3,
               ablations=(), engine: str = "cosim", scale: float = 1.0):
    """Build the FMUs and run the recordings as a resumable campaign: the five of the protocol, then the
    training and held-out runs of each ablation (ids ``dynamic.no-<term>``, ``heldout.no-<term>``);
    ``scale``: factor on the unsourced time-correlated sizes of every recording (1: the sourced unit).

    Returns {id: recording} as a :class:`.storage.StoredRecordings`: each stored recording is loaded when
    accessed, none is held here (the quick profile's five recordings are 0.7 GB).  ``workers`` (default every
    core): the in-process recordings are spooled to files in the recordings folder as they are computed, so a
    worker sends back only the spool files' names; the recordings are the same bits with any number of workers."""
    from .storage import StoredRecordings

    from fmus.build import build_fmus
    from sarins.campaign import Task, build_artifacts, code_hash, run_campaign

    from sarins_fmu.experiments import mems_calibration as mc

    from .recording import record_task

    if engine not in ("cosim", "inprocess"):
        raise ValueError(f"unknown engine {engine!r}; choose cosim or inprocess")
    names = ("Turntable", "IMUThermal")
    fmu_dir = out / "fmus"  # built in a temporary folder, moved into place, rebuilt when the code changes
    if engine == "cosim":
        build_artifacts(fmu_dir, [f"{n}.fmu" for n in names], lambda tmp: build_fmus(tmp, list(names), cross=False), code_hash())
    common = dict(profile_name=profile_name, fmu_dir=str(fmu_dir), seed=seed)
    volatile = ("fmu_dir",)
    if engine != "cosim":
        common["engine"] = engine  # (absent for cosim: the recordings' keys stay those of earlier campaigns)
        if not scheduler:  # (a Dask worker may not see this folder)
            # written there chunk by chunk and streamed into the result file (stale pieces: '.*.tmp', removed
            # by the campaign); no part of the result
            common["spool"] = str(out / "recordings")
            volatile += ("spool",)
    if float(scale) != 1.0:
        mc.scaled_overrides(scale)  # checks it
        common["scale"] = float(scale)  # (absent for the sourced unit, likewise)
    tasks = [Task(kind, record_task, dict(kind=kind, **common), volatile=volatile) for kind in mc.KINDS]
    tasks += [Task(f"{kind}.no-{term}", record_task, dict(kind=kind, ablation=term, **common), volatile=volatile)
              for term in ablations for kind in ("dynamic", "heldout")]
    return StoredRecordings(run_campaign(tasks, out / "recordings", workers=workers,
                                         scheduler=scheduler, progress=progress, description="mems-calibration recordings",
                                         keep=False))


def evaluate(models: dict, test, floor, *, log=None, stream_samples: int = 300):
    """Residuals on ``test`` and the cost of each model.

    Returns (residuals {name: (n', 6)} with 'raw' first, every :func:`thinning`-th row (what the figures
    plot), stats {name: dict} (of every row),
    info {name: n_parameters, fit_s, fit_cpu_s (the fitting thread's CPU seconds; None if unknown), predict_s
    (whole test set, batch, chunk by chunk; wall time, the evaluations of :func:`evaluate_sets` running side by
    side), predict_cpu_s (the evaluating thread's CPU seconds), stream_us (per sample, one at a time as in the
    compensator FMU)}).
    """
    return evaluate_sets(models, {"test": test}, floor, log=log, stream_samples={"test": stream_samples})["test"]


# rows evaluated at once: the GRNN's own chunks (its truncation unchanged), a few MB of temporaries per thread
EVAL_ROWS = 1 << 17


def _inputs(data, targets: list, reading: list):
    """The inputs X of ``data``, :data:`EVAL_ROWS` rows at a time, in order; each chunk's targets Y appended to
    ``targets`` and the seconds spent reading added to ``reading[0]``."""
    chunks = data.chunks(EVAL_ROWS)
    while True:
        t0 = time.perf_counter()
        try:
            X, Y = next(chunks)
        except StopIteration:
            return
        reading[0] += time.perf_counter() - t0
        targets.append(Y)
        yield X


def _residual_chunks(data, predict=None):
    """(residual chunk, prediction seconds) over ``data`` :data:`EVAL_ROWS` rows at a time, in order:
    ``predict`` (a model's :meth:`predict_batch_chunks`) minus the targets, or the raw output X[:, :6] - Y
    when None.  The seconds count the prediction only (not the reading of the rows)."""
    import numpy as np

    targets, reading = [], [0.0]
    if predict is None:
        for X in _inputs(data, targets, reading):
            yield X[:, :6] - targets.pop(0), 0.0
        return
    for out, seconds in _timed(predict(_inputs(data, targets, reading)), reading):
        yield np.subtract(out, targets.pop(0), out=out), seconds


def _timed(outputs, reading: list):
    """(item, seconds) for each item of the iterator ``outputs``: the seconds its making took, less the
    seconds of input reading counted in ``reading[0]`` meanwhile."""
    while True:
        t0, read0 = time.perf_counter(), reading[0]
        try:
            item = next(outputs)
        except StopIteration:
            return
        yield item, time.perf_counter() - t0 - (reading[0] - read0)


class _Summary:
    """Every :func:`thinning`-th residual row, the :class:`.analysis.ResidualSums` of every row and the
    prediction seconds of one model on one data set, fed a chunk of residual rows at a time in order."""

    def __init__(self, n: int):
        from . import analysis

        self.step, self.start, self.seconds = thinning(n), 0, 0.0
        self.sums, self.thinned = analysis.ResidualSums(), []

    def add(self, residual, seconds: float) -> None:
        self.thinned.append(residual[(-self.start) % self.step::self.step].copy())
        self.sums.add(residual)
        self.seconds += seconds
        self.start += len(residual)

    def result(self, floor) -> tuple:
        """(thinned rows, :func:`.analysis.residual_stats` of every row, prediction seconds)."""
        import numpy as np

        rows = np.concatenate(self.thinned) if self.thinned else np.empty((0, 6))
        return rows, self.sums.stats(floor), self.seconds


def _residual_summary(data, floor, predict=None):
    """(every :func:`thinning`-th residual row, :func:`.analysis.residual_stats` of every row, prediction
    seconds) of one model on one data set, chunk by chunk (:class:`.analysis.ResidualSums`: the whole
    array's statistics bit for bit)."""
    summary = _Summary(len(data))
    for residual, dt in _residual_chunks(data, predict):
        summary.add(residual, dt)
    return summary.result(floor)


def _streamed_summaries(model, sets: dict, floor) -> dict:
    """{set name: :func:`_residual_summary`} of a recurrent model on every set of ``sets`` at once, the sets
    advancing side by side (:meth:`~sarins_fmu.identify.compensators.RecurrentCompensator.predict_batch_streams`:
    each set's rows bit for bit those of its own run); each call's seconds shared between the sets by rows."""
    import numpy as np

    keys = list(sets)
    targets = {k: [] for k in keys}
    reading = [0.0]
    summaries = {k: _Summary(len(sets[k])) for k in keys}
    outputs = model.predict_batch_streams([_inputs(sets[k], targets[k], reading) for k in keys])
    for step, seconds in _timed(outputs, reading):
        rows = sum(len(out) for _, out in step)
        for index, out in step:
            key = keys[index]
            y = targets[key][0][:len(out)]
            targets[key][0] = targets[key][0][len(out):]
            if not len(targets[key][0]):
                targets[key].pop(0)
            summaries[key].add(np.subtract(out, y, out=out), seconds * len(out) / rows if rows else 0.0)
    return {k: summaries[k].result(floor) for k in keys}


def evaluate_sets(models: dict, sets: dict, floor, *, log=None, stream_samples=None, threads=None) -> dict:
    """:func:`evaluate` of every model on every dataset of ``sets`` ({name: Dataset, or a
    :class:`.storage.StoredSet` read from disk}), the (model, dataset) evaluations on ``threads`` threads
    (default ``SARINS_THREADS`` or every core; the C core releases the GIL), longest first, each
    :data:`EVAL_ROWS` rows at a time; ``stream_samples`` {set name: rows of the one-at-a-time timing}
    (default 0).  Returns {set name: (residuals, stats, info)} as :func:`evaluate`; the numbers do not depend
    on threads, and equal those of the whole sets in one piece bit for bit."""
    from concurrent.futures import ThreadPoolExecutor

    from sarins_fmu.core.imu import thread_count

    stream_samples = stream_samples or {}
    # a recurrent model runs on every set at once (the sets side by side in the C core, one job), the others
    # a job per set
    together = [name for name, model in models.items() if hasattr(model, "predict_batch_streams") and len(sets) > 1]
    jobs = [(name, key) for key in sets for name in models if name not in together] + [(name, None) for name in together]
    jobs.sort(key=lambda job: -_eval_us(job[0]) * (
        len(sets[job[1]]) if job[1] is not None else sum(len(d) for d in sets.values())))

    def one(job):
        name, key = job
        cpu0 = time.thread_time()  # the C core runs on this thread (it releases the GIL, starts no threads)
        if key is None:
            if log:
                log(f"mems-calibration: evaluating {name} on {' + '.join(str(len(d)) for d in sets.values())} "
                    f"samples ({', '.join(sets)}, side by side)")
            found = _streamed_summaries(models[name], sets, floor)
            cpu = time.thread_time() - cpu0
            total = sum(len(d) for d in sets.values())
            return {k: (*found[k], cpu * len(sets[k]) / total) for k in sets}
        data = sets[key]
        if log:
            log(f"mems-calibration: evaluating {name} on {len(data)} samples ({key})")
        rows, stats, seconds = _residual_summary(data, floor, models[name].predict_batch_chunks)
        return {key: (rows, stats, seconds, time.thread_time() - cpu0)}

    workers = max(1, min(len(jobs), thread_count() if threads is None else int(threads)))
    with ThreadPoolExecutor(workers) as pool:
        done = {(job[0], key): result for job, results in zip(jobs, pool.map(one, jobs))
                for key, result in results.items()}
    out = {}
    for key, data in sets.items():
        raw_rows, raw_stats, _ = _residual_summary(data, floor)
        residuals, stats = {"raw": raw_rows}, {"raw": raw_stats}
        info = {}
        n_stream = stream_samples.get(key, 0)
        head = next(data.chunks(n_stream))[0] if n_stream > 0 and len(data) else ()
        for name, model in models.items():
            residuals[name], stats[name], predict_s, predict_cpu_s = done.pop((name, key))
            fit_cpu = getattr(model, "fit_cpu_seconds", None)
            info[name] = dict(n_parameters=int(model.n_parameters), fit_s=float(model.fit_seconds or 0.0),
                              fit_cpu_s=None if fit_cpu is None else float(fit_cpu), predict_s=predict_s,
                              predict_cpu_s=predict_cpu_s, stream_us=_stream_us(model, head))
        out[key] = (residuals, stats, info)
    return out


FIGURE_POINTS = 4000  # points per panel of the residual figures (report.residual_figure's max_points)


def thinning(n: int) -> int:
    """Row step of the residuals kept for the figures: every row the figures plot, no other."""
    return max(1, n // FIGURE_POINTS)


# CPU cost of evaluating one sample, us (the evaluating thread's CPU seconds per sample, reading and residual
# sums included: the reference machine, the 2-core machine of 2026-12-07, paper campaign,
# summary['evaluation_cpu_s'] / samples, benchmarks/bench_mems_phases.py): orders the evaluations, longest
# first, and estimates the phase; the GRNN's grows with its patterns (:func:`_eval_us`)
EVAL_US_PER_SAMPLE = {"traditional": 0.17, "rbf": 0.24, "lstm": 2.2, "gru": 1.6, "lstm3": 7.0, "gru3": 5.6,
                      "lstm-memoryless": 1.4, "gru-memoryless": 1.0}
GRNN_US = (0.15, 0.042)  # GRNN: us per sample, fixed + per 1000 patterns (quick 5000: 0.35, paper 20000: 0.98)


def _eval_us(name: str, grnn_patterns: int = 20000) -> float:
    """Estimated evaluation CPU us per sample of model ``name`` (:data:`EVAL_US_PER_SAMPLE`; 1 for a name it
    lacks)."""
    if name == "grnn":
        return GRNN_US[0] + GRNN_US[1] * grnn_patterns / 1e3
    return EVAL_US_PER_SAMPLE.get(name, 1.0)


def _stream_us(model, rows) -> float | None:
    """Wall time per sample of the one-at-a-time compensation (the FMU's path), us; None without rows."""
    if not len(rows):
        return None
    stream = model.stream()
    t0 = time.perf_counter()
    for x in rows:
        stream.step(x)
    return (time.perf_counter() - t0) / len(rows) * 1e6


def _reductions(stats: dict) -> dict:
    from . import analysis

    return {name: analysis.reductions(s, stats["raw"]) for name, s in stats.items() if name != "raw"}


def run_ablations(ablations, recs, full_test, prof, kinds, out: Path, floor, options: dict, *, refit=False,
                  log=None) -> dict:
    """Per switched-off term: the models of ``kinds`` fitted again on the training run without it and
    evaluated on the held-out run without it, and the term's rms on the held-out run (``full_test``: the
    held-out set with every term, a Dataset or :class:`.storage.StoredSet`)."""
    from sarins_fmu.experiments import mems_calibration as mc

    from . import analysis

    from .storage import StoredSet

    result = {}
    if ablations and isinstance(full_test, StoredSet):
        full_test = full_test.load()
    for term in ablations:
        train_rec = _lazy(recs, f"dynamic.no-{term}")
        train = mc.dataset(train_rec, prof)
        key = models_key({"dynamic": train_rec}, options)
        del train_rec
        models, reused, _ = model_set(out / "models" / f"no-{term}", kinds, train, None, key, options,
                                      refit=refit, log=log)
        del train
        test = mc.dataset(_lazy(recs, f"heldout.no-{term}"), prof)
        _, stats, info = evaluate(models, test, floor, log=log, stream_samples=0)
        red = _reductions(stats)
        result[term] = dict(reductions=red, order=analysis.ordering(red), reused_models=reused,
                            fit_s={k: i["fit_s"] for k, i in info.items()},
                            term_rms=analysis.term_rms(full_test.X, test.X).tolist())
    return result


def build_datasets(recs, prof, folder: Path, options: dict, check_samples=None):
    """The data sets of the protocol's recordings, each recording read from its file a slice at a time
    (:meth:`.storage.StoredRecordings.lazy`) and each set written a part at a time (:func:`.storage.save_chunks`):
    neither a recording nor a set is held whole.

    Writes the held-out set, the third power-up's first ``check_samples`` (None: as many as the held-out
    set) and the training set to ``folder``; returns (training set, {'held-out', 'repowered', 'in-sample' (the
    training set's tail as long as the held-out set): StoredSet}, traditional fit, models key, {'dynamic',
    'heldout': programme series for the figure})."""
    from sarins_fmu.experiments import mems_calibration as mc

    from . import report as rep
    from .fitting import digest_recording, models_digest
    from .storage import save_chunks

    series, stored = {}, {}
    for kind, name in (("heldout", "held-out"), ("repowered", "repowered")):
        rec = _lazy(recs, kind)
        if kind == "heldout":
            series[kind] = rep.programme_series(rec)
        limit = None
        if kind == "repowered":
            limit = len(stored["held-out"]) if check_samples is None else min(int(check_samples),
                                                                               len(stored["held-out"]))
        stored[name] = save_chunks(folder, name, *mc.dataset_chunks(rec, prof), limit=limit)
        del rec
    digest = models_digest(options)  # the recordings in the order of models_key: dynamic, rates, tumble
    rec = _lazy(recs, "dynamic")
    digest_recording(digest, rec)
    series["dynamic"] = rep.programme_series(rec)
    train = save_chunks(folder, "training", *mc.dataset_chunks(rec, prof))
    del rec
    stored["in-sample"] = train.tail(len(stored["held-out"]))  # the training run's tail, read from its file
    rates = recs["rates"]
    digest_recording(digest, rates)
    tumble = recs["tumble"]
    digest_recording(digest, tumble)
    fit = mc.traditional_calibration(tumble, rates, prof)
    return train, stored, fit, digest.hexdigest(), series


def _lazy(recs, key: str) -> dict:
    """Recording ``key`` of ``recs`` with its large arrays read from disk a slice at a time when ``recs``
    is a :class:`.storage.StoredRecordings` (else as it is)."""
    return recs.lazy(key) if hasattr(recs, "lazy") else recs[key]


def run_mems_calibration(profile_name: str, out: Path, *, kinds, workers=None, scheduler=None, progress=True, seed=3,
                         report_dir=None, rnn_steps=400, grnn_patterns=5000, rbf_samples=10000, skipped=(),
                         refit=False, ablations=(), ablation_kinds=(), engine="inprocess", check_samples=None,
                         scale: float = 1.0, calibrated: dict | None = None, device: str = "cpu") -> dict:
    """The whole campaign; returns the summary (also written to ``<out>/summary.json``).

    Like the recordings, fitted models are reused: ``<out>/models/<kind>.npz``
    from an earlier run with the same recordings, options and code
    (``<out>/models/index.json``) is loaded instead of fitted again, unless
    ``refit``; likewise ``<out>/models/no-<term>/`` for each ablation.  ``check_samples``: samples of the
    third power-up evaluated, from its start (None: the held-out length).  ``scale``: factor on the mems
    preset's unsourced time-correlated sizes
    (:data:`~sarins_fmu.experiments.mems_calibration.CALIBRATED_TERMS`; 1: the sourced unit).
    ``calibrated``: the result of :func:`run_calibrated`, reported in the section 'Calibrated unit'.
    ``device``: where torch trains the recurrent models (resolved, :func:`.recurrent.training_device`).

    Memory: the recordings are streamed to disk as they are recorded and read back a slice at a time; the
    data sets are written to ``<out>/datasets`` a part at a time and read back a chunk at a time; the
    training set is held whole only by this process while it fits the non-recurrent models, after the
    recurrent fits' processes have forked (they read it from disk) (docs/mems-calibration.md, *Memory*).
    """
    from dataclasses import asdict

    import numpy as np

    from sarins.campaign import write_text
    from sarins_fmu import imu
    from sarins_fmu.experiments import mems_calibration as mc

    from . import analysis
    from . import report as rep

    out = Path(out)
    wall = {}
    load_start = os.getloadavg()[0]
    prof = mc.profile(profile_name)
    fit_options = dict(rnn_steps=rnn_steps, grnn_patterns=grnn_patterns, rbf_samples=rbf_samples)
    progress_lines = Progress(estimates(prof, kinds, engine, workers, check_samples, ablations, ablation_kinds,
                                        **fit_options), enabled=progress)
    progress_lines.start("recording", f"{len(mc.KINDS) + 2 * len(ablations)} recordings ({engine})")
    t0 = time.perf_counter()
    recs = record_all(profile_name, out, workers=workers, scheduler=scheduler, progress=progress, seed=seed,
                      ablations=ablations, engine=engine, scale=scale)
    wall["recording campaign (this call; 0 when resumed)"] = time.perf_counter() - t0
    for name in sorted(recs):
        wall[f"co-simulation {name}"] = _wall_s(recs.paths[name])
    progress_lines.start("datasets", "truth of every sample, the traditional calibration")
    report_dir = Path(report_dir) if report_dir else out
    report_dir.mkdir(parents=True, exist_ok=True)
    options = dict(rnn_steps=rnn_steps, grnn_patterns=grnn_patterns, rbf_samples=rbf_samples, device=device)
    train, sets, fit, key, series = build_datasets(recs, prof, out / "datasets", options, check_samples)
    figures = [rep.programme_figure(report_dir / "fig_programmes.png", series, prof).name]
    del series
    test = sets["held-out"]
    n_train, n_test, n_check = len(train), len(test), len(sets["repowered"])
    floor = analysis.noise_floor(imu.preset("mems"), prof.step)

    def log(text):
        progress_lines.note(text.removeprefix("mems-calibration: "))
    progress_lines.start("fitting", f"{len(kinds)} models")
    t0 = time.perf_counter()
    models, reused, fit_load = model_set(out / "models", kinds, train, fit, key, options, refit=refit, log=log)
    del train  # the evaluation reads the sets from disk
    wall["model fitting (this call)"] = time.perf_counter() - t0
    progress_lines.start("evaluation", f"{len(models)} models on 3 sets (2 x {n_test} + {n_check} samples)")
    t0 = time.perf_counter()
    evaluated = evaluate_sets(models, sets, floor, log=log, stream_samples={"held-out": 300})
    residuals, stats, info = evaluated["held-out"]
    stats_repowered, stats_in_sample = evaluated["repowered"][1], evaluated["in-sample"][1]
    evaluation_cpu = {name: {key: result[2][name]["predict_cpu_s"] for key, result in evaluated.items()}
                      for name in models}
    del evaluated
    wall["model evaluation"] = time.perf_counter() - t0
    red = _reductions(stats)
    progress_lines.start("ablation", f"{len(ablations)} terms switched off")
    t0 = time.perf_counter()
    ablation = run_ablations(ablations, recs, test, prof, ablation_kinds, out, floor, options, refit=refit, log=log)
    wall["ablation fits and evaluation"] = time.perf_counter() - t0

    progress_lines.start("report", "figures, per-step training costs, report.md")
    step = thinning(n_test)
    figures += rep.residual_figures(report_dir, test.time[::step], residuals)
    summary = dict(
        profile=profile_name, engine=engine, step=prof.step, cal_step=prof.cal_step, tumble_dwell=prof.tumble_dwell,
        warmup=prof.warmup, programmes={"training": asdict(prof.train), "held-out": asdict(prof.test)},
        seeds={k: mc.run_seed(k, seed) for k in mc.KINDS}, n_train=n_train, n_test=n_test, n_check=n_check,
        gyro_fit_rms_dps=fit.gyro_rms_residual * 180 / np.pi, accel_fit_rms_mg=fit.accel_rms_residual / rep.G_MG,
        noise_floor=floor.tolist(), models=info, wall_s=wall, reductions=red, order=analysis.ordering(red),
        reductions_repowered=_reductions(stats_repowered), reductions_in_sample=_reductions(stats_in_sample),
        step_cost_ms=step_costs(kinds), table3=rep.table3(stats, red),
        stats={n: {k: v.tolist() for k, v in s.items()} for n, s in stats.items()},
        ablation=ablation, options=options, seed=seed, reused_models=reused, rnn_window=RNN_WINDOW,
        load_average=[load_start, os.getloadavg()[0]], fit_load_average=fit_load,
        rnn_streams=RNN_STREAMS, phases=progress_lines.measured, scale=float(scale), evaluation_cpu_s=evaluation_cpu)
    if calibrated is not None:
        summary["calibrated"] = calibrated
    if skipped:
        from sarins_fmu.identify.recurrent import INSTALL_HINT

        summary.update(skipped=list(skipped), skip_reason=INSTALL_HINT)
    text = rep.markdown(summary, rep.calibration_tables(fit, imu.preset("mems")), figures)
    summary["report"] = str((report_dir / "report.md").resolve())
    write_text(report_dir / "report.md", text)
    progress_lines.start("done", f"report {summary['report']}")
    write_text(out / "summary.json", json.dumps(summary, indent=1))
    return summary


def _wall_s(path: Path) -> float:
    """The ``wall_s`` a stored recording holds (NaN without one), read without loading its arrays."""
    import numpy as np

    with np.load(path, allow_pickle=False) as data:
        return float(data["wall_s"]) if "wall_s" in data.files else float("nan")


# The campaign's cost model on the reference machine (the 2-core machine of 2026-12-07: quick and paper
# campaigns, benchmarks/bench_mems_phases.py).  Recording, CPU s per recorded sample: in process measured;
# co-simulated hypothetical (150 us per master step on an earlier machine, scaled by the in-process ratio 2.2/5)
RECORD_S_PER_SAMPLE = {"inprocess": 2.2e-6, "cosim": 66e-6}
DATASET_S_PER_SAMPLE = 0.68e-6  # truth and inputs of one dynamic sample, s
RBF_FIT_S_PER_SAMPLE = 1.4e-4  # RBF fit (2000 candidates, 30 neurons), CPU s per training sample


def estimates(prof, kinds, engine, workers, check_samples, ablations, ablation_kinds, *, rnn_steps, grnn_patterns,
              rbf_samples) -> dict:
    """Estimated seconds of each phase on the reference machine ({phase: s}, in order) from the campaign's
    cost model: recording and dataset cost per sample, recurrent training steps (:data:`.fitting.STEP_MS`)
    shared by the fitting processes, and C-core evaluation cost per sample (:data:`EVAL_US_PER_SAMPLE`)
    shared by the evaluation threads."""
    from sarins_fmu.core.imu import thread_count
    from sarins_fmu.experiments import mems_calibration as mc

    from .fitting import STEP_MS

    cores = thread_count()
    parallel = max(1, min(cores, workers or cores))
    n = {k: mc.stop_time(k, prof) / (prof.step if k in mc.DYNAMIC_KINDS else prof.cal_step) for k in mc.KINDS}
    n_dyn = n["dynamic"] + n["heldout"] + n["repowered"]
    n_check = n["heldout"] if check_samples is None else min(check_samples, n["heldout"])

    def fits(names):  # the recurrent fits in the fitting processes, the RBF in this one beside them
        steps = [rnn_steps * STEP_MS.get(k, 100.0) / 1e3 for k in names if k in RECURRENT]
        rbf = RBF_FIT_S_PER_SAMPLE * min(rbf_samples, n["dynamic"]) if "rbf" in names else 0.0
        return max((sum(steps) + rbf) / parallel, max(steps, default=0.0), rbf) + 1.0

    def evaluations(names, samples):
        return sum(_eval_us(k, grnn_patterns) for k in names) * samples / 1e6 / cores

    record = RECORD_S_PER_SAMPLE[engine] * (sum(n.values()) + 2 * len(ablations) * (n["dynamic"] + n["heldout"]))
    record_parallel = workers or cores
    return {"recording": record / max(1, min(cores, record_parallel)) + 0.5, "datasets": DATASET_S_PER_SAMPLE * n_dyn,
            "fitting": fits(kinds), "evaluation": evaluations(kinds, 2 * n["heldout"] + n_check),
            "ablation": len(ablations) * (fits(ablation_kinds) + evaluations(ablation_kinds, n["heldout"])),
            "report": 1.0 + (1.2 if any(k in RECURRENT for k in kinds) else 0.0), "done": 0.0}
