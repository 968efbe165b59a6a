"""Seed 003: recordings, traditional calibration, compensators, the quick campaign."""

import json
import subprocess
import sys
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


@pytest.mark.parametrize("changes", [dict(step=0.0), dict(step=0.3), dict(cal_step=1.0), dict(cycles=1),
                                     dict(warmup=-1.0), dict(ramp_c_per_min=float("nan"))])
def test_bad_profiles_rejected(changes):
    with pytest.raises(ValueError):
        mems_calibration.with_profile(QUICK, **changes)


def test_unknown_profile_and_recording_rejected():
    with pytest.raises(ValueError, match="profile"):
        mems_calibration.profile("huge")
    with pytest.raises(ValueError, match="recording"):
        mems_calibration.turntable_parameters("spin", QUICK)


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
    """PyTorch's counts (two bias vectors per gate): GRU about 24 % fewer than LSTM (seed 003)."""
    lstm, gru = recurrent.n_parameters("lstm", 7, 60, 6), recurrent.n_parameters("gru", 7, 60, 6)
    assert (lstm, gru) == (16926, 12786)
    assert 0.23 < 1 - gru / lstm < 0.25


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
@pytest.mark.parametrize("cell", ["lstm", "gru"])
def test_recurrent_numpy_cells_equal_torch(tmp_path, cell):
    X, Y = _toy_series(1200)
    comp = compensators.make(cell, hidden=16, steps=20, seq_len=50, streams=8).fit(X[:1000], Y[:1000])
    y_torch = comp.predict(X[1000:])
    y_numpy = comp._output(X[1000:], comp.weights.run(comp._z(X[1000:])))
    np.testing.assert_allclose(y_numpy, y_torch, rtol=0, atol=1e-6 * np.abs(Y).max())
    stream = compensators.load(comp.save(tmp_path / "r.npz")).stream()
    y_stream = np.array([stream.step(x) for x in X[1000:1100]])
    np.testing.assert_allclose(y_stream, y_numpy[:100], rtol=0, atol=1e-12)
    recurrent.save_state_dict(comp.weights, tmp_path / "w.pt")
    back = recurrent.load_state_dict(tmp_path / "w.pt")
    assert back.cell == cell and np.array_equal(back.w_hh, comp.weights.w_hh)


def test_recurrent_without_torch_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "torch", None)  # import torch -> ImportError
    with pytest.raises(ImportError, match=r"sarins-fmu\[deep\]"):
        recurrent.require_torch()
    assert not recurrent.torch_available()


# --------------------------------------------------------------- co-simulation
@pytest.mark.integration
def test_cosimulated_recording_equals_in_process(fmu_dir, tmp_path):
    prof = mems_calibration.with_profile(QUICK, warmup=20.0, ramp_c_per_min=65.0, hold_min=0.5)
    a = record_cosim("dynamic", prof, fmu_dir, seed=5, csv=tmp_path / "dyn.csv")
    b = mems_calibration.record_in_process("dynamic", prof, seed=5)
    for key in ("dtheta", "dv", "temps", "angle", "rate"):
        np.testing.assert_allclose(a[key], b[key], rtol=0, atol=1e-9 * np.abs(b[key]).max())
    assert (tmp_path / "dyn.csv").stat().st_size > 0


@pytest.mark.integration
def test_quick_campaign_orders_models_as_the_paper(tmp_path):
    """`sarins campaign mems-calibration --profile quick`: every network beats the raw output and GRNN and
    RBFNN beat the traditional model on the dynamic test set (std and mean |residual|)."""
    out = tmp_path / "mems-calibration"
    cmd = [sys.executable, "-m", "sarins", "campaign", "mems-calibration", "--profile", "quick", "--out", str(out),
           "--workers", "1", "--no-progress"]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600,
                          env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 0, done.stderr[-3000:]
    summary = json.loads((out / "summary.json").read_text())
    red = summary["reductions"]
    networks = [k for k in ("rbf", "grnn", "lstm", "gru") if k in red]
    assert set(networks) >= {"rbf", "grnn"}
    for name in networks:
        assert red[name]["std"] > 0 and red[name]["mae"] > 0 and red[name]["mean"] > 0, name
    for name in ("rbf", "grnn"):
        assert red[name]["std"] > red["traditional"]["std"] and red[name]["mae"] > red["traditional"]["mae"]
    if recurrent.torch_available():
        assert summary["models"]["lstm"]["n_parameters"] == 16926
        assert summary["models"]["gru"]["n_parameters"] == 12786
    for name in ("report.md", "fig4_gyro_x_residual.png", "fig5_accel_x_residual.png"):
        assert (out / name).stat().st_size > 0
    for name in summary["models"]:
        assert compensators.load(out / "models" / f"{name}.npz").kind == name


