"""Allan deviation read-outs of the presets against their specs (sarins_fmu.allan)."""

import math

import numpy as np
import pytest

from sarins_fmu import allan, allan_readout, imu

RATE_HZ = 1.0  # a modest rate keeps the default run short; the slow test samples at 10 Hz


def _curves(name, duration, rate_hz=RATE_HZ, seed=1):
    gyro, accel, _ = allan.static_record(imu.preset(name), duration, rate_hz, seed=seed)
    taus, adev = allan.allan_deviation(np.hstack([gyro, accel]), rate_hz)
    return taus, adev


def test_flicker_floor_is_flat_at_0664_b():
    """The Gauss-Markov sum gives the flicker floor 0.664 B over 20 tau_min .. tau_max / 5."""
    from dataclasses import replace

    b = 1e-5
    model = replace(imu.preset("ideal"), gyro=imu.TriadErrors(flicker=np.full(3, b)),
                    flicker_tau_min=1.0, flicker_tau_max=3e4)
    duration = 2e5
    gyro, _, _ = allan.static_record(model, duration, 1.0, seed=3)
    taus, adev = allan.allan_deviation(gyro, 1.0, taus=[20, 50, 100, 200, 500, 1000, 2000])
    # within 2 % (the synthesis' ripple and its edge at 20 tau_min) plus 3 sigma of the mean over 3 axes
    # of an Allan deviation from M = T / tau clusters, relative sigma 1 / sqrt(2 (M - 1)) each
    sigma = 1.0 / np.sqrt(2.0 * 3 * (duration / taus - 1.0))
    assert np.all(np.abs(adev.mean(axis=1) / (allan.FLOOR * b) - 1) < 0.02 + 3 * sigma)


def _inside(name, hours, rate_hz, seed):
    """Every term the preset states (white N, flicker B, rate random walk K) inside its read-out's interval
    (a term not resolved: [0, bound]); returns the read-outs."""
    model = imu.preset(name)
    gyro, accel, _ = allan.static_record(model, hours * 3600.0, rate_hz, seed=seed)
    data = np.hstack([gyro, accel])
    reads = []
    for j, triad in enumerate(allan.TRIADS):
        spec = allan.spec(model, triad)
        for i in range(3):
            r = allan_readout.read_terms(allan_readout.octave_curve(data[:, 3 * j + i], rate_hz))
            for term in ("random_walk", "bias_instability", "rate_random_walk"):
                value = spec[term][i]
                if value > 0:
                    assert r[term].low <= value <= r[term].high, (name, triad, i, term, r[term], value)
            reads.append(r)
    return reads


@pytest.mark.parametrize("hours, rate_hz, seed", [pytest.param(2.0, 100.0, 0, marks=pytest.mark.slow), (28.0, 1.0, 0), (28.0, 1.0, 5)])
def test_mems_spec_inside_the_read_out_intervals(hours, rate_hz, seed):
    reads = _inside("mems", hours, rate_hz, seed)
    # the gyros' flat floor (B = 3 deg/h) is resolved; N is read at 1 s within 3 % of the spec
    assert all(r["bias_instability"].resolved for r in reads[:3])
    model = imu.preset("mems")
    for r, n in zip(reads, np.concatenate([model.gyro.random_walk, model.accel.random_walk])):
        assert r["random_walk"].tau == 1.0 and r["random_walk"].value == pytest.approx(n, rel=0.03)


def test_nav_rlg_random_walk_and_gauss_markov_bias_instability():
    """nav-rlg has no flicker floor (the papers imply none): its bias
    instability is a Gauss-Markov process, read with its correlation time.
    The gyro's (1e-4 deg/h, 2 h) peaks at 0.62e-4 deg/h, a quarter of the
    0.0005 deg/sqrt(h) random-walk line there, so only the random walk is
    read on the gyro curve; the floor and the rate random walk are not resolved."""
    duration = 4e5
    taus, adev = _curves("nav-rlg", duration)
    model = imu.preset("nav-rlg")
    gm_read = []
    for j, triad in enumerate(allan.TRIADS):
        spec = allan.spec(model, triad)
        for i in range(3):
            n, gm = allan.fit_gauss_markov(taus, adev[:, 3 * j + i], spec["gauss_markov_time"][i], duration)
            assert n == pytest.approx(spec["random_walk"][i], rel=0.10), (triad, i)
            if triad == "accel":
                gm_read.append(gm / spec["gauss_markov"][i])
    assert np.mean(gm_read) == pytest.approx(1.0, rel=0.10)
    peak = 0.62 * model.gyro.bias_instability[0]
    line = model.gyro.random_walk[0] / math.sqrt(1.89 * model.gyro.bias_corr_time[0])
    assert peak / line < 0.3
    for r in _inside("nav-rlg", 28.0, 1.0, 1)[:3]:
        assert not r["bias_instability"].resolved and r["bias_instability"].value is None


