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


def fit_models(kinds, train, fit, *, rnn_steps: int, grnn_patterns: int, rbf_samples: int, seed: int = 0,
               log=None) -> dict:
    """Fitted compensators by name (the traditional one from the calibration fit ``fit``; the controls of
    :data:`CONTROLS` as memoryless recurrent compensators).

    ``log``: optional callable taking one line of progress text.
    """
    from sarins_fmu.identify import compensators

    rnn = dict(steps=rnn_steps, seed=seed, seq_len=RNN_WINDOW, streams=RNN_STREAMS)
    models = {}
    for kind in kinds:
        if log:
            log(f"mems-calibration: fitting {kind} on {len(train)} samples")
        if kind == "traditional":
            t0 = time.perf_counter()
            model = compensators.TraditionalCompensator(fit.gyro, fit.accel)
            model.fit_seconds = time.perf_counter() - t0
        elif kind in CONTROLS:
            model = compensators.make(CONTROLS[kind], memory=False, **rnn).fit(train.X, train.Y)
        else:
            opts = {"rbf": dict(max_samples=rbf_samples), "grnn": dict(max_patterns=grnn_patterns)}.get(kind, rnn)
            model = compensators.make(kind, **opts).fit(train.X, train.Y)
        models[kind] = model
    return models


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
            stored[kind] = model
    return stored


def model_set(model_dir: Path, kinds, train, fit, recs: dict, options: dict, *, refit=False, log=None):
    """The fitted models of one training set: reused from ``model_dir`` when made from the same
    recordings ``recs``, options and code, else fitted and saved there.

    Returns (models, reused names, load): ``load`` is the machine's 1-min
    load average before and after the fits that made the models' fit times
    (from the index when every model is reused; None if unknown).
    """
    from sarins.campaign import atomic_output, write_text

    model_dir.mkdir(parents=True, exist_ok=True)
    key = models_key(recs, options)
    stored = {} if refit else _stored_models(model_dir, kinds, key)
    todo = [k for k in kinds if k not in stored]
    load_before = os.getloadavg()[0]
    fitted = fit_models(todo, train, fit, log=log, **options)
    load = [load_before, os.getloadavg()[0]] if todo else _index(model_dir).get("fit_load_average")
    models = {k: stored.get(k) or fitted[k] for k in kinds}
    for name, model in fitted.items():
        with atomic_output(model_dir / f"{name}.npz", keep_suffix=True) as tmp:
            model.save(tmp)
    index = dict(models_key=key, fit_s={k: m.fit_seconds for k, m in models.items()}, fit_load_average=load)
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


def models_key(recs: dict, options: dict) -> str:
    """Identity of fitted models: the recordings they were fitted on, the
    fitting options and the code."""
    import hashlib

    import numpy as np

    from sarins.campaign import canonical_json, code_hash

    digest = hashlib.sha256(canonical_json(options).encode())
    digest.update(code_hash([__file__]).encode())
    for kind in sorted(recs):
        for key in sorted(recs[kind]):
            if key != "wall_s":
                digest.update(key.encode())
                digest.update(np.ascontiguousarray(recs[kind][key]).tobytes())
    return digest.hexdigest()
