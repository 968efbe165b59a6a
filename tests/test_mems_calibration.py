"""Seed 003: recordings, traditional calibration, compensators, the quick campaign."""

import json
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu import imu, turntable
from sarins_fmu.experiments import mems_calibration
from sarins.mems_calibration.recording import record_cosim
from sarins_fmu.identify import compensators, recurrent
from sarins_fmu.identify.modelfile import ModelFileError

QUICK = mems_calibration.PROFILES["quick"]
ROOT = Path(__file__).resolve().parents[1]

needs_torch = pytest.mark.skipif(not recurrent.torch_available(),
                                 reason="PyTorch is not installed (pip install 'sarins-fmu[deep]')")

MIS_G = np.array([[0, 2e-3, -1e-3], [1.5e-3, 0, 3e-4], [-2e-3, 1e-3, 0]])
MIS_A = np.array([[0, -1e-3, 5e-4], [7e-4, 0, -2e-3], [1e-3, 2e-3, 0]])
GYRO = imu.TriadErrors(bias=[1e-4, -2e-4, 3e-4], scale_factor=[1e-3, -5e-4, 2e-3], misalignment=MIS_G)
ACCEL = imu.TriadErrors(bias=[0.02, -0.01, 0.03], scale_factor=[2e-3, -1e-3, 5e-4], misalignment=MIS_A)


class NonRotatingBase:
    """A base with gravity but no Earth rotation (the moving-base interface of sarins_fmu.imu)."""

    def base_motion(self, t_start, h):
        n = len(t_start)
        return np.zeros((n, 3)), np.tile([0.0, 0.0, 9.8], (n, 1))


def _fit_noise_free(model, base=None):
    tumble = mems_calibration.record_in_process("tumble", QUICK, model=model, base=base)
    rates = mems_calibration.record_in_process("rates", QUICK, model=model, base=base)
    return mems_calibration.traditional_calibration(tumble, rates, QUICK, base=base)


def _rel(fitted, triad):
    k = np.eye(3) + np.diag(triad.scale_factor) + triad.misalignment
    return (np.max(np.abs(fitted.bias - triad.bias)) / np.max(np.abs(triad.bias)),
            np.max(np.abs(fitted.matrix - k)) / np.max(np.abs(k - np.eye(3))))


def test_traditional_fit_recovers_noise_free_gyro_triad():
    """Gyro bias, scale factors and misalignment from the simulated tumble + rate test, 1e-9 relative."""
    fit = _fit_noise_free(imu.ImuModel(gyro=GYRO))
    assert max(_rel(fit.gyro, GYRO)) < 1e-9
    assert fit.gyro_rms_residual < 1e-12


def test_traditional_fit_recovers_noise_free_accelerometer_triad():
    """Accelerometer triad from the tumble, 1e-9 relative.  Gyros error-free and a base without
    Earth rotation: any rotation inside a step turns the accelerometer errors inside the velocity
    increment (rotation compensation), a real h-dependent effect of 1e-5 relative here."""
    fit = _fit_noise_free(imu.ImuModel(accel=ACCEL), NonRotatingBase())
    assert max(_rel(fit.accel, ACCEL)) < 1e-9


def test_tumble_and_rate_test_schemes_are_the_library_schedules():
    s1 = turntable.schedule_for("tumble-24", 1.0, dwell=10.0, rate_dps=10.0, accel_dps2=10.0)
    s2, pos = turntable.tumble_24(dwell=10.0)
    assert np.array_equal(s1.times, s2.times) and np.array_equal(s1.accel, s2.accel) and len(pos) == 24
    r1 = turntable.schedule_for("rate-test", 1.0, rate_dps=10.0, accel_dps2=10.0)
    r2, windows = turntable.rate_test()
    assert np.array_equal(r1.times, r2.times) and len(windows) == 66
    assert turntable.gimbal_axes_of("rate-test") == turntable.gimbal_axes_of("tumble-24") == "z,x,y"


@pytest.mark.parametrize("changes", [dict(step=0.0), dict(step=0.3), dict(cal_step=1.0), dict(train=dict(cycles=0)),
                                     dict(test=dict(cycles=1.5)), dict(warmup=-1.0),
                                     dict(train=dict(ramp_c_per_min=float("nan"))), dict(test=dict(first="middle")),
                                     dict(test=dict(rates_dps=(1.0, 0.0, 80.0))), dict(train=dict(low_c=50.0)),
                                     dict(test=dict(step_c=-1.0)), dict(train=dict(accels_dps2=(1.0, 2.0)))])
def test_bad_profiles_rejected(changes):
    with pytest.raises(ValueError):
        mems_calibration.with_profile(QUICK, **changes)


def test_unknown_profile_and_recording_rejected():
    with pytest.raises(ValueError, match="profile"):
        mems_calibration.profile("huge")
    with pytest.raises(ValueError, match="recording"):
        mems_calibration.turntable_parameters("spin", QUICK)
    with pytest.raises(ValueError, match="recording"):
        mems_calibration.schedule_of("spin", QUICK)
    with pytest.raises(ValueError, match="ablation"):
        mems_calibration.ablation_overrides("noise")


def test_heldout_programme_differs_from_training_within_its_envelope():
    """Held-out run: other rates, accelerations, chamber set points, ramp, holds and order, each inside the
    training run's range; the Turntable FMU parameters carry all of it."""
    for prof in mems_calibration.PROFILES.values():
        tr, te = prof.train, prof.test
        periods = [[4 * r / a for r, a in zip(run.rates_dps, run.accels_dps2)] for run in (tr, te)]
        assert all(a != b for a, b in zip(*periods)) and len(set(periods[1])) == 3  # out of phase
        assert all(b <= a for a, b in zip(tr.rates_dps, te.rates_dps)) and tr.rates_dps != te.rates_dps
        assert tr.low_c < te.low_c < te.high_c < tr.high_c and tr.first != te.first
        assert te.ramp_c_per_min < tr.ramp_c_per_min and te.step_c > 0 and tr.step_c == 0
        p = mems_calibration.turntable_parameters("heldout", prof)
        assert p["chamber_first"] == "high" and p["chamber_step"] == te.step_c
        assert p["table_outer_rate"] == pytest.approx(te.rates_dps[2] * np.pi / 180)
        amb = mems_calibration.ambient_of("heldout", prof)
        t = np.arange(0.0, prof.duration("heldout"), 10.0)
        assert amb(t).max() == te.high_c and amb(t).min() == te.low_c
        assert np.argmax(amb(t)) < np.argmin(amb(t))  # hot end first


def test_test_runs_are_other_power_ups_and_same_session_keeps_the_turn_on_bias():
    """'heldout' and 'repowered' are power-ups of their own (seeds s+1, s+2: new turn-on biases, no
    override); 'same-session' pins the training run's turn-on bias as a constant bias; an ablation zeroes
    its term everywhere (no turn-on added back)."""
    from sarins_fmu import imu_correlated

    seed = 3
    preset = imu.preset("mems")
    assert mems_calibration.recording_overrides("heldout", seed) == {}
    assert mems_calibration.recording_overrides("repowered", seed) == {}
    seeds = [mems_calibration.run_seed(k, seed) for k in ("dynamic", "heldout", "repowered")]
    assert seeds == [seed, seed + 1, seed + 2]
    ons = [imu_correlated.turn_on_bias(preset, s) for s in seeds]
    assert not np.allclose(ons[0], ons[1]) and not np.allclose(ons[1], ons[2])
    assert mems_calibration.run_seed("heldout", 2**31 - 1) == 0
    same = mems_calibration.recording_model("same-session", seed)
    assert np.allclose(same.gyro.bias, preset.gyro.bias + ons[0][:3], rtol=0, atol=1e-15)
    assert np.allclose(same.accel.bias, preset.accel.bias + ons[0][3:], rtol=0, atol=1e-15)
    assert not same.gyro.turn_on_bias.any() and not same.accel.turn_on_bias.any()
    off = mems_calibration.recording_model("same-session", seed, "turn-on")
    assert np.array_equal(off.gyro.bias, preset.gyro.bias)
    every = mems_calibration.recording_model("dynamic", seed, "all")
    assert not any(np.any(getattr(every.gyro, f)) for f in ("flicker", "hysteresis", "bias_dtdt", "turn_on_bias",
                                                             "rate_hysteresis", "filter_time_constant"))
    assert not any(every.thermal.die_time_constant) and not every.accel_lever_arm.any()


