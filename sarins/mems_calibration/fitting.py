"""Seed 003's fitted models: fitting, plain model files on disk, reuse while nothing they depend on changed.

Fitted models are keyed by :func:`models_key` (the recordings they were
fitted on, the fitting options, the library's code and this module), so
report-only changes elsewhere in the application never force a refit.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

# controls, not seed 003's models: the one-layer LSTM / GRU trained and run without memory
# (every sample from a zero state): what the same network does with the current input alone
CONTROLS = {"lstm-memoryless": "lstm", "gru-memoryless": "gru"}
RECURRENT = ("lstm", "gru", "lstm3", "gru3") + tuple(CONTROLS)
RNN_WINDOW, RNN_STREAMS = 100, 32  # truncated-BPTT window (samples) and parallel streams (seed 003 gives neither)


# one training step, CPU ms (window 100, 32 streams, one thread; the 2-core machine of 2026-12-07, the paper
# campaign's fit CPU / 4000 steps, the quick campaign's within 10 %): the campaign's time estimate, and the
# order of the fits, longest first
STEP_MS = {"lstm": 5.7, "gru": 14.9, "lstm3": 16.0, "gru3": 49.8, "lstm-memoryless": 5.9, "gru-memoryless": 6.1}
_TRAIN = None  # the training set a forked fitting process inherits (not pickled to it)


def fit_models(kinds, train, fit, *, rnn_steps: int, grnn_patterns: int, rbf_samples: int, seed: int = 0,
               log=None, workers: int | None = None, device: str = "cpu") -> dict:
    """Fitted compensators by name (the traditional one from the calibration fit ``fit``; the controls of
    :data:`CONTROLS` as memoryless recurrent compensators) on ``train``: a data set in memory, or a
    :class:`.storage.StoredSet`, which every fit (in the fitting processes and in this one) reads from disk a
    slice at a time: no process holds it whole (the same numbers, tests/test_mems_calibration.py).

    The recurrent fits (one torch thread each) run side by side in ``workers`` forked processes (default
    ``SARINS_THREADS`` or every core), longest first; the others in this process meanwhile.  Each fit is
    seeded, so the models do not depend on ``workers``.  ``log``: optional callable taking one line of
    progress text.  ``device``: where torch trains the recurrent models (a name
    :func:`sarins_fmu.identify.recurrent.training_device` has resolved); on a GPU they are fitted one after
    another in this process (one GPU, and CUDA does not survive a fork), the other models after them.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from sarins_fmu.core.imu import thread_count

    global _TRAIN
    stored = hasattr(train, "column")  # a StoredSet: the fitting processes read it from disk
    rnn = dict(steps=rnn_steps, seed=seed, seq_len=RNN_WINDOW, streams=RNN_STREAMS, device=device)
    options = {"rbf": dict(max_samples=rbf_samples), "grnn": dict(max_patterns=grnn_patterns)}
    recurrent_kinds = sorted((k for k in kinds if k in RECURRENT), key=lambda k: -STEP_MS.get(k, 100.0))
    workers = min(len(recurrent_kinds), thread_count() if workers is None else int(workers))
    if device != "cpu":
        workers = 1
    models, pending = {}, {}
    pool = None
    if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
        _TRAIN = None if stored else train
        pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"))
        if log:
            log(f"mems-calibration: fitting {', '.join(recurrent_kinds)} on {len(train)} samples ({workers} "
                "processes, longest first)")
        for kind in recurrent_kinds:  # (the processes are forked at the first submission)
            pending[kind] = pool.submit(_fit_recurrent, kind, rnn, train if stored else None)
    try:
        for kind in kinds:
            if kind in pending:
                continue
            if log:
                log(f"mems-calibration: fitting {kind} on {len(train)} samples")
            if kind == "traditional":
                t0 = time.perf_counter()
                model = compensators_module().TraditionalCompensator(fit.gyro, fit.accel)
                model.fit_seconds = time.perf_counter() - t0
            elif kind in RECURRENT:
                model = _fit_recurrent(kind, rnn, train)
            else:
                model = compensators_module().make(kind, **options[kind]).fit(*_columns(train))
            models[kind] = model
        names = {future: kind for kind, future in pending.items()}
        for future in as_completed(names):
            models[names[future]] = future.result()
            if log:
                log(f"mems-calibration: fitted {names[future]} ({models[names[future]].fit_seconds:.0f} s)")
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
        _TRAIN = None
    return {k: models[k] for k in kinds}


def compensators_module():
    from sarins_fmu.identify import compensators

    return compensators


def _columns(train) -> tuple:
    """(X, Y) of a data set: its arrays, or a :class:`.storage.StoredSet`'s columns read a slice at a time."""
    if hasattr(train, "column"):
        return train.column("X"), train.column("Y")
    return train.X, train.Y


