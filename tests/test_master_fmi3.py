"""FMI 3.0 co-simulation FMUs in the master: arrays, structural parameters, mixed FMI 2.0 / 3.0.

The fixtures (tests/fmu_fixtures/fmi3, C, compiled once per session): ``Burst3``
outputs ``samples[n]``, y = slope * t at the ends of the n sub-intervals of the last
step; ``Sum3`` integrates its input ``u[n]`` by the rectangle rule, integral +=
(h / n) * sum(u).  Gauss-Seidel feeds Sum3 the samples of the same step, so the
integral is the right Riemann sum of slope * t with step h / n:
slope * (T^2 / 2 + T h / (2 n)).
"""
from __future__ import annotations

import json
import subprocess
import sys
import warnings
import zipfile

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from fmu_fixtures.fixtures import fixture_fmus, fmi3_fmus  # noqa: F401 (fixtures)
from orchestration import (Component, Connection, FMUCallError, IncompatibleConnectionError,
                           Master, StartValueError, System, SystemDescriptionError,
                           SystemFileError, UnconnectedInputWarning, build_container_fmu,
                           read_system, simulate_system, write_ssp)
from orchestration.fmitypes import element_names
from orchestration.fmu import read_description

pytestmark = pytest.mark.integration

SLOPE, N, H, STOP = 2.0, 5, 0.1, 1.0


def burst_sum(fmus, n_burst: int = N, n_sum: int = N, **burst) -> System:
    return System("burst_sum",
                  [Component("b", fmus["Burst3"], {"slope": SLOPE, "n": n_burst, **burst}),
                   Component("s", fmus["Sum3"], {"n": n_sum})],
                  [Connection.between("b.samples", "s.u"), Connection.between("b.count", "s.m"),
                   Connection.between("b.pairs", "s.v")])