def test_profiles_record_at_the_papers_200_hz():
    assert all(p.step == pytest.approx(1 / 200) for p in mems_calibration.PROFILES.values())


def test_an_ablation_changes_only_its_term():
    """Same seed, one term off: the measured outputs differ by that term alone (white noise identical)."""
    prof = mems_calibration.with_profile(QUICK, step=0.05, warmup=20.0,
                                         test=dict(ramp_c_per_min=30.0, hold_min=0.5, step_hold_min=0.2))
    rec = {a: mems_calibration.record_in_process("heldout", prof, seed=4,
                                                 model=mems_calibration.recording_model("same-session", 3, a))
           for a in (None, "hysteresis", "flicker")}
    # gyro hysteresis: +-c_h once the play is taken up (scale factor and misalignment of 1e-3 on top)
    d_h = (rec[None]["dtheta"] - rec["hysteresis"]["dtheta"]) / prof.step
    c_h = np.abs(imu.preset("mems").gyro.hysteresis)
    assert np.all(np.abs(d_h) <= c_h * 1.001) and np.all(np.abs(d_h).max(axis=0) > 0.999 * c_h)
    d_f = (rec[None]["dtheta"] - rec["flicker"]["dtheta"]) / prof.step
    assert 0 < np.abs(d_f).std() < 10 * imu.preset("mems").gyro.flicker.max()  # a bias path, not white noise


# ------------------------------------------------------------------ compensators
def _toy_series(n=3000, seed=0):
    """A smooth input series and a truth with nonlinear, coupled, thermal errors (SI-like sizes)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    w = 0.5 * np.column_stack([np.sin(0.05 * t), np.cos(0.031 * t), np.sin(0.017 * t + 1)])
    f = np.column_stack([np.sin(0.01 * t), np.cos(0.013 * t), 9.8 + 0.1 * np.sin(0.02 * t)])
    temp = 10.0 + 20.0 * np.sin(0.002 * t)
    truth = np.column_stack([w, f])
    err = 1e-3 * np.column_stack([w ** 2 + np.tanh(w) * temp[:, None] / 20.0, 0.01 * f + w[:, [0]] ** 2])
    meas = truth + err + 1e-5 * rng.standard_normal(truth.shape)
    return np.column_stack([meas, temp]), truth


def test_grnn_compensator_is_nadaraya_watson_by_hand():
    """Two patterns, standardised inputs: the correction is the Gaussian-weighted mean (eqs 3-6)."""
    X = np.zeros((2, 7))
    X[1] = 2.0  # standardised: -1 and +1 in every column
    Y = np.zeros((2, 6))
    Y[0], Y[1] = -1.0, 4.0  # corrections d = Y - X[:, :6]: -1 and 2
    comp = compensators.GRNNCompensator(sigma=2.0).fit(X, Y)
    q = np.full((1, 7), 0.5)  # standardised -0.5 in every column
    d2 = np.array([7 * 0.5 ** 2, 7 * 1.5 ** 2])
    p = np.exp(-d2 / (2 * 2.0 ** 2))
    d = (p[0] * -1.0 + p[1] * 2.0) / p.sum()
    np.testing.assert_allclose(comp.predict(q), np.full((1, 6), 0.5 + d), rtol=1e-12)


@pytest.mark.parametrize("kind", ["traditional", "rbf", "grnn"])
@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_compensator_round_trip_and_stream(tmp_path, kind, suffix):
    X, Y = _toy_series()
    opts = {"rbf": dict(max_neurons=10), "grnn": dict(max_patterns=500)}.get(kind, {})
    comp = compensators.make(kind, **opts).fit(X[:2000], Y[:2000])
    back = compensators.load(comp.save(tmp_path / f"m{suffix}"))
    assert back.kind == kind
    np.testing.assert_allclose(back.predict(X[2000:]), comp.predict(X[2000:]), rtol=0, atol=1e-12)
    stream = back.stream()
    np.testing.assert_allclose(np.array([stream.step(x) for x in X[2000:2010]]), comp.predict(X[2000:2010]),
                               atol=1e-12)


@pytest.mark.parametrize("kind", ["rbf", "grnn"])
def test_networks_reduce_toy_errors(kind):
    X, Y = _toy_series()
    comp = compensators.make(kind).fit(X[::2], Y[::2])  # interleaved: the test samples lie inside
    raw = np.abs(X[1::2, :6] - Y[1::2]).mean()
    assert np.abs(comp.predict(X[1::2]) - Y[1::2]).mean() < 0.5 * raw


def test_bad_compensator_input_and_files(tmp_path):
    with pytest.raises(ValueError, match="unknown compensator"):
        compensators.make("svm")
    comp = compensators.make("traditional")
    with pytest.raises(ValueError):
        comp.fit(np.zeros((10, 6)), np.zeros((10, 6)))
    X, Y = _toy_series(200)
    X[3, 2] = np.nan
    with pytest.raises(ValueError):
        comp.fit(X, Y)
    with pytest.raises(ModelFileError, match="no such file"):
        compensators.load(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ModelFileError):
        compensators.load(bad)
    other = compensators.make("grnn").fit(*_toy_series(100)).net.save(tmp_path / "grnn.json")
    with pytest.raises(ModelFileError, match="format tag"):
        compensators.load(other)


def test_recurrent_parameter_counts():
    """PyTorch's counts (two bias vectors per gate): GRU about 24 % fewer than LSTM (seed 003) in both
    readings of the paper's '3-layer recurrent hidden layer'; layer l > 0 reads 60 hidden inputs."""
    lstm, gru = recurrent.n_parameters("lstm", 7, 60, 6), recurrent.n_parameters("gru", 7, 60, 6)
    assert (lstm, gru) == (16926, 12786)
    assert 0.23 < 1 - gru / lstm < 0.25
    lstm3, gru3 = recurrent.n_parameters("lstm", 7, 60, 6, 3), recurrent.n_parameters("gru", 7, 60, 6, 3)
    assert lstm3 == lstm + 2 * 4 * (60 * 60 * 2 + 2 * 60) and gru3 == gru + 2 * 3 * (60 * 60 * 2 + 2 * 60)
    assert 0.24 < 1 - gru3 / lstm3 < 0.25
    with pytest.raises(ValueError, match="layers"):
        compensators.RecurrentCompensator("gru", layers=2)
    with pytest.raises(ValueError, match="layers"):
        compensators.make("gru3", layers=1)


@needs_torch
def test_memoryless_control_is_a_map_of_the_current_input(tmp_path):
    """memory=False: each output depends on its own input only (permuting the inputs permutes the
    outputs), in torch, in the numpy cells and in the stream, and the option survives the model file."""
    X, Y = _toy_series(1200)
    comp = compensators.make("gru", hidden=16, steps=20, seq_len=50, streams=8, memory=False).fit(X[:1000], Y[:1000])
    perm = np.random.default_rng(0).permutation(200)
    x = X[1000:]
    # torch runs the batch in float32, and a row's place in the batch may change the kernel path (SIMD
    # body or tail): each row is then computed with other rounding.  From a zero state the GRU is
    # h = (1 - g_z) tanh(.) with gate inputs W_ih z + b_ih + b_hh (dot products of d + 2 terms), and the
    # output W_out h + b_out (H + 1 terms), scaled by target_scale in float64.  Bound (Higham 3.1, gamma_n
    # in float32; sigmoid and tanh are 1-Lipschitz and taken within 2 ulp of values <= 1, as torch's
    # vectorised functions are): |dh| <= 2 gamma_(d+2) max|W_ih||z| + |b| + 8 eps32, and
    # |dy| <= 2 scale (gamma_(H+1) (|W_out| 1 + |b_out|) + |W_out| |dh|).
    w = comp.weights
    layer = w._layer[0]
    eps32 = float(np.finfo(np.float32).eps)
    gamma = lambda n: n * eps32 / (1 - n * eps32)  # noqa: E731
    z = np.abs(comp._z(x))
    d, hidden = layer["w_ih"].shape[1], layer["w_hh"].shape[1]
    gates = (z @ np.abs(layer["w_ih"]).T + np.abs(layer["b_ih"]) + np.abs(layer["b_hh"])).max()
    dh = 2 * gamma(d + 2) * gates + 8 * eps32
    w_out = np.abs(w.w_out).sum(axis=1)
    bound = 2 * comp.target_scale * (gamma(hidden + 1) * (w_out + np.abs(w.b_out)) + w_out * dh)
    assert np.all(np.abs(comp.predict(x[perm]) - comp.predict(x)[perm]) <= bound)
    back = compensators.load(comp.save(tmp_path / "g.npz"))
    assert back.options["memory"] is False
    stream = back.stream()
    np.testing.assert_allclose(np.array([stream.step(r) for r in x[:50]]), comp.predict(x[:50]), rtol=0,
                               atol=1e-6 * np.abs(Y).max())
    with_memory = compensators.make("gru", hidden=16, steps=20, seq_len=50, streams=8).fit(X[:1000], Y[:1000])
    assert np.abs(with_memory.predict(x[perm]) - with_memory.predict(x)[perm]).max() > 1e-9