def test_gauss_markov_allan_variance_limits():
    std, tc = 2.0, 100.0
    assert allan.gauss_markov_avar(1e5, std, tc) == pytest.approx(2 * std**2 * tc / 1e5, rel=2e-3)
    assert allan.gauss_markov_avar(1e-2, std, tc) == pytest.approx(2 / 3 * std**2 * 1e-2 / tc, rel=1e-3)


def test_bad_allan_input():
    with pytest.raises(ValueError, match="finite"):
        allan.allan_deviation(np.array([1.0, np.nan, 2.0, 3.0]), 1.0)
    with pytest.raises(ValueError, match="fewer than 2"):
        allan.static_record(imu.preset("ideal"), 1.0, 1.0)
    with pytest.raises(ValueError, match="triad"):
        allan.spec(imu.preset("ideal"), "magnetometer")


@pytest.mark.slow
def test_mems_read_outs_at_10_hz_over_four_days():
    reads = _inside("mems", 96.0, 10.0, 5)
    assert all(r["rate_random_walk"].resolved for r in reads[:3])  # the +1/2 line shows past 1e4 s


def test_allan_command_prints_read_outs_and_writes_the_plot(tmp_path, capsys):
    import json

    from sarins.cli import main

    png = tmp_path / "allan.png"
    assert main(["allan", "--imu", "mems", "--hours", "6", "--seed", "2", "--plot", str(png), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    gx = out["channels"][0]
    assert gx["channel"] == "gyro_x" and gx["random_walk_unit"] == "deg/sqrt(h)"
    assert gx["random_walk"] == pytest.approx(gx["random_walk_spec"], rel=0.1)
    assert png.stat().st_size > 10000
    assert main(["allan", "--imu", "nav-rlg", "--hours", "111", "--json"]) == 0
    ax = json.loads(capsys.readouterr().out)["channels"][3]  # accel_x: a Gauss-Markov bias, read with its T
    assert ax["gauss_markov_unit"] == "ug" and ax["gauss_markov"] == pytest.approx(ax["gauss_markov_spec"], rel=0.1)
    assert main(["allan", "--imu", "ideal", "--hours", "0.5"]) == 0
    assert "gyro_z" in capsys.readouterr().out
    assert main(["allan", "--rate-hz", "-1"]) == 2
    assert "sarins allan: error: --rate-hz" in capsys.readouterr().err


def test_allan_command_on_a_recorded_log(tmp_path, capsys):
    import json

    from sarins.cli import main
    from sarins_fmu.imu_log import write_log

    gyro, accel, _ = allan.static_record(imu.preset("mems"), 20000.0, 1.0, seed=4)
    log = write_log(tmp_path / "static.npz", np.arange(1, 20001.0), gyro, accel, lat_deg=45.0)
    assert main(["allan", "--log", str(log), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["source"].startswith("log ") and "random_walk_spec" not in out["channels"][0]
    assert out["channels"][0]["random_walk"] == pytest.approx(0.15, rel=0.1)  # deg/sqrt(h), the mems preset's ARW
    low, high = out["channels"][0]["random_walk_interval"]
    assert low <= out["channels"][0]["random_walk"] <= high
    assert out["channels"][0]["quantization"] is None  # not resolved: no -1 slope in the record
    assert out["warnings"] == []


# -- our overlapping Allan deviation (issue 21: allantools dropped, it pulled Sphinx and numpydoc in) --


def test_hand_computed_series_exactly():
    """y = 1, 3, 2, 6, 4: m = 1, the successive differences 2, -1, 4, -2: sigma^2 = 25 / (2 * 4);
    m = 2, the overlapping 2-sample means 2, 2.5, 4, 5 differ by 2 and 2.5 at lag 2:
    sigma^2 = (4 + 6.25) / (2 * 2); m = 3 leaves no two differences and is dropped."""
    for rate in (1.0, 2.0):  # the deviation of rate data does not depend on the rate; tau does
        taus, dev = allan.overlapping_adev([1.0, 3.0, 2.0, 6.0, 4.0], rate, np.array([1.0, 2.0, 3.0]) / rate)
        np.testing.assert_allclose(taus, np.array([1.0, 2.0]) / rate, rtol=0, atol=0)
        np.testing.assert_allclose(dev, [math.sqrt(25.0 / 8.0), math.sqrt(10.25 / 4.0)], rtol=1e-14)


def test_white_noise_falls_as_one_over_root_tau():
    """White rate noise of std sigma_1 at tau0: sigma(tau) = sigma_1 / sqrt(tau / tau0). The overlapping
    estimate at m samples has a relative std below 1 / sqrt(K / m) (K samples); checked at 3 times that."""
    rate, n, sigma1 = 10.0, 200_000, 2.5e-6
    y = np.random.default_rng(7).normal(0.0, sigma1, n)
    taus, dev = allan.overlapping_adev(y, rate, allan.default_taus(n, rate))
    m = np.round(taus * rate)
    expected = sigma1 / np.sqrt(m)
    bound = 3.0 / np.sqrt(n / m)
    assert len(taus) > 30
    assert np.all(np.abs(dev / expected - 1.0) < bound), np.max(np.abs(dev / expected - 1.0) / bound)


def test_random_walk_rises_with_slope_one_half():
    """A rate random walk (integrated white noise) has sigma(tau) = K sqrt(tau / 3): log-log slope +1/2."""
    rate, n, k = 1.0, 100_000, 1e-8
    y = np.cumsum(np.random.default_rng(11).normal(0.0, k / math.sqrt(rate), n))
    taus, dev = allan.overlapping_adev(y, rate, np.geomspace(10.0, n / 20.0, 20))
    slope = np.polyfit(np.log(taus), np.log(dev), 1)[0]
    assert abs(slope - 0.5) < 0.05, slope
    np.testing.assert_allclose(dev, k * np.sqrt(taus / 3.0), rtol=0.35)


def test_averaging_times_and_bad_input():
    taus, _ = allan.allan_deviation(np.random.default_rng(0).normal(size=100), 10.0, [0.04, 0.1, 0.1, 0.12, 50.0])
    np.testing.assert_allclose(taus, [0.1])  # 0.04 s -> m = 0 dropped, repeats merged, 50 s beyond the record
    with pytest.raises(ValueError, match="at least two cluster"):
        allan.allan_deviation(np.ones(10), 1.0, [6.0])
    with pytest.raises(ValueError, match="sample rate"):
        allan.allan_deviation(np.ones(10), 0.0)


def test_the_package_does_not_need_allantools():
    import tomllib
    from pathlib import Path

    project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]
    assert not any(d.startswith("allantools") for d in project["dependencies"])
    source = Path(allan.__file__).read_text()
    assert "import allantools" not in source


@pytest.mark.parametrize("seed, rate, n", [(1, 10.0, 5000), (2, 200.0, 20_000), (3, 1.0, 777)])
def test_same_numbers_as_allantools_when_it_is_installed(seed, rate, n):
    allantools = pytest.importorskip("allantools")
    rng = np.random.default_rng(seed)
    y = rng.normal(size=n) * 1e-5 + np.cumsum(rng.normal(size=n)) * 1e-7 + 3.0
    taus = allan.default_taus(n, rate)
    ours_t, ours = allan.overlapping_adev(y, rate, taus)
    theirs_t, theirs, _, _ = allantools.oadev(y - y.mean(), rate=rate, data_type="freq", taus=taus)
    np.testing.assert_array_equal(ours_t, theirs_t)
    np.testing.assert_allclose(ours, theirs, rtol=1e-10)