def run(system, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        return simulate_system(system, *args, **kwargs)


def test_fixtures_pass_fmpy_validate(fmi3_fmus):
    from fmpy.validation import validate_fmu

    for path in fmi3_fmus.values():
        assert validate_fmu(str(path)) == []


def test_gauss_seidel_moves_the_array_in_one_call_and_matches_the_closed_form(fmi3_fmus):
    result = run(burst_sum(fmi3_fmus), STOP, H)
    t = np.arange(0.0, STOP + H / 2, H)
    assert_allclose(result["time"], t, atol=1e-15)
    columns = [f"b.samples[{k}]" for k in range(1, N + 1)]
    assert [name for name in result.dtype.names if name.startswith("b.samples")] == columns
    samples = np.column_stack([result[c] for c in columns])
    expected = SLOPE * (t[1:, None] - H + np.arange(1, N + 1) * H / N)
    assert_allclose(samples[1:], expected, rtol=1e-14)
    assert_allclose(samples[0], 0.0)
    assert_allclose(result["b.ends[1]"], samples[:, 0])
    assert_allclose(result["b.ends[2]"], samples[:, -1])
    # right Riemann sum of slope * t with step h / n
    assert_allclose(result["s.integral"], SLOPE * (t ** 2 / 2 + t * H / (2 * N)), rtol=1e-13)
    assert_array_equal(result["s.m_out"], np.arange(t.size))
    # the [n, 2] array: columns row-major, moved whole; Sum3 adds its columns
    pairs = [name for name in result.dtype.names if name.startswith("b.pairs")]
    assert pairs[:4] == ["b.pairs[1,1]", "b.pairs[1,2]", "b.pairs[2,1]", "b.pairs[2,2]"]
    assert len(pairs) == 2 * N
    assert_allclose(result[f"b.pairs[{N},1]"][1:], t[1:], rtol=1e-14)
    assert_allclose(result[f"b.pairs[{N},2]"], samples[:, -1])
    times = N * (t[1:] - H) + H * (N + 1) / 2  # sum of the sub-interval ends of the last step
    assert_allclose(result["s.v_sum[1]"][1:], times, rtol=1e-13)
    assert_allclose(result["s.v_sum[2]"][1:], SLOPE * times, rtol=1e-13)
    assert result["b.count"].dtype == np.int32 and result["s.flag_out"].dtype == np.bool_
    assert result.meta["order"] == ["b", "s"]


def test_jacobi_delays_the_array_by_one_step(fmi3_fmus):
    result = run(burst_sum(fmi3_fmus), STOP, H, scheme="jacobi")
    j = np.arange(result.size)  # steps done; Sum3 integrates the samples of the step before
    done = np.maximum(j - 1, 0)
    integral = SLOPE * H ** 2 * (done * (done - 1) / 2 + done * (N + 1) / (2 * N))
    assert_allclose(result["s.integral"], integral, rtol=1e-13, atol=1e-15)
    assert_array_equal(result["s.m_out"][1:], j[:-1])


def test_single_fmus_equal_fmpy_simulate_fmu(fmi3_fmus):
    from fmpy import simulate_fmu

    u = [1.0, -2.0, 3.5, 4.0]
    for name, starts in (("Burst3", {"slope": SLOPE}), ("Sum3", {"u": u, "k": 2.0})):
        system = System(name, [Component("c", fmi3_fmus[name], starts)], [])
        ours = run(system, STOP, H)
        theirs = simulate_fmu(str(fmi3_fmus[name]), stop_time=STOP, output_interval=H,
                              start_values=starts)
        assert_allclose(ours["time"], theirs["time"], atol=1e-12)
        for field in theirs.dtype.names[1:]:
            value = theirs[field].reshape(len(theirs), -1)  # row-major, as the master's columns
            for k, column in enumerate(element_names(f"c.{field}", theirs.dtype[field].shape)):
                # FMPy steps by differences of communication points (h differs in the last bits)
                assert_allclose(ours[column], value[:, k], rtol=1e-14, atol=1e-15, err_msg=column)


def test_mixed_fmi2_and_fmi3_system(fixture_fmus, fmi3_fmus):
    # FMI 2.0 Real/Integer/Boolean into FMI 3.0 Float32/Int32/Boolean and FMI 3.0 Float64/Int32/Boolean
    # into FMI 2.0 (Real -> Float32 and the Booleans, int in FMI 2.0 and bool in FMI 3.0, are cast)
    system = System("mixed",
                    [Component("ramp", fixture_fmus["Ramp"], {"slope": 2.0, "offset": -0.5}),
                     Component("b", fmi3_fmus["Burst3"], {"slope": SLOPE, "n": 4}),
                     Component("s", fmi3_fmus["Sum3"], {"n": 4}),
                     Component("gain", fixture_fmus["Gain"], {"k": 3.0})],
                    [Connection.between("ramp.y", "s.k"), Connection.between("ramp.count", "s.m"),
                     Connection.between("ramp.positive", "s.flag"),
                     Connection.between("b.samples", "s.u"),
                     Connection.between("b.y", "gain.u"), Connection.between("s.m_out", "gain.n_in"),
                     Connection.between("s.flag_out", "gain.flag_in")])
    h = 0.125
    for scheme in ("gauss-seidel", "jacobi"):
        result = run(system, 1.0, h, scheme=scheme)
        t = result["time"]
        ramp = -0.5 + 2.0 * t
        assert_allclose(result["ramp.y"], ramp)
        if scheme == "gauss-seidel":
            assert_array_equal(result["s.m_out"], result["ramp.count"])
            assert_array_equal(result["s.flag_out"], ramp > 0)
            assert_array_equal(result["gain.flag_out"][1:], ramp[1:] > 0)
            assert_array_equal(result["gain.n_out"], result["ramp.count"])
            assert_allclose(result["gain.y"][1:], 3.0 * SLOPE * t[1:])
            mean = SLOPE * (t[1:] - h + h * (np.arange(1, 5).mean()) / 4)
            assert_allclose(result["s.scaled"][1:], ramp[1:] * mean, rtol=1e-6)  # k is a Float32
        else:  # one step of delay per link: s.flag_out lags one, gain.flag_out two
            assert_array_equal(result["s.flag_out"][1:], ramp[:-1] > 0)
            assert_array_equal(result["gain.flag_out"][2:], ramp[:-2] > 0)
            assert_array_equal(result["gain.n_out"][2:], result["ramp.count"][:-2])
            assert_allclose(result["gain.y"][1:], 3.0 * SLOPE * t[:-1])
        assert result["gain.flag_out"].dtype == np.bool_


def test_array_dimension_mismatch_is_refused_naming_both_ends(fmi3_fmus):
    with pytest.raises(IncompatibleConnectionError,
                       match=r"b\.samples is an array of shape \[4\], s\.u is an array of shape \[6\]"):
        Master(burst_sum(fmi3_fmus, n_burst=4, n_sum=6))
    scalar_to_array = System("x", [Component("b", fmi3_fmus["Burst3"]), Component("s", fmi3_fmus["Sum3"])],
                             [Connection.between("b.y", "s.u")])
    with pytest.raises(IncompatibleConnectionError, match=r"b\.y is a scalar, s\.u is an array of shape \[4\]"):
        Master(scalar_to_array)


def test_structural_parameter_and_array_start_values_are_checked(fmi3_fmus):
    with pytest.raises(StartValueError, match="-1 is not a valid UInt64 value"):
        Master(burst_sum(fmi3_fmus, n_burst=-1))
    wrong = System("x", [Component("s", fmi3_fmus["Sum3"], {"n": 3, "u": [1.0, 2.0]})], [])
    with pytest.raises(StartValueError, match=r"shape \[3\] needs 3 values"):
        Master(wrong)
    # n = 100 passes the type check; the FMU refuses it in Configuration Mode, saying why
    with pytest.raises(FMUCallError, match=r"fmi3SetUInt64.*n must be in 1\.\.64"):
        run(burst_sum(fmi3_fmus, n_burst=100, n_sum=100), STOP, H)


def test_units_of_fmi3_variables_are_converted(fmi3_fmus):
    system = burst_sum(fmi3_fmus)
    system.connections.append(Connection.between("b.y", "s.k"))  # m into mm: factor 1000
    result = run(system, STOP, H)
    t = result["time"][1:]
    mean = SLOPE * (t - H + H * (N + 1) / (2 * N))
    assert_allclose(result["s.scaled"][1:], 1000.0 * SLOPE * t * mean, rtol=1e-6)  # k is a Float32
    assert result.meta["converted_connections"] == {"b.y -> s.k": [1000.0, 0.0]}


def test_get_and_set_arrays_and_strings_during_a_run(fmi3_fmus):
    seen = []

    def callback(time, master):
        seen.append(master.get("b.samples"))
        master.set("s.u", [1.0, 1.0, 1.0, 1.0])
        assert master.get("b.label") == "first burst"
        assert master.get("s.k") == 0.5 and master.get("b.n") == 4

    system = System("x", [Component("b", fmi3_fmus["Burst3"], {"label": "first burst"}),
                          Component("s", fmi3_fmus["Sum3"], {"k": 0.5})], [])
    result = run(system, 0.3, 0.1, callback=callback)
    assert seen[0].shape == (4,) and seen[0].dtype == np.float64
    assert_allclose(seen[-1], 0.2 + np.arange(1, 5) * 0.1 / 4)
    assert_allclose(result["s.integral"], [0.0, 0.0, 0.1, 0.2])  # u = 1 from the second step on


def test_terminate_simulation_ends_the_run_after_that_step(fmi3_fmus):
    result = run(burst_sum(fmi3_fmus, stop_after=3), STOP, H)
    assert result.meta["terminated_by"] == "b" and result.meta["stopped_early"]
    assert result.meta["steps"] == 3
    assert_allclose(result["time"], [0.0, 0.1, 0.2, 0.3])


def test_ssp_file_with_fmi3_components_and_the_cli_units_sidecar(fmi3_fmus, tmp_path):
    system = burst_sum(fmi3_fmus)
    path = write_ssp(system, tmp_path / "burst.ssp")
    from_file = run(read_system(path), STOP, H)
    in_python = run(system, STOP, H)
    assert from_file.dtype.names == in_python.dtype.names
    for name in in_python.dtype.names:
        assert_array_equal(from_file[name], in_python[name])
    csv = tmp_path / "out.csv"
    done = subprocess.run([sys.executable, "-m", "sarins", "cosim", str(path), "--stop-time", "0.2",
                           "--step", "0.1", "--no-progress", "--output", str(csv)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    header = csv.read_text().splitlines()[0].split(",")
    assert header[1:N + 1] == [f"b.samples[{k}]" for k in range(1, N + 1)]
    units = json.loads((tmp_path / "out.csv.units.json").read_text())
    assert units["b.samples[1]"] == units[f"b.samples[{N}]"] == "m"
    assert units["s.integral"] == "m.s" and units["b.count"] == "1"


def test_refused_where_fmi3_is_not_supported(fmi3_fmus, tmp_path):
    with pytest.raises(SystemDescriptionError, match="hosts FMI 2.0 components only; this one is FMI 3.0"):
        build_container_fmu(burst_sum(fmi3_fmus), tmp_path / "c.fmu")
    with pytest.raises(SystemFileError, match=r"FMI version 3\.0 is not supported \(FMI 2\.0 co-simulation only\)"):
        read_description(fmi3_fmus["Burst3"], "b")  # what the third-party importers read with
    with_array_start = System("x", [Component("s", fmi3_fmus["Sum3"], {"u": [1.0, 2.0, 3.0, 4.0]})], [])
    with pytest.raises(SystemFileError, match="cannot be written to SSP 1.0"):
        write_ssp(with_array_start, tmp_path / "x.ssp")


def test_fmu_with_clocks_is_refused(fmi3_fmus, tmp_path):
    clocked = tmp_path / "Clocked.fmu"
    with zipfile.ZipFile(fmi3_fmus["Burst3"]) as source, zipfile.ZipFile(clocked, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b"  </ModelVariables>", b'    <Clock name="tick" valueReference="9" '
                                    b'causality="input" intervalVariability="triggered"/>\n  </ModelVariables>')
            target.writestr(item, data)
    with pytest.raises(SystemFileError, match="FMI 3.0 clocks are not supported.*: tick"):
        Master(System("x", [Component("c", clocked)], []))