def test_one_layer_model_file_without_the_new_options_loads(tmp_path):
    """Recurrent files written before 'layers' and 'memory' existed still load as one layer with memory."""
    from sarins_fmu.identify.modelfile import save_model_file

    rng = np.random.default_rng(2)
    g, h = 3, 4
    arrays = {"net.w_ih": rng.standard_normal((g * h, 7)), "net.w_hh": rng.standard_normal((g * h, h)),
              "net.b_ih": np.zeros(g * h), "net.b_hh": np.zeros(g * h), "net.w_out": rng.standard_normal((6, h)),
              "net.b_out": np.zeros(6), "target_mean": np.zeros(6), "target_scale": np.ones(6),
              "input_mean": np.zeros(7), "input_scale": np.ones(7)}
    options = dict(hidden=h, steps=1, seq_len=10, streams=1, lr=1e-3, seed=0, threads=1)
    path = save_model_file(tmp_path / "old.npz", compensators.FORMAT_TAG, compensators.FORMAT_VERSION,
                           {"kind": "gru", "model": {"cell": "gru", "options": options}, "fit_seconds": 1.0}, arrays)
    model = compensators.load(path)
    assert model.kind == "gru" and model.weights.layers == 1 and model.options["memory"] is True
    assert model.predict(rng.standard_normal((5, 7))).shape == (5, 6)


@needs_torch
@pytest.mark.parametrize("cell", ["lstm", "gru"])
def test_recurrent_overfits_a_tiny_sequence(cell):
    rng = np.random.default_rng(1)
    z = rng.standard_normal((64, 7))
    t = np.column_stack([np.tanh(np.cumsum(z[:, :3], axis=0) / 4), z[:, 3:6] * 0.5])  # needs memory
    weights, losses = recurrent.train(cell, z, t, hidden=16, steps=150, seq_len=64, streams=1, lr=2e-2, seed=0,
                                      threads=1)
    assert losses[0] > 0.2 and losses[-1] < 0.01
    import torch

    net = recurrent._from_weights(torch, weights)
    assert sum(p.numel() for p in net.parameters()) == recurrent.n_parameters(cell, 7, 16, 6)


@needs_torch
@pytest.mark.parametrize("cell", ["lstm", "gru", "lstm3", "gru3"])
def test_recurrent_numpy_cells_equal_torch(tmp_path, cell):
    """Stacked layers included: the numpy cells (the FMU's path) run torch's network, float32 vs float64."""
    X, Y = _toy_series(1200)
    comp = compensators.make(cell, hidden=16, steps=20, seq_len=50, streams=8).fit(X[:1000], Y[:1000])
    assert comp.kind == cell and comp.weights.layers == (3 if cell.endswith("3") else 1)
    y_torch = comp.predict(X[1000:])
    y_numpy = comp._output(X[1000:], comp.weights.run(comp._z(X[1000:])))
    np.testing.assert_allclose(y_numpy, y_torch, rtol=0, atol=1e-6 * np.abs(Y).max())
    stream = compensators.load(comp.save(tmp_path / "r.npz")).stream()
    y_stream = np.array([stream.step(x) for x in X[1000:1100]])
    np.testing.assert_allclose(y_stream, y_numpy[:100], rtol=0, atol=1e-12)
    recurrent.save_state_dict(comp.weights, tmp_path / "w.pt")
    back = recurrent.load_state_dict(tmp_path / "w.pt")
    assert back.cell == comp.weights.cell and all(np.array_equal(a, comp.weights.arrays()[k]) for k, a in back.arrays().items())


@needs_torch
@pytest.mark.parametrize("cell", ["lstm", "gru3"])
def test_recurrent_run_in_chunks_is_one_call_bit_for_bit(monkeypatch, cell):
    """run() feeds torch chunks of RUN_CHUNK samples with the state carried (bounded workspace): the same
    bits as one call over the whole series, with and without memory, a chunk boundary mid-series."""
    import torch

    X, Y = _toy_series(700)
    comp = compensators.make(cell, hidden=16, steps=5, seq_len=50, streams=8).fit(X[:500], Y[:500])
    z = comp._z(X)
    monkeypatch.setattr(recurrent, "RUN_CHUNK", 64)  # 700 = 10 chunks of 64 and one of 60
    for memory in (True, False):
        x = torch.tensor(z[None] if memory else z[:, None], dtype=torch.float32)
        with torch.no_grad():
            whole, _ = recurrent._from_weights(torch, comp.weights)(x)
        whole = (whole[0] if memory else whole[:, 0]).double().numpy()
        assert np.array_equal(recurrent.run(comp.weights, z, memory=memory), whole)


def test_recurrent_without_torch_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch -> ImportError
    with pytest.raises(ImportError, match=r"sarins-fmu\[deep\]"):
        recurrent.require_torch()
    assert not recurrent.torch_available()


def test_training_device_names(monkeypatch):
    """cpu as given, auto by what torch sees, CUDA names checked against the devices torch sees; every other
    name refused; without torch auto is the CPU and a CUDA name asks for the extra."""
    assert recurrent.training_device() == "cpu" and recurrent.training_device(" CPU ") == "cpu"
    for bad in ("gpu", "tpu", "mps", "cuda:x", "cpu:0", "cuda:", ""):
        with pytest.raises(ValueError, match="unknown training device"):
            recurrent.training_device(bad)
    if recurrent.torch_available():
        import torch

        seen = torch.cuda.device_count() if torch.cuda.is_available() else 0
        assert recurrent.training_device("auto") == ("cuda" if seen else "cpu")
        with pytest.raises(ValueError, match=f"sees {seen} CUDA device"):
            recurrent.training_device(f"cuda:{seen}")
        monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
        monkeypatch.setattr(torch.cuda, "device_count", lambda: 2)
        assert recurrent.training_device("auto") == "cuda" and recurrent.training_device("cuda:1") == "cuda:1"
        with pytest.raises(ValueError, match="sees 2 CUDA device"):
            recurrent.training_device("cuda:2")
        monkeypatch.undo()
    monkeypatch.setitem(sys.modules, "torch", None)
    assert recurrent.training_device("auto") == "cpu"
    with pytest.raises(ImportError, match=r"sarins-fmu\[deep\]"):
        recurrent.training_device("cuda")


@needs_torch
def test_training_on_the_cpu_device_is_the_default():
    """device='cpu' (and 'auto' where torch sees no GPU) trains the very weights of the default."""
    import torch

    z, t = _toy_series(400)
    runs = [recurrent.train("gru", z, t[:, :6], hidden=8, steps=5, seq_len=50, streams=4, threads=1, **extra)
            for extra in ({}, {"device": "cpu"}) + (({"device": "auto"},) if not torch.cuda.is_available() else ())]
    for weights, losses in runs[1:]:
        assert np.array_equal(losses, runs[0][1])
        assert all(np.array_equal(a, runs[0][0].arrays()[k]) for k, a in weights.arrays().items())


@needs_torch
@pytest.mark.skipif(not recurrent.torch_available() or not __import__("torch").cuda.is_available(),
                    reason="no CUDA GPU that torch sees (a CPU build of torch, or no GPU)")
