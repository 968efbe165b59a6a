"""Optional error states of the ESKF (eskf.h: scale factors, lever arm, the receiver's Gauss-Markov errors) against
the truth: off they are the 15-state filter bit for bit; on they converge to the simulated values within their
3 sigma, and the Gauss-Markov states bring the position NEES with the SPS preset into its chi-square band."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core
from sarins_fmu.experiments.aided_nav import MANOEUVRES

STEP = 0.01
WHITE_GNSS = gnss.WHITE


@pytest.fixture(scope="module")
def truth():
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), MANOEUVRES), STEP)


def test_no_optional_state_is_the_15_state_filter_bit_for_bit(truth):
    a = aided.navigate(truth, seed=4, aiding=("gnss", "zupt", "zaru"))
    state = core.EskfState(aided._config(aided.IMU_NOISE["tactical"], aided.FilterSettings(), gnss.PRESETS["sps"], STEP),
                           truth.nav_rows()[0], np.zeros(core.ESKF_OPT))
    assert state.n == 15
    b = aided.navigate(truth, seed=4, aiding=("gnss", "zupt", "zaru"), filter_states=())
    for x, y in ((a.nav, b.nav), (a.cov, b.cov), (a.bias_g, b.bias_g)):
        assert np.array_equal(x, y)
    assert a.states == {} and a.cov.shape[1:] == (15, 15)


@pytest.mark.parametrize("states, n", [(("sf",), 21), (("lever",), 18), (("gnss-gm",), 21),
                                       (("sf", "lever", "gnss-gm"), 30)])
def test_the_state_dimension_and_layout(truth, states, n):
    r = aided.navigate(truth, seed=1, filter_states=states, covariance="diagonal")
    assert r.variance.shape[1] == n
    assert list(r.state_index.values()) == list(range(15, n, 3))
    full = aided.navigate(truth, seed=1, filter_states=states)
    assert full.cov.shape[1:] == (n, n)
    assert np.array_equal(full.variance, r.variance) and np.array_equal(full.nav, r.nav)
    assert np.allclose(full.cov, np.swapaxes(full.cov, 1, 2), rtol=0, atol=0)
    assert (np.linalg.eigvalsh(full.cov[-1]) > -1e-12 * np.abs(full.cov[-1]).max()).all()


def test_scale_factors_converge_within_3_sigma(truth):
    noise = dataclasses.replace(aided.IMU_NOISE["tactical"], gyro_sf_std=1e-3, accel_sf_std=1e-3)
    z_g, z_a, sig_gz = [], [], []
    for seed in range(5):
        r = aided.navigate(truth, noise=noise, gnss=WHITE_GNSS, seed=seed, filter_states=("sf",))
        sg, sa = aided.scale_factors(noise, seed)
        z_g.append((r.states["scale_g"][-1] - sg) / r.state_sigma("scale_g")[-1])
        z_a.append((r.states["scale_a"][-1] - sa) / r.state_sigma("scale_a")[-1])
        sig_gz.append(r.state_sigma("scale_g")[-1, 2])
        # without the states the 15-state filter's attitude is over-confident: the SF error is not in its model
        assert r.nees("attitude").mean() < 6.0
    assert (np.abs(z_g) < 3.0).all() and (np.abs(z_a) < 3.0).all()
    assert max(sig_gz) < 0.2e-3  # the yaw gyro's scale factor is learnt in the turns: prior 1e-3


def test_scale_factors_fix_the_15_state_filters_attitude_nees(truth):
    noise = dataclasses.replace(aided.IMU_NOISE["tactical"], gyro_sf_std=1e-3, accel_sf_std=1e-3)
    with_sf = [aided.navigate(truth, noise=noise, gnss=WHITE_GNSS, seed=s, filter_states=("sf",)).nees("attitude")
               .mean() for s in range(4)]
    without = [aided.navigate(truth, noise=noise, gnss=WHITE_GNSS, seed=s).nees("attitude").mean() for s in range(4)]
    assert np.mean(with_sf) < 5.0 < 10.0 < np.mean(without)


def test_the_lever_arm_converges_within_3_sigma(truth):
    """The filter told a lever arm 0.5 m off horizontally and 0.3 m vertically: the horizontal components are
    learnt in the turns (sigma below 0.1 m from the prior 0.5 m), the vertical one barely (a level drive); every component ends
    within 3 sigma of the truth."""
    receiver = dataclasses.replace(WHITE_GNSS, lever_arm=(0.5, 1.5, 1.2))
    settings = aided.FilterSettings(lever_arm=(0.0, 1.0, 0.9), lever0_std=0.5)
    for seed in range(4):
        r = aided.navigate(truth, gnss=receiver, seed=seed, filter_states=("lever",), settings=settings)
        err = r.states["lever"][-1] - receiver.lever_arm
        sigma = r.state_sigma("lever")[-1]
        assert (sigma[:2] < 0.1).all(), sigma  # from the prior 0.5 m
        assert (np.abs(err) < 3.0 * sigma).all(), (err, sigma)
    r0 = aided.navigate(truth, gnss=receiver, seed=0, settings=settings)  # no lever state: the offset stays
    assert r0.nees("position").mean() > 2.0 * r.nees("position").mean()


def test_the_gauss_markov_states_bring_the_sps_position_nees_into_its_band():
    segments = ({"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
                {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 300},
                {"kind": "turn", "rate_dps": 6, "angle_deg": -90}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
                {"kind": "stop", "duration": 10})  # docs/examples/aided_navigation_numbers.py drive(300, 0.01)
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), segments), STEP)
    off = aided.nees_monte_carlo(truth, 20, gnss=gnss.PRESETS["sps"])
    on = aided.nees_monte_carlo(truth, 50, gnss=gnss.PRESETS["sps"], filter_states=("gnss-gm",))
    assert off.mean_nees["position"].mean() > 20.0  # white-noise filter, Gauss-Markov receiver: over-confident
    lo, hi = on.band
    for block in ("position", "velocity", "attitude"):
        assert lo < on.mean_nees[block].mean() < hi, block
        assert on.inside[block] > 0.85, block


@pytest.mark.parametrize("bad, match", [(("scale",), "unknown filter states scale"),
                                        (("lever",), "need 'gnss'")])
def test_bad_filter_states_are_refused_naming_them(truth, bad, match):
    with pytest.raises(ValueError, match=match):
        aided.navigate(truth, aiding=("zupt",), filter_states=bad)


@pytest.mark.parametrize("index, value", [(0, 16.0), (0, 2.5), (1, -1.0), (8, 0.0)])
def test_the_core_refuses_bad_options(truth, index, value):
    opt = aided._options(("sf", "gnss-gm"), aided.FilterSettings(), gnss.PRESETS["sps"], True)
    opt[index] = value
    with pytest.raises(ValueError):
        core.EskfState(aided._config(aided.IMU_NOISE["tactical"], aided.FilterSettings(), None, STEP),
                       truth.nav_rows()[0], opt)


def test_imu_scale_factors_are_their_own_draws(truth):
    base = aided.IMU_NOISE["tactical"]
    a = aided.corrupt(truth, base, 3)
    b = aided.corrupt(truth, dataclasses.replace(base, gyro_sf_std=1e-3), 3)
    sg, _ = aided.scale_factors(dataclasses.replace(base, gyro_sf_std=1e-3), 3)
    assert np.allclose(b[0] - a[0], sg * truth.dtheta, rtol=0, atol=1e-18)
    assert np.array_equal(a[1], b[1])
    with pytest.raises(ValueError, match="numpy"):
        aided.corrupt(truth, dataclasses.replace(base, gyro_sf_std=1e-3), 3, stream="core")


SANITIZED_RUN = """
import numpy as np
from sarins_fmu import aided, trajectory as tr
from sarins_fmu.core import _lib
assert str(_lib.library_path()) == {lib!r}, _lib.library_path()
segments = ({{"kind": "stop", "duration": 5}}, {{"kind": "accelerate", "to_speed": 10, "accel": 2.0}},
            {{"kind": "turn", "rate_dps": 10, "angle_deg": 90}}, {{"kind": "accelerate", "to_speed": 0, "accel": 2.0}},
            {{"kind": "stop", "duration": 3}})
truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), segments), 0.02)
for states in [(), ("sf",), ("lever",), ("gnss-gm",), ("sf", "lever", "gnss-gm")]:
    for cov in ("full", "diagonal"):
        r = aided.navigate(truth, aiding=("gnss", "zupt", "zaru", "odometer", "nhc"), filter_states=states,
                           covariance=cov, settings=aided.FilterSettings(sf_tau=100.0))
        assert np.isfinite(r.nav).all() and np.isfinite(r.variance).all()
print("sanitized run ok")
"""


@pytest.mark.slow
def test_optional_states_under_address_and_undefined_behaviour_sanitizers(tmp_path):
    """The core rebuilt with ASan + UBSan (tests/sanitized_core.py) runs every state layout, 15 .. 30."""
    import sanitized_core

    sanitized_core.run(tmp_path, SANITIZED_RUN)