def _fit_recurrent(kind: str, rnn: dict, train=None):
    """One recurrent compensator (or memoryless control) fitted on ``train`` (default the inherited set; a
    :class:`.storage.StoredSet` is read from disk a slice at a time, the same numbers)."""
    X, Y = _columns(_TRAIN if train is None else train)
    compensators = compensators_module()
    if kind in CONTROLS:
        return compensators.make(CONTROLS[kind], memory=False, **rnn).fit(X, Y)
    return compensators.make(kind, **rnn).fit(X, Y)


def _index(model_dir: Path) -> dict:
    """``<model_dir>/index.json`` as a dict ({} when missing or unreadable)."""
    try:
        index = json.loads((model_dir / "index.json").read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return {}
    return index if isinstance(index, dict) else {}


def _stored_models(model_dir: Path, kinds, key: str) -> dict:
    """Models of an earlier run made from the same recordings, options and code (``models_key`` in
    ``<model_dir>/index.json``, with their fit times); an unreadable model file is fitted again with a
    notice."""
    from sarins_fmu.identify import compensators

    index = _index(model_dir)
    if index.get("models_key") != key:
        return {}
    fit_times = index.get("fit_s") if isinstance(index.get("fit_s"), dict) else {}
    stored = {}
    for kind in kinds:
        path = model_dir / f"{kind}.npz"
        if path.exists():
            try:
                model = compensators.load(path)
            except (ValueError, OSError) as exc:
                print(f"mems-calibration: refitting {path}: {' '.join(str(exc).split())}", file=sys.stderr)
                continue
            seconds = fit_times.get(kind)
            model.fit_seconds = float(seconds) if isinstance(seconds, (int, float)) else model.fit_seconds
            cpu = (index.get("fit_cpu_s") if isinstance(index.get("fit_cpu_s"), dict) else {}).get(kind)
            model.fit_cpu_seconds = float(cpu) if isinstance(cpu, (int, float)) else None
            stored[kind] = model
    return stored


def model_set(model_dir: Path, kinds, train, fit, recs, options: dict, *, refit=False, log=None):
    """The fitted models of one training set: reused from ``model_dir`` when made from the same
    recordings ``recs`` (or their :func:`models_key` with these options, a str), options and code, else
    fitted and saved there.

    Returns (models, reused names, load): ``load`` is the machine's 1-min
    load average before and after the fits that made the models' fit times
    (from the index when every model is reused; None if unknown).
    """
    from sarins.campaign import atomic_output, write_text

    model_dir.mkdir(parents=True, exist_ok=True)
    key = recs if isinstance(recs, str) else models_key(recs, options)
    stored = {} if refit else _stored_models(model_dir, kinds, key)
    todo = [k for k in kinds if k not in stored]
    load_before = os.getloadavg()[0]
    fitted = fit_models(todo, train, fit, log=log, **options)
    load = [load_before, os.getloadavg()[0]] if todo else _index(model_dir).get("fit_load_average")
    models = {k: stored.get(k) or fitted[k] for k in kinds}
    for name, model in fitted.items():
        with atomic_output(model_dir / f"{name}.npz", keep_suffix=True) as tmp:
            model.save(tmp)
    index = dict(models_key=key, fit_s={k: m.fit_seconds for k, m in models.items()},
                 fit_cpu_s={k: getattr(m, "fit_cpu_seconds", None) for k, m in models.items()}, fit_load_average=load)
    write_text(model_dir / "index.json", json.dumps(index, indent=1))
    return models, sorted(stored), load


def step_costs(kinds) -> dict:
    """ms per recurrent training step (window 100, 32 streams, one thread) of LSTM and GRU, one layer,
    with PyTorch's oneDNN RNN path on and off: why the GRU trains slower ({} without recurrent models)."""
    from sarins_fmu.identify import recurrent

    if not any(k in RECURRENT for k in kinds):
        return {}
    return {cell: {("onednn" if on else "no_onednn"): 1e3 * recurrent.training_step_seconds(cell, steps=10, onednn=on)
                   for on in (True, False)} for cell in recurrent.CELLS}


def models_key(recs, options: dict) -> str:
    """Identity of fitted models: the recordings they were fitted on ({kind: recording}; a mapping that loads
    each on access holds one at a time), the fitting options and the code."""
    digest = models_digest(options)
    for kind in sorted(recs):
        digest_recording(digest, recs[kind])
    return digest.hexdigest()


def models_digest(options: dict):
    """The SHA-256 of :func:`models_key` before the recordings: the options and the code.  Feed it the
    recordings with :func:`digest_recording` in the order of their kinds' names."""
    import hashlib

    from sarins.campaign import canonical_json, code_hash

    digest = hashlib.sha256(canonical_json(options).encode())
    digest.update(code_hash([__file__]).encode())
    return digest


def digest_recording(digest, rec: dict) -> None:
    """Add one recording's arrays (``wall_s`` aside) to a :func:`models_digest`."""
    import numpy as np

    for key in sorted(rec):
        if key != "wall_s":
            digest.update(key.encode())
            value = rec[key]
            if hasattr(value, "blocks"):  # read from disk a block at a time: the same bytes in order
                for block in value.blocks():
                    digest.update(np.ascontiguousarray(block).tobytes())
            else:
                digest.update(np.ascontiguousarray(value).tobytes())