@pytest.mark.parametrize("cell", ["lstm", "gru"])
def test_training_on_a_gpu_learns_what_the_cpu_learns(cell):
    """On a GPU: the same initial weights (first loss equal to float32 rounding), the same fit of a tiny
    sequence that needs memory (both below 0.01, from above 0.2), and the same weights from run to run
    (cuDNN's deterministic kernels)."""
    rng = np.random.default_rng(1)
    z = rng.standard_normal((64, 7))
    t = np.column_stack([np.tanh(np.cumsum(z[:, :3], axis=0) / 4), z[:, 3:6] * 0.5])
    opts = dict(hidden=16, steps=150, seq_len=64, streams=1, lr=2e-2, seed=0, threads=1)
    cpu, cpu_losses = recurrent.train(cell, z, t, **opts)
    gpu, gpu_losses = recurrent.train(cell, z, t, device="cuda", **opts)
    again, _ = recurrent.train(cell, z, t, device="cuda", **opts)
    assert abs(gpu_losses[0] - cpu_losses[0]) <= 1e-5 * cpu_losses[0]
    assert gpu_losses[0] > 0.2 and gpu_losses[-1] < 0.01 and cpu_losses[-1] < 0.01
    assert all(np.array_equal(a, gpu.arrays()[k]) for k, a in again.arrays().items())


# --------------------------------------------------------------- co-simulation
@pytest.mark.integration
def test_cosimulated_recording_equals_in_process(fmu_dir, tmp_path):
    # a 50 ms step keeps the test short; the output dynamics' state still carries from step to step
    prof = mems_calibration.with_profile(QUICK, step=0.05, warmup=20.0,
                                         test=dict(ramp_c_per_min=30.0, hold_min=0.5, step_hold_min=0.2))
    overrides = mems_calibration.recording_overrides("heldout", 5, "hysteresis")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. no unconnected-input warning
        a = record_cosim("heldout", prof, fmu_dir, seed=5, csv=tmp_path / "dyn.csv", model_overrides=overrides)
    b = mems_calibration.record_in_process("heldout", prof, seed=5,
                                           model=mems_calibration.recording_model("heldout", 5, "hysteresis"))
    for key in ("dtheta", "dv", "temps", "angle", "rate"):
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-9 * np.abs(b[key]).max())
    assert (tmp_path / "dyn.csv").stat().st_size > 0


def _campaign(out: Path, *extra: str, timeout: int = 900) -> dict:
    cmd = [sys.executable, "-m", "sarins", "campaign", "mems-calibration", "--profile", "quick", "--out", str(out),
           "--workers", "2", "--no-progress", "--engine", "inprocess", *extra]  # 200 Hz: in process (same numbers)
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stderr[-3000:]
    assert "warning" not in done.stderr, done.stderr[-3000:]
    return json.loads((out / "summary.json").read_text())


# the default suite's subset: one model of each group (the cheapest recurrent one) and the memory control;
# the slow test runs every model and the ablation
QUICK_MODELS = "traditional,rbf,grnn,lstm,lstm-memoryless"


@pytest.fixture(scope="module")
def quick_campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("mems-quick")
    return out, _campaign(out, "--models", QUICK_MODELS if recurrent.torch_available() else "traditional,rbf,grnn")


def _assert_report_claims(summary: dict, one_layer) -> None:
    """What the quick profile shows (docs/mems-calibration.md, *Quick profile*): the
    one-layer recurrent networks ``one_layer`` beat both shallow models, their memoryless controls beat them."""
    from sarins.mems_calibration.report import MEMORY_EFFECT

    red, ins = summary["reductions"], summary["reductions_in_sample"]
    # every network beats the traditional model on every metric, the signed mean included
    for name in red:
        if name != "traditional":
            assert all(red[name][m] > red["traditional"][m] for m in red[name]), name
    # the one-layer recurrent networks beat both shallow models on the held-out run: std, mean |r| and the
    # systematic residual (not on the signed mean; the three-layer networks lose to RBFNN: not claimed)
    for cell in one_layer:
        for m in ("std", "mae", "sys"):
            assert red[cell][m] > max(red["rbf"][m], red["grnn"][m]), (cell, m)
    # memory is not what makes the recurrent models better: their memoryless controls score at least as
    # well (on the 200 Hz records of the datasheet-sized mems preset they score 3-4 points better)
    for cell in one_layer:
        assert red[f"{cell}-memoryless"]["sys"] > red[cell]["sys"] - MEMORY_EFFECT, cell
    assert red["lstm-memoryless"]["sys"] > max(red["rbf"]["sys"], red["grnn"]["sys"])
    # The old report's carry-over claim (RBFNN within CARRY_OVER of its in-sample score, GRNN not) was made
    # with the held-out run on the same power-up; the held-out run is now another power-up (its own turn-on
    # bias), and RBFNN loses 6.4 points there (seed 3), so the claim is not checked until the report is
    # regenerated on this protocol.
    assert ins["rbf"]["sys"] > red["rbf"]["sys"] and ins["grnn"]["sys"] > red["grnn"]["sys"]


@pytest.mark.slow  # 30 s: the quick campaign (kept out of the default run's 4 min budget)
@pytest.mark.integration
def test_quick_campaign_orders_models_as_the_report_claims(quick_campaign):
    """`sarins campaign mems-calibration --profile quick` (the default suite's model subset): the ordering
    and the reasons the report states, on the held-out programme."""
    out, summary = quick_campaign
    red = summary["reductions"]
    assert set(red) >= {"traditional", "rbf", "grnn"}
    if not recurrent.torch_available():
        pytest.skip("PyTorch is not installed: the recurrent half of the claims cannot be checked")
    _assert_report_claims(summary, ("lstm",))
    from sarins.mems_calibration.analysis import ordered_metrics

    assert set(ordered_metrics(summary["order"])) >= {"std", "mae", "sys"}  # with LSTM as the only recurrent
    assert summary["models"]["lstm"]["n_parameters"] == 16926
    for name in ("report.md", "fig_programmes.png", "fig4_gyro_x_residual.png", "fig5_accel_x_residual.png"):
        assert (out / name).stat().st_size > 0
    for name in summary["models"]:
        assert compensators.load(out / "models" / f"{name}.npz").kind == name.replace("-memoryless", "")
    assert summary["n_test"] > 0.5 * summary["n_train"] > 0
    held = next(line for line in (out / "report.md").read_text().splitlines() if "holds on:" in line)
    assert all(m in held.split("; not on")[0] for m in ("std", "mean |r|", "systematic"))
    text = (out / "report.md").read_text()
    assert "| claim | paper value | ours (median) | ours 5-95 % | paper's percentile in ours |" in text
    assert "| traditional: mean reduction (%), Table 3 | 9.2 |" in text
    assert "**The quick profile is too small to test:** traditional: mean reduction (%)" in text


def test_comparison_claims_pool_the_groups_models_and_power_ups():
    from sarins.mems_calibration.report import comparison_claims

    red = {"traditional": {"mean": 20.0, "std": 15.0}, "rbf": {"mean": 60.0, "std": 50.0},
           "grnn": {"mean": 70.0, "std": 55.0}, "lstm": {"mean": 80.0, "std": 60.0},
           "gru": {"mean": 82.0, "std": 61.0}, "lstm3": {"mean": 84.0, "std": 62.0},
           "lstm-memoryless": {"mean": 1.0, "std": 1.0}}
    rep = {k: {"mean": v["mean"] - 10.0, "std": v["std"] - 10.0} for k, v in red.items()}
    rows = {c.name: c for c in comparison_claims({"reductions": red, "reductions_repowered": rep})}
    assert sorted(rows["traditional: mean reduction (%), Table 3"].sample) == [10.0, 20.0]
    assert sorted(rows["shallow: std reduction (%), Table 3"].sample) == [40.0, 45.0, 50.0, 55.0]
    recurrent_mean = rows["recurrent: mean reduction (%), Table 3"]  # the memoryless control is not in a group
    assert sorted(recurrent_mean.sample) == [70.0, 72.0, 74.0, 80.0, 82.0, 84.0]
    assert recurrent_mean.cells()[4] == "0 %"  # the paper's 55 % is below all six
    assert not rows["shallow: mean reduction (%), Table 3"].tested