@pytest.mark.integration
def test_campaign_without_torch_says_how_to_install_and_runs_the_others(tmp_path, monkeypatch, capsys):
    """The recordings of a finished campaign are reused (resume); torch hidden."""
    import argparse

    from sarins.mems_calibration import campaign as mc_campaign

    monkeypatch.setitem(sys.modules, "torch", None)
    prof = dict(profile="quick", workers=1, scheduler=None, out=str(tmp_path), no_progress=True, seed=3,
                report_dir=None, models="traditional,grnn,gru", rnn_steps=None, grnn_patterns=300, rbf_samples=None,
                refit=False)
    assert mc_campaign.run(argparse.Namespace(**prof)) == 0
    assert "pip install 'sarins-fmu[deep]'" in capsys.readouterr().err
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["models"]) == {"traditional", "grnn"}
    assert summary["reductions"]["grnn"]["std"] > summary["reductions"]["traditional"]["std"]
    assert summary["reused_models"] == []
    assert mc_campaign.run(argparse.Namespace(**prof)) == 0  # recordings and models reused
    again = json.loads((tmp_path / "summary.json").read_text())
    assert again["reused_models"] == ["grnn", "traditional"] and again["reductions"] == summary["reductions"]
    assert "reused" in (tmp_path / "report.md").read_text()
    with pytest.raises(ValueError, match="unknown model"):
        mc_campaign.run(argparse.Namespace(**{**prof, "models": "svm"}))


# ----------------------------------------------------------- compensator FMU
@pytest.fixture(scope="module")
def chain_fmus(fmu_dir):
    return fmu_dir


SHORT = mems_calibration.with_profile(QUICK, warmup=20.0, ramp_c_per_min=65.0, hold_min=0.5)


@pytest.fixture(scope="module")
def short_training():
    rec = mems_calibration.record_in_process("dynamic", SHORT, seed=2)
    return mems_calibration.dynamic_dataset(rec, SHORT)


def _compensator_run(chain_fmus, fmu, stop=30.0, ins=True, scheme="gauss-seidel", record=None):
    from sarins.systems import compensated_chain
    from orchestration import simulate_system

    system = compensated_chain(
        chain_fmus, fmu, turntable=mems_calibration.turntable_parameters("dynamic", SHORT),
        imu=mems_calibration.imu_parameters(SHORT, seed=9), ins=dict(align_time=10.0, coarse_time=5.0,
                                                          lat0=mems_calibration.LAT_DEG * np.pi / 180), step=SHORT.step)
    record = record or ["imu.dtheta_?", "imu.dv_?", "imu.temp_*", "comp.dtheta_?", "comp.dv_?", "comp.model_kind",
                        "ins.lat"]
    return simulate_system(system, stop, SHORT.step, scheme=scheme, record=record, progress=False)