@pytest.mark.slow
@pytest.mark.integration
@pytest.mark.skipif(not recurrent.torch_available(), reason="PyTorch is not installed")
def test_quick_campaign_with_every_model_and_the_ablation(tmp_path):
    """Every model (both readings of the recurrent architecture) and the all-terms-off ablation: the
    same claims, and without the time-correlated terms the recurrent-shallow gap stays and memory still
    adds nothing."""
    from sarins.mems_calibration.report import MEMORY_EFFECT

    summary = _campaign(tmp_path / "c", "--ablation", "all")
    _assert_report_claims(summary, ("lstm", "gru"))
    red, off = summary["reductions"], summary["ablation"]["all"]["reductions"]
    gap = red["lstm"]["sys"] - max(red["rbf"]["sys"], red["grnn"]["sys"])  # 5.3 points (seed 3)
    assert off["lstm"]["sys"] - max(off["rbf"]["sys"], off["grnn"]["sys"]) > gap - MEMORY_EFFECT  # 16.6 points
    assert abs(off["lstm"]["sys"] - off["lstm-memoryless"]["sys"]) < MEMORY_EFFECT
    assert off["lstm"]["sys"] > red["lstm"]["sys"]  # the time-correlated terms cost the networks accuracy
    rms = np.asarray(summary["ablation"]["all"]["term_rms"])
    assert np.all(rms > 0)


@pytest.mark.integration
@pytest.mark.slow  # shares the quick campaign's fixture
def test_campaign_without_torch_says_how_to_install_and_runs_the_others(quick_campaign, tmp_path, monkeypatch,
                                                                        capsys):
    """The recordings of a finished campaign are reused (resume, in another folder); torch hidden."""
    import argparse

    from sarins.mems_calibration import campaign as mc_campaign

    shutil.copytree(quick_campaign[0] / "recordings", tmp_path / "recordings")
    monkeypatch.setitem(sys.modules, "torch", None)
    prof = dict(profile="quick", workers=1, scheduler=None, out=str(tmp_path), no_progress=True, seed=3,
                report_dir=None, models="traditional,grnn,gru", rnn_steps=None, grnn_patterns=300, rbf_samples=None,
                refit=False, ablation="none", ablation_models="rbf,grnn,lstm", engine="inprocess")
    assert mc_campaign.run(argparse.Namespace(**prof)) == 0
    err = capsys.readouterr().err
    assert "pip install 'sarins-fmu[deep]'" in err and "recomputing" not in err
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["models"]) == {"traditional", "grnn"} and summary["step_cost_ms"] == {}
    # GRNN from 300 patterns: mean 79.9 % against 3.6 %, std 14.9 against 15.4 (seed 3)
    assert summary["reductions"]["grnn"]["mean"] > summary["reductions"]["traditional"]["mean"] + 30.0
    assert summary["reused_models"] == []
    assert mc_campaign.run(argparse.Namespace(**prof)) == 0  # recordings and models reused
    again = json.loads((tmp_path / "summary.json").read_text())
    assert again["reused_models"] == ["grnn", "traditional"] and again["reductions"] == summary["reductions"]
    assert "reused" in (tmp_path / "report.md").read_text()
    with pytest.raises(ValueError, match="unknown model"):
        mc_campaign.run(argparse.Namespace(**{**prof, "models": "svm"}))


def test_systematic_residual_and_ordering_by_hand():
    """Systematic rms = sqrt(mean r^2 - floor^2): 0 for white noise at the floor, |c| for a constant c on
    top of it; the ordering reads every recurrent model against every shallow one."""
    from sarins.mems_calibration import analysis

    rng = np.random.default_rng(0)
    floor = np.array([1e-3] * 3 + [1e-2] * 3)
    noise = rng.standard_normal((400_000, 6)) * floor
    # the sample mean square of 4e5 samples scatters by sqrt(2 / 4e5) = 0.2 % of floor^2: sys <= ~0.05 floor
    assert np.all(analysis.residual_stats(noise, floor)["sys"] < 0.1 * floor)
    c = np.array([2e-3, -1e-3, 5e-4, 3e-2, 0.0, -1e-2])
    sys_c = analysis.residual_stats(noise + c, floor)["sys"]
    assert np.all(np.abs(sys_c - np.abs(c)) < 0.1 * floor)
    red = {"traditional": dict.fromkeys(analysis.METRICS, 10.0), "rbf": dict.fromkeys(analysis.METRICS, 40.0),
           "grnn": dict.fromkeys(analysis.METRICS, 30.0), "lstm": dict.fromkeys(analysis.METRICS, 50.0),
           "gru3": dict.fromkeys(analysis.METRICS, 45.0)}
    red["gru3"]["mean"] = 35.0  # below RBFNN on the mean only
    order = analysis.ordering(red)
    assert analysis.ordered_metrics(order) == ["std", "mae", "sys"]
    assert order["mean"]["worst_recurrent"] == ["gru3", 35.0] and order["mean"]["best_shallow"] == ["rbf", 40.0]
    assert analysis.ordering({"traditional": red["traditional"]})["std"]["recurrent_over_shallow"] is None


# ----------------------------------------------------------- compensator FMU
LINUX_ONLY = dict(win64=False, aarch64=False)  # the chain runs here; other platforms: tests/test_portable_fmus.py
@pytest.fixture(scope="module")
def chain_fmus(fmu_dir):
    return fmu_dir


SHORT = mems_calibration.with_profile(QUICK, step=0.1, warmup=20.0, train=dict(ramp_c_per_min=65.0, hold_min=0.5))


@pytest.fixture(scope="module")
def short_training():
    rec = mems_calibration.record_in_process("dynamic", SHORT, seed=2)
    return mems_calibration.dataset(rec, SHORT)


def _compensator_run(chain_fmus, fmu, stop=30.0, ins=True, scheme="gauss-seidel", record=None):
    from sarins.systems import compensated_chain
    from orchestration import simulate_system

    system = compensated_chain(
        chain_fmus, fmu, turntable=mems_calibration.turntable_parameters("dynamic", SHORT),
        imu=mems_calibration.imu_parameters(SHORT, seed=9), ins=dict(align_time=10.0, coarse_time=5.0,
                                                          lat0=mems_calibration.LAT_DEG * np.pi / 180), step=SHORT.step)
    record = record or ["imu.dtheta_?", "imu.dv_?", "imu.temp_*", "comp.dtheta_?", "comp.dv_?", "comp.model_kind",
                        "comp.temperature", "ins.lat"]
    return simulate_system(system, stop, SHORT.step, scheme=scheme, record=record, progress=False)


@pytest.mark.integration
def test_compensated_chain_gives_the_same_solution_under_both_schemes(chain_fmus, tmp_path):
    """IMUCompensator is time-tagged (raw_increment_end_time in, increment_end_time out): the chain's
    navigation solution is bit-identical under Gauss-Seidel and Jacobi at the same nav_time (Jacobi two
    steps later: one per link)."""
    from fmus.compensator_export import export_compensator

    X, Y = _toy_series(300)
    fmu = export_compensator(compensators.make("traditional").fit(X, Y).save(tmp_path / "t.json"), tmp_path / "out",
                             **LINUX_ONLY)
    names = ["ins.nav_time", "ins.lat", "ins.lon", "ins.yaw", "ins.v_e", "ins.v_n"]
    runs = [_compensator_run(chain_fmus, fmu, stop=20.0, scheme=s, record=names) for s in ("gauss-seidel", "jacobi")]
    rows = []
    for run in runs:
        nav = np.asarray(run["ins.nav_time"])
        keep = np.concatenate([[True], np.diff(nav) != 0])
        rows.append({t: tuple(run[n][i] for n in names[1:]) for i, t in enumerate(nav) if keep[i]})
    assert np.array_equal(runs[1]["ins.nav_time"][2:], runs[0]["ins.nav_time"][:-2])
    common = sorted(set(rows[0]) & set(rows[1]))
    assert len(common) > 0.9 * len(runs[0]["ins.nav_time"]) and common[-1] > 0  # it navigated
    assert all(rows[0][t] == rows[1][t] for t in common)


@pytest.mark.integration
@pytest.mark.filterwarnings("ignore:inputs left unconnected")  # the INS's axial-drift correction input
@pytest.mark.parametrize("kind", ["traditional", "grnn", "gru", "lstm3"])
def test_compensator_fmu_between_imu_and_ins(chain_fmus, short_training, tmp_path, kind):
    """Exported model as an FMU in Turntable -> IMUThermal -> IMUCompensator -> StrapdownINS:
    fmpy validate is clean and its increments are the library's compensation, bit for bit."""
    from fmpy.validation import validate_fmu

    from fmus.compensator_export import export_compensator

    if kind in ("gru", "lstm3") and not recurrent.torch_available():
        pytest.skip("PyTorch is not installed: recurrent models cannot be trained (pip install 'sarins-fmu[deep]')")
    train = short_training
    rnn = dict(hidden=8, steps=5, seq_len=20, streams=4)
    opts = {"grnn": dict(max_patterns=300), "gru": rnn, "lstm3": rnn}.get(kind, {})
    model = compensators.make(kind, **opts).fit(train.X, train.Y)
    fmu = export_compensator(model.save(tmp_path / "model.json"), tmp_path / "out", **LINUX_ONLY)
    assert validate_fmu(str(fmu)) == []
    res = _compensator_run(chain_fmus, fmu)
    h = SHORT.step
    raw = np.column_stack([res[f"imu.{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"])[1:] / h
    temp = res["comp.temperature"][1:]  # the mean of the six temperatures, as the FMU summed them
    temps = np.column_stack([res[f"imu.temp_{s}"] for s in
                             ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")])[1:]
    np.testing.assert_allclose(temp, temps.mean(axis=1), rtol=4 * np.finfo(float).eps)  # 6 additions
    comp = np.column_stack([res[f"comp.{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"])[1:]
    # the FMU and the library run the same C function over the same binary model: bit for bit
    np.testing.assert_array_equal(comp, model.predict(np.column_stack([raw, temp])) * h)
    assert res["comp.model_kind"][-1] == compensators.KINDS.index(kind)
    assert np.all(np.isfinite(res["ins.lat"]))


@pytest.mark.integration
def test_compensator_fmu_with_a_bad_model_file_reports_an_error(chain_fmus, tmp_path):
    from fmu_driver import Slave

    from fmus.compensator_export import export_compensator

    X, Y = _toy_series(200)
    fmu = export_compensator(compensators.make("traditional").fit(X, Y).save(tmp_path / "t.json"), tmp_path,
                             **LINUX_ONLY)
    bad = tmp_path / "broken.npz"
    bad.write_bytes(b"not a model")
    log = []
    slave = Slave(fmu, "comp", log)
    try:
        slave.set(model_file=str(bad))
        slave.fmu.enterInitializationMode()
        from fmpy.fmi1 import FMICallException

        with pytest.raises(FMICallException, match="status 3"):  # reported at the end of initialisation
            slave.fmu.exitInitializationMode()
        assert any("broken.npz" in text.decode() if isinstance(text, bytes) else "broken.npz" in text
                   for _, _, text in log)
    finally:
        slave.free()
    with pytest.raises(ModelFileError):
        export_compensator(bad, tmp_path / "never")


@pytest.mark.integration
@needs_torch
def test_recurrent_compensator_fmu_reset_and_two_instances(short_training, tmp_path):
    """The recurrent state lives in the instance: reset restarts it, a second instance does not share it."""
    from fmu_driver import Slave

    from fmus.compensator_export import export_compensator

    train = short_training
    model = compensators.make("lstm", hidden=8, steps=5, seq_len=20, streams=4).fit(train.X, train.Y)
    fmu = export_compensator(model.save(tmp_path / "lstm.npz"), tmp_path, **LINUX_ONLY)
    h = SHORT.step
    x = train.X[:15]

    def step(slave, k, row):
        slave.set(**{f"raw_dtheta_{a}": row[i] * h for i, a in enumerate("xyz")},
                  **{f"raw_dv_{a}": row[3 + i] * h for i, a in enumerate("xyz")},
                  **{f"temp_{s}": row[6] for s in ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")})
        slave.fmu.doStep(k * h, h)
        return np.array(slave.get(*[f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"])) / h

    a, b = Slave(fmu, "a"), Slave(fmu, "b")
    try:
        for s in (a, b):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        first = []
        for k, (row, other) in enumerate(zip(x, x[::-1])):  # interleaved: b's state must not leak into a
            first.append(step(a, k, row))
            step(b, k, other)
        first = np.array(first)
        stream = model.stream()
        np.testing.assert_array_equal(first * h, np.array([stream.step(r) for r in x]) * h)
        a.fmu.reset()
        a.fmu.enterInitializationMode()
        a.fmu.exitInitializationMode()
        np.testing.assert_array_equal(np.array([step(a, k, row) for k, row in enumerate(x)]), first)
    finally:
        a.free()
        b.free()


def _build_compensator_cli(tmp_path, model, out):
    env = {**__import__("os").environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "sarins", "build-fmus", "--only", "IMUCompensator", "--out", str(out),
           "--compensator", str(model)]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300, env=env)


@pytest.mark.slow  # builds every platform's binary (the library path is in the default run: export_compensator)
@pytest.mark.integration
def test_build_fmus_cli_ships_a_compensator(tmp_path):
    import zipfile

    X, Y = _toy_series(300)
    model = compensators.make("grnn", max_patterns=50).fit(X, Y).save(tmp_path / "g.json")
    done = _build_compensator_cli(tmp_path, model, tmp_path / "out")
    assert done.returncode == 0, done.stderr
    with zipfile.ZipFile(tmp_path / "out" / "IMUCompensator.fmu") as z:  # the binary model the C model reads
        assert z.read("resources/compensator.bin") == compensators.load(model).binary()


def test_build_fmus_cli_refuses_a_missing_compensator_before_building(tmp_path):
    bad = _build_compensator_cli(tmp_path, tmp_path / "missing.json", tmp_path / "out_bad")
    assert bad.returncode == 2 and "missing.json" in bad.stderr
    assert not (tmp_path / "out_bad").exists()  # nothing built


def test_recording_records_name_the_ablation_and_the_run():
    """A stored recording is reused only for the same run, seed and switched-off term (canonical record)."""
    from sarins.campaign import Task
    from sarins.mems_calibration.recording import record_task
    from sarins.results import task_record

    def record(**kwargs):
        args = dict(kind="heldout", profile_name="quick", fmu_dir="f", seed=3) | kwargs
        return task_record(Task("r", record_task, args, volatile=("fmu_dir",)))

    base = record()
    assert base == record(fmu_dir="elsewhere")
    assert len({str(r) for r in (base, record(ablation="flicker"), record(ablation="all"), record(kind="repowered"),
                                 record(seed=4), record(profile_name="paper"))}) == 6


def test_record_task_refuses_an_unknown_engine():
    from sarins.mems_calibration.recording import record_task

    with pytest.raises(ValueError, match="engine"):
        record_task("tumble", "quick", "unused", engine="warp")


def test_progress_names_the_phase_and_scales_its_estimate():
    """One line per event naming the phase; what is left is rescaled by the finished phases' measured time."""
    import io
    import time as _time

    from sarins.mems_calibration.progress import Progress

    out = io.StringIO()
    p = Progress({"recording": 0.05, "fitting": 100.0, "done": 0.0}, stream=out)
    p.start("recording", "5 recordings")
    _time.sleep(1.2)  # 60 times the estimate: the machine is slow
    p.start("fitting", "9 models")
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("mems-calibration [recording 1/3] 5 recordings | elapsed 0:00, about 1:40 left")
    assert lines[1].startswith("mems-calibration [fitting 2/3] 9 models | elapsed 0:01")
    assert p.remaining() > 1000.0  # 100 s estimated, scaled by the measured ratio (at most 20)
    assert set(p.measured) == {"recording"} and p.measured["recording"]["wall_s"] >= 1.2
    silent = Progress({"a": 1.0}, enabled=False, stream=out)
    silent.start("a", "x")
    assert out.getvalue().count("\n") == 2


def test_campaign_estimates_cover_every_phase():
    from sarins.mems_calibration.campaign import estimates

    est = estimates(QUICK, ["traditional", "rbf", "grnn", "lstm", "gru3"], "inprocess", None, 288_000, ["all"],
                    ["rbf"], rnn_steps=400, grnn_patterns=5000, rbf_samples=10000)
    assert list(est) == ["recording", "datasets", "fitting", "evaluation", "ablation", "report", "done"]
    assert all(v > 0 for k, v in est.items() if k != "done")
    from sarins.mems_calibration.fitting import STEP_MS

    assert est["fitting"] >= 400 * STEP_MS["gru3"] / 1e3  # the GRU-3's steps at least (one process each)


def test_parallel_fits_and_evaluations_give_the_sequential_numbers():
    """Recurrent fits in forked processes and evaluations on threads: the same weights and statistics as
    one at a time (each fit seeded; each evaluation independent)."""
    from sarins.mems_calibration import analysis, campaign, fitting

    X, Y = _toy_series(3000)
    train = mems_calibration.Dataset(X, Y, np.arange(len(X)) * 0.1)
    kinds = ["grnn", "lstm", "gru-memoryless"] if recurrent.torch_available() else ["grnn", "rbf"]
    opts = dict(rnn_steps=3, grnn_patterns=300, rbf_samples=500)
    two = fitting.fit_models(kinds, train, None, workers=2, **opts)
    one = fitting.fit_models(kinds, train, None, workers=1, **opts)
    for k in kinds:
        np.testing.assert_array_equal(two[k].predict(X[:50]), one[k].predict(X[:50]))
    floor = analysis.noise_floor(imu.preset("mems"), 0.1)
    sets = {"a": train, "b": train.tail(700)}
    par = campaign.evaluate_sets(two, sets, floor, threads=2, stream_samples={"a": 5})
    seq = campaign.evaluate_sets(two, sets, floor, threads=1)
    for key in sets:
        for name in par[key][1]:
            for metric, value in par[key][1][name].items():
                np.testing.assert_array_equal(value, seq[key][1][name][metric])
    assert par["a"][2]["grnn"]["stream_us"] > 0 and seq["a"][2]["grnn"]["stream_us"] is None
    # the costs benchmarks/bench_mems_phases.py reports: each fit's and each (model, set) evaluation's CPU seconds
    for k in kinds:
        assert two[k].fit_cpu_seconds > 0 and one[k].fit_cpu_seconds > 0
        for key in sets:
            info = par[key][2][k]
            assert 0 < info["predict_cpu_s"] and info["fit_cpu_s"] == two[k].fit_cpu_seconds


# ------------------------------------------------------------- memory: chunks
@pytest.mark.parametrize("spool", [None, 0, 1000])
@pytest.mark.parametrize("rows", [1, 7, 1000, 1 << 16])
def test_residual_sums_in_chunks_are_the_whole_arrays_statistics_bit_for_bit(rows, spool, tmp_path, monkeypatch):
    """Rows kept in memory, all in the temporary file (spool 0) or the first 1000 in memory and the rest in the
    file: the whole array's statistics bit for bit; the file is in the temporary folder and goes with the
    object."""
    import gc
    import tempfile

    from sarins.mems_calibration import analysis

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    rng = np.random.default_rng(4)
    r = rng.standard_normal((3001, 6)) * [1e-3, 1.0, 1e3, 1e-6, 5.0, 7.0] + [1.0, 0.0, -3.0, 1e-3, 0.0, 0.0]
    floor = np.array([0.3, 0.0, 10.0, 1e-7, 1.0, 0.1])
    sums = analysis.ResidualSums(spool)
    for a in range(0, len(r), rows):
        sums.add(r[a:a + rows])
    sums.add(r[:0])  # an empty chunk adds nothing
    assert (sums._spool is not None) == (spool is not None and len(r) > spool)
    got, whole = sums.stats(floor), analysis.residual_stats(r, floor)
    for key in whole:
        np.testing.assert_array_equal(got[key], whole[key], err_msg=key)
    again = sums.stats(floor)  # the file is read again from its start
    assert all(np.array_equal(again[key], got[key]) for key in got)
    with pytest.raises(ValueError, match="residual rows"):
        sums.add(r[:3, :4])
    with pytest.raises(ValueError, match="no residual rows"):
        analysis.ResidualSums().stats(floor)
    del sums
    gc.collect()
    assert not list(tmp_path.iterdir())  # an unnamed file: nothing left behind


def test_dataset_in_chunks_is_the_whole_recordings_bit_for_bit():
    """The data set built a chunk at a time: the truth and inputs of the whole recording, row for row."""
    rec = mems_calibration.record_in_process("dynamic", SHORT, seed=2)
    X = mems_calibration.measured_of(rec)
    Y = np.column_stack(mems_calibration.truth_of(rec, SHORT.internal_rate))
    keep = rec["time"][1:] > SHORT.warmup + 1e-9
    assert 0 < keep.sum() < len(keep)
    for rows in (7, 1000, len(keep) + 5):
        data = mems_calibration.dataset(rec, SHORT, rows=rows)
        np.testing.assert_array_equal(data.X, X[keep])
        np.testing.assert_array_equal(data.Y, Y[keep])
        np.testing.assert_array_equal(data.time, rec["time"][1:][keep])
    with pytest.raises(ValueError, match="rows"):
        mems_calibration.dataset(rec, SHORT, rows=0)


def test_recordings_spooled_by_worker_processes_are_the_same_bits(tmp_path):
    """The campaign records in process on every core: each worker spools its recording and sends back the
    spool files, which the campaign streams into the result files -- the arrays of one process's recordings."""
    from sarins.campaign import Task, run_campaign
    from sarins.mems_calibration.recording import record_task
    from sarins.results import load_result

    changes = dict(step=0.1, warmup=20.0, train=dict(ramp_c_per_min=65.0, hold_min=0.5))
    stored = {}
    for workers in (1, 2):
        folder = tmp_path / f"workers{workers}"
        tasks = [Task(kind, record_task, dict(kind=kind, profile_name="quick", fmu_dir="", profile_changes=changes,
                                              engine="inprocess", spool=str(folder)), volatile=("fmu_dir", "spool"))
                 for kind in ("dynamic", "heldout")]
        stored[workers] = run_campaign(tasks, folder, workers=workers, progress=False, keep=False)
    for kind in ("dynamic", "heldout"):
        one, two = load_result(stored[1][kind]), load_result(stored[2][kind])
        assert set(one) == set(two) and len(one["time"]) > 1000
        for key in set(one) - {"wall_s"}:
            np.testing.assert_array_equal(two[key], one[key], err_msg=f"{kind}.{key}")
    assert not list(tmp_path.rglob(".spool-*"))


def test_streamed_recording_and_chunked_sets_are_the_whole_arrays_bit_for_bit(tmp_path, monkeypatch):
    """The campaign's low-memory path: the recording spooled chunk by chunk and streamed into its result file,
    read back a slice at a time, its data sets written a part at a time -- the same arrays, bit for bit, as the
    whole-array path (one chunk, np.savez-style file, load_result, dataset)."""
    import hashlib

    from sarins.mems_calibration import fitting, storage
    from sarins.results import StoredResultError, load_result, save_result

    whole = mems_calibration.record_in_process("heldout", SHORT, seed=4, chunk=10**9)
    spooled = mems_calibration.record_in_process("heldout", SHORT, seed=4, chunk=333, spool=tmp_path)
    assert len(whole["time"]) > 3 * 333
    assert {type(v) for v in spooled.values()} == {mems_calibration.SpooledArray}
    for key in whole:
        np.testing.assert_array_equal(np.asarray(spooled[key]), whole[key], err_msg=key)
    save_result(tmp_path / "whole.npz", dict(whole, wall_s=1.5), {"id": 1})
    save_result(tmp_path / "streamed.npz", dict(spooled, wall_s=1.5), {"id": 1})
    assert not list(tmp_path.glob(".spool-*"))  # each spool file removed once streamed
    a, b = load_result(tmp_path / "whole.npz"), load_result(tmp_path / "streamed.npz")
    assert set(a) == set(b) == set(whole) | {"wall_s"}
    for key in whole:
        assert a[key].dtype == b[key].dtype == whole[key].dtype
        np.testing.assert_array_equal(b[key], whole[key], err_msg=key)
        np.testing.assert_array_equal(a[key], whole[key], err_msg=key)

    monkeypatch.setattr(storage, "LAZY_BYTES", 0)  # every 2-D array read from the file a slice at a time
    lazy = storage.open_recording(tmp_path / "streamed.npz")
    assert isinstance(lazy["temps"], storage.StoredArray) and isinstance(lazy["time"], np.ndarray)
    assert lazy["wall_s"] == 1.5
    temps = whole["temps"]
    for key in (slice(None), slice(5, 700), slice(None, None, 7), slice(3, -2, 1000), slice(10, 5)):
        np.testing.assert_array_equal(lazy["temps"][key], temps[key])
    np.testing.assert_array_equal(lazy["rate"][-1], whole["rate"][-1])
    digests = [fitting.models_digest({}) for _ in range(2)]
    fitting.digest_recording(digests[0], a)
    fitting.digest_recording(digests[1], lazy)
    assert digests[0].hexdigest() == digests[1].hexdigest()

    data = mems_calibration.dataset(whole, SHORT)
    for rows, limit in ((50, None), (1 << 16, None), (333, 1001), (7, 10**9)):
        n, parts = mems_calibration.dataset_chunks(lazy, SHORT, rows=rows)
        stored = storage.save_chunks(tmp_path, f"set{rows}", n, parts, limit=limit).load()
        ref = data.head(len(data) if limit is None else limit)
        for column in ("X", "Y", "time"):
            np.testing.assert_array_equal(getattr(stored, column), getattr(ref, column), err_msg=column)
            assert getattr(stored, column).dtype == np.float64
    np.testing.assert_array_equal(mems_calibration.dataset(lazy, SHORT, rows=99).X, data.X)

    member = lazy["temps"]
    raw = bytearray((tmp_path / "streamed.npz").read_bytes())
    raw[member.offset + 100] ^= 1  # a byte of temps flipped on disk
    (tmp_path / "bad.npz").write_bytes(bytes(raw))
    with pytest.raises(StoredResultError, match="temps"):
        storage.open_recording(tmp_path / "bad.npz")
    assert hashlib.sha256(bytes(raw)).hexdigest() != hashlib.sha256((tmp_path / "streamed.npz").read_bytes()).hexdigest()


def test_in_process_recording_does_not_depend_on_its_chunk():
    a = mems_calibration.record_in_process("heldout", SHORT, seed=4)
    b = mems_calibration.record_in_process("heldout", SHORT, seed=4, chunk=333)
    assert set(a) == set(b) and len(a["time"]) > 3 * 333
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_fits_on_a_stored_set_equal_the_fits_on_the_arrays(tmp_path, monkeypatch):
    """The fits' statistics summed a block at a time are numpy's on the whole arrays, bit for bit, and the
    recurrent fits' processes reading the training set from disk give the models fitted on it in memory."""
    from sarins.mems_calibration import fitting
    from sarins.mems_calibration.storage import save_set
    from sarins_fmu.identify import compensators

    X, Y = _toy_series(3000)
    X, Y = X * [1e-3, 2.0, 5e2, 1.0, 3.0, 7.0, 40.0] + 11.0, Y * 3.0 - 2.0  # means far from zero
    train = mems_calibration.Dataset(X, Y, np.arange(len(X)) * 0.1)
    monkeypatch.setattr(compensators, "STATS_ROWS", 333)  # 3000 rows: nine blocks and a short one
    for rows in (X, Y - X[:, :6]):
        mean, std = compensators.column_stats(lambda a, b, rows=rows: rows[a:b], len(rows))
        np.testing.assert_array_equal(mean, rows.mean(axis=0))
        np.testing.assert_array_equal(std, rows.std(axis=0))
    stored = save_set(tmp_path, "training", train)
    kinds = ["rbf", "grnn"] + (["lstm", "gru-memoryless"] if recurrent.torch_available() else [])
    opts = dict(rnn_steps=3, grnn_patterns=300, rbf_samples=500)
    disk = fitting.fit_models(kinds, stored, None, workers=2, **opts)
    memory = fitting.fit_models(kinds, train, None, workers=1, **opts)
    d = Y - X[:, :6]
    for k in kinds:
        np.testing.assert_array_equal(disk[k].target_mean, d.mean(axis=0))
        np.testing.assert_array_equal(disk[k].target_scale, d.std(axis=0))
        np.testing.assert_array_equal(disk[k].predict(X[:200]), memory[k].predict(X[:200]), err_msg=k)
        if k in fitting.RECURRENT:
            np.testing.assert_array_equal(disk[k].input_mean, X.mean(axis=0))
            np.testing.assert_array_equal(disk[k].input_scale, X.std(axis=0))
            np.testing.assert_array_equal(disk[k].losses, memory[k].losses)
    column = stored.column("X")
    np.testing.assert_array_equal(column[[0, 5, 2999]], X[[0, 5, 2999]])
    np.testing.assert_array_equal(stored.tail(100).column("Y")[10:20], Y[-90:-80])
    bad = Y.copy()
    bad[1234, 2] = np.nan
    with pytest.raises(ValueError):
        compensators.make("rbf", max_samples=100).fit(column, save_set(tmp_path, "bad", train.__class__(
            X, bad, train.time)).column("Y"))


def test_evaluation_in_chunks_from_disk_equals_the_whole_sets(tmp_path, monkeypatch):
    """evaluate_sets a chunk at a time, on sets in memory and read back from disk: the statistics and the
    figure rows of the whole arrays in one piece, bit for bit (the recurrent state carried over chunks)."""
    from sarins.mems_calibration import analysis, campaign, fitting
    from sarins.mems_calibration.storage import save_set

    X, Y = _toy_series(3000)
    train = mems_calibration.Dataset(X, Y, np.arange(len(X)) * 0.1)
    kinds = ["rbf", "lstm", "gru-memoryless"] if recurrent.torch_available() else ["rbf"]
    models = fitting.fit_models(kinds, train, None, workers=1, rnn_steps=3, grnn_patterns=300, rbf_samples=500)
    floor = analysis.noise_floor(imu.preset("mems"), 0.1)
    monkeypatch.setattr(campaign, "EVAL_ROWS", 700)  # 3000 rows: four full chunks and a short one
    monkeypatch.setattr(campaign, "FIGURE_POINTS", 7)  # every 428th row, across the chunk ends
    stored = save_set(tmp_path, "a", train)
    sets = {"memory": train, "disk": stored, "tail": stored.tail(1100)}
    got = campaign.evaluate_sets(models, sets, floor, threads=2, stream_samples={"disk": 5})
    for key, data in (("memory", train), ("disk", train), ("tail", train.tail(1100))):
        residuals, stats, info = got[key]
        step = campaign.thinning(len(data))
        assert step > 1
        whole = {"raw": data.X[:, :6] - data.Y} | {k: m.predict_batch(data.X) - data.Y for k, m in models.items()}
        for name, r in whole.items():
            np.testing.assert_array_equal(residuals[name], r[::step], err_msg=f"{key} {name}")
            for metric, value in analysis.residual_stats(r, floor).items():
                np.testing.assert_array_equal(stats[name][metric], value, err_msg=f"{key} {name} {metric}")
        assert all((i["stream_us"] is not None) == (key == "disk") for i in info.values())
    np.testing.assert_array_equal(stored.tail(1100).time, train.time[-1100:])


def test_grnn_in_chunks_of_its_truncation_equals_one_call():
    from sarins_fmu.identify.grnn import CHUNK_ROWS

    X, Y = _toy_series(4000)
    model = compensators.make("grnn", max_patterns=200).fit(X, Y)
    n = 2 * CHUNK_ROWS + 1234
    Xq = X[np.arange(n) % len(X)] + 1e-4 * np.sin(np.arange(n))[:, None]
    parts = list(model.predict_batch_chunks(Xq[a:a + CHUNK_ROWS] for a in range(0, n, CHUNK_ROWS)))
    np.testing.assert_array_equal(np.concatenate(parts), model.predict_batch(Xq))
    with pytest.raises(ValueError, match="multiples"):
        list(model.predict_batch_chunks([Xq[:100], Xq[100:200]]))


def test_stored_recordings_load_one_at_a_time(tmp_path):
    from sarins.campaign import Task, run_campaign
    from campaign_tasks import square
    from sarins.mems_calibration.storage import StoredRecordings

    tasks = [Task(f"t{k}", square, dict(x=k)) for k in range(3)]
    kept = run_campaign(tasks, tmp_path, workers=1, progress=False)
    for _ in range(2):  # computed, then resumed
        paths = run_campaign(tasks, tmp_path / "lazy", workers=1, progress=False, keep=False)
        assert all(isinstance(p, Path) and p.is_file() for p in paths.values())
        recs = StoredRecordings(paths)
        assert list(recs) == ["t0", "t1", "t2"] and len(recs) == 3
        for key in kept:
            assert recs[key] is not recs[key]  # loaded on each access, nothing cached
            assert set(recs[key]) == set(kept[key])
            for field, value in kept[key].items():
                np.testing.assert_array_equal(recs[key][field], value)