@pytest.mark.integration
def test_compensated_chain_gives_the_same_solution_under_both_schemes(chain_fmus, tmp_path):
    """IMUCompensator is time-tagged (raw_increment_end_time in, increment_end_time out): the chain's
    navigation solution is bit-identical under Gauss-Seidel and Jacobi at the same nav_time (Jacobi two
    steps later: one per link)."""
    from fmus.compensator_export import export_compensator

    X, Y = _toy_series(300)
    fmu = export_compensator(compensators.make("traditional").fit(X, Y).save(tmp_path / "t.json"), tmp_path / "out")
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
@pytest.mark.parametrize("kind", ["traditional", "grnn", "gru"])
def test_compensator_fmu_between_imu_and_ins(chain_fmus, short_training, tmp_path, kind):
    """Exported model as an FMU in Turntable -> IMUThermal -> IMUCompensator -> StrapdownINS:
    fmpy validate is clean and its increments are the library's compensation (1e-12)."""
    from fmpy.validation import validate_fmu

    from fmus.compensator_export import export_compensator

    if kind == "gru" and not recurrent.torch_available():
        pytest.skip("PyTorch is not installed: recurrent models cannot be trained (pip install 'sarins-fmu[deep]')")
    train, _ = short_training
    opts = {"grnn": dict(max_patterns=300), "gru": dict(hidden=8, steps=5, seq_len=20, streams=4)}.get(kind, {})
    model = compensators.make(kind, **opts).fit(train.X, train.Y)
    fmu = export_compensator(model.save(tmp_path / "model.json"), tmp_path / "out")
    assert validate_fmu(str(fmu)) == []
    res = _compensator_run(chain_fmus, fmu)
    h = SHORT.step
    raw = np.column_stack([res[f"imu.{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"])[1:] / h
    temp = np.column_stack([res[f"imu.temp_{s}"] for s in
                            ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")]).mean(axis=1)[1:]
    comp = np.column_stack([res[f"comp.{q}_{a}"] for q in ("dtheta", "dv") for a in "xyz"])[1:] / h
    expected = model.predict(np.column_stack([raw, temp]))
    tol = 1e-6 if kind == "gru" else 1e-12  # the FMU runs the recurrent cells in float64, torch in float32
    np.testing.assert_allclose(comp, expected, rtol=0, atol=tol * np.abs(expected).max())
    assert res["comp.model_kind"][-1] == compensators.KINDS.index(kind)
    assert np.all(np.isfinite(res["ins.lat"]))


@pytest.mark.integration
def test_compensator_fmu_with_a_bad_model_file_reports_an_error(chain_fmus, tmp_path):
    from fmu_driver import Slave

    from fmus.compensator_export import export_compensator

    X, Y = _toy_series(200)
    fmu = export_compensator(compensators.make("traditional").fit(X, Y).save(tmp_path / "t.json"), tmp_path)
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

    train, _ = short_training
    model = compensators.make("lstm", hidden=8, steps=5, seq_len=20, streams=4).fit(train.X, train.Y)
    fmu = export_compensator(model.save(tmp_path / "lstm.npz"), tmp_path)
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
        np.testing.assert_allclose(first, np.array([stream.step(r) for r in x]), rtol=0,
                                   atol=1e-12 * np.abs(first).max())
        a.fmu.reset()
        a.fmu.enterInitializationMode()
        a.fmu.exitInitializationMode()
        np.testing.assert_array_equal(np.array([step(a, k, row) for k, row in enumerate(x)]), first)
    finally:
        a.free()
        b.free()


@pytest.mark.integration
def test_build_fmus_cli_ships_a_compensator(tmp_path):
    import zipfile

    X, Y = _toy_series(300)
    model = compensators.make("grnn", max_patterns=50).fit(X, Y).save(tmp_path / "g.json")
    env = {**__import__("os").environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "sarins", "build-fmus", "--only", "IMUCompensator", "--out",
           str(tmp_path / "out"), "--compensator"]
    done = subprocess.run(cmd + [str(model)], cwd=ROOT, capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 0, done.stderr
    with zipfile.ZipFile(tmp_path / "out" / "IMUCompensator.fmu") as z:
        assert "resources/compensator.npz" in z.namelist()
    cmd[cmd.index("--out") + 1] = str(tmp_path / "out_bad")
    bad = subprocess.run(cmd + [str(tmp_path / "missing.json")], cwd=ROOT, capture_output=True, text=True,
                         timeout=300, env=env)
    assert bad.returncode != 0 and "missing.json" in bad.stderr
    assert not (tmp_path / "out_bad").exists()  # nothing built
