"""The native AidedINS FMU (fmus/c/aided_ins/model.c over the C core's eskf.h).

Fed the increments of sarins_fmu.aided.corrupt, each GNSS fix at the step after which navigate applies
it (its own schedule, aided.fix_rows) and navigate's per-step aiding rows (aided.per_step_aiding: ZUPT,
odometer, NHC, ZARU) as its inputs, the outputs (navigation, bias estimates, the filter's sigmas) equal
navigate's rows at every step bit for bit, for each aiding alone and all together, untagged and
time-tagged, FMI 2.0 and 3.0, and through the C host with an empty environment (no allocation after
initialisation); an FMU state taken mid-run repeats the rest, also deserialized into another instance;
bad parameters and bad aiding inputs are refused naming them.
"""

from __future__ import annotations

import subprocess
import zipfile
from typing import NamedTuple

import numpy as np
import pytest
from fmpy import read_model_description

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu
from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr

STEP = 0.02
SEED = 5
SEGMENTS = ({"kind": "stop", "duration": 1}, {"kind": "accelerate", "to_speed": 8, "accel": 2.0},
            {"kind": "turn", "rate_dps": 15, "angle_deg": 45}, {"kind": "cruise", "duration": 2})
GNSS = gnss.preset("sps", rate_hz=5.0, latency=2 * STEP, lever_arm=(0.2, 0.9, 1.1))
OUTAGES = [[3.0, 4.0]]
NOISE = aided.IMU_NOISE["tactical"]
SETTINGS = aided.FilterSettings(out_every=1)
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
OUT = NAV + [f"bias_{q}_{a}" for q in "ga" for a in "xyz"] + [f"sigma_{q}_{a}" for q in ("pos", "vel", "att")
                                                            for a in "enu"]
INPUTS = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"] + [f"fix_{n}" for n in NAV[:6]]
# the aiding inputs and their columns of the core's aiding row (eskf.h sarins_eskf_aid)
AID_INT = {"zupt": 0, "odo_valid": 4, "nhc": 6, "zaru": 9}
AID_REAL = {"zupt_v_e": 1, "zupt_v_n": 2, "zupt_v_u": 3, "odo_speed": 5, "nhc_v_x": 7, "nhc_v_z": 8}
STATE_SWITCHES = ["state_scale_factors", "state_lever_arm", "state_gnss_pos_gm", "state_gnss_vel_gm"]  # bits 1 2 4 8
STATE_SETTINGS = ["gyro_sf0_std", "accel_sf0_std", "sf_tau", "lever0_std", "gnss_pos_gm_std_e", "gnss_pos_gm_std_n",
                  "gnss_pos_gm_std_u", "gnss_pos_gm_tau", "gnss_vel_gm_std_e", "gnss_vel_gm_std_n", "gnss_vel_gm_std_u",
                  "gnss_vel_gm_tau"]  # eskf.h SARINS_ESKF_OPT after STATES
STATE_OUT = [f"{q}_{a}" for q, axes in (("scale_g", "xyz"), ("scale_a", "xyz"), ("lever_est", "xyz"),
                                        ("gnss_pos_gm", "enu"), ("gnss_vel_gm", "enu")) for a in axes]
SETTING_NAMES = ["step", "arw", "vrw", "gyro_rw", "accel_rw", "pos0_std", "vel0_std", "tilt0_std", "heading0_std",
                 "gyro_bias0_std", "accel_bias0_std", "lever_x", "lever_y", "lever_z", "latency", "zupt_std",
                 "cov_every", "nhc_std", "odo_std", "zaru_std"]


class Case(NamedTuple):
    """An aided run's FMU inputs and navigate's rows: params; inputs (K, 12) increments and fix values;
    flags (K, 2) fix valid / fix new; expected (K, 24) navigation, bias estimates, sigmas; aid (K, 10)
    navigate's per-step aiding rows; fixes (m, 11) its fix rows (aided.fix_rows); fix_time (m,) their
    validity times, s."""

    params: dict
    inputs: np.ndarray
    flags: np.ndarray
    expected: np.ndarray | None
    aid: np.ndarray
    fixes: np.ndarray
    fix_time: np.ndarray


def make_case(aiding, filter_states=(), settings=SETTINGS) -> Case:
    """With filter_states, the optional states' switches and priors are parameters too and expected carries
    their estimates after the 24 columns (STATE_OUT)."""
    SETTINGS = settings  # noqa: N806  (the module's name: the body below reads it)
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=35.0, heading_deg=-30.0), SEGMENTS), STEP)
    odometer = aided.OdometerConfig() if "odometer" in aiding else None
    result = aided.navigate(truth, noise=NOISE, gnss=GNSS, aiding=aiding, outages=OUTAGES, settings=SETTINGS,
                            seed=SEED, odometer=odometer, filter_states=filter_states)
    dtheta, dv, _, _ = aided.corrupt(truth, NOISE, SEED)
    rng = np.random.default_rng([SEED, 3018])  # navigate's: the initial errors, then the aiding's jitter
    nav0 = aided._initial_state(truth, SETTINGS, rng)
    aid = aided.per_step_aiding(truth, aiding, SETTINGS, odometer, rng, SEED)
    params = dict(zip(SETTING_NAMES, aided._config(NOISE, SETTINGS, GNSS, STEP, odometer).tolist()))
    params.update({f"{n}0": float(v) for n, v in zip(NAV, nav0)})
    params.update({f"gnss_{k}_std_{a}": float(v) for k, std in (("pos", GNSS.pos_std()), ("vel", GNSS.vel_std()))
                   for a, v in zip("enu", std)})
    if filter_states:
        opt = aided._options(filter_states, SETTINGS, GNSS, True)
        params.update(dict(zip(STATE_SWITCHES, [(int(opt[0]) >> b) & 1 for b in range(4)])))
        params.update(dict(zip(STATE_SETTINGS, opt[1:].tolist())))
        if "gnss-gm" in filter_states:  # the fixes' white part (aided.fix_rows(white=True))
            params.update({f"gnss_{k}_std_{a}": float(max(v, aided.GM_STD_FLOOR))
                           for k, std in (("pos", GNSS.pos_white_std), ("vel", GNSS.vel_white_std))
                           for a, v in zip("enu", std)})
    fixes = gnss.simulate(truth, GNSS, SEED, OUTAGES)
    rows, fix_time = aided.fix_rows(fixes, GNSS, STEP, white="gnss-gm" in filter_states), fixes.time
    if "gnss" not in aiding:
        rows, fix_time = rows[:0], fix_time[:0]
    k = truth.n_steps
    inputs = np.zeros((k, 12))
    inputs[:, :3], inputs[:, 3:6] = dtheta, dv
    flags = np.zeros((k, 2), int)
    for row in rows:
        i = int(row[0])
        if i < k:
            inputs[i, 6:] = row[2:8]
            flags[i, :2] = (int(row[1]), 1)
    sigma = np.sqrt(np.diagonal(result.cov, axis1=1, axis2=2)[:, :9])
    expected = np.column_stack([result.nav, result.bias_g, result.bias_a, sigma])
    if filter_states:
        est = [result.states.get(name, np.zeros((len(expected), 3))) for name, _ in aided.BLOCKS]
        expected = np.column_stack([expected, *est])
    if "gnss" in aiding:
        assert 0 < (flags[:, 1] & ~flags[:, 0]).sum() < flags[:, 1].sum()  # the outage drops some fixes
    return Case(params, inputs, flags, expected, aid, rows, fix_time)


@pytest.fixture(scope="module")
def case():
    return make_case(("gnss",))


@pytest.fixture(scope="module")
def zaru_case(case):
    """GNSS and ZARU at the first second's stop (50 steps)."""
    c = make_case(("gnss", "zaru"))
    assert c.aid[:, 9].sum() == 50 and not np.array_equal(c.expected, case.expected)
    return c


AIDINGS = {"zupt": ("zupt",), "odometer": ("odometer",), "nhc": ("nhc",),
           "all": ("gnss", "zupt", "odometer", "nhc", "zaru")}


@pytest.fixture(scope="module")
def aid_cases(case):
    """ZUPT at the first second's stop (50 steps), the odometer at 10 Hz (100 readings), NHC while moving (450 steps), each
    alone (no GNSS), and all five aidings together; each run differs from the GNSS-only run and from the
    pure INS (navigate(aiding=()))."""
    cases = {name: make_case(aiding) for name, aiding in AIDINGS.items()}
    pure = make_case(())
    counts = {name: (c.aid[:, 0].sum(), c.aid[:, 4].sum(), c.aid[:, 6].sum(), c.aid[:, 9].sum())
              for name, c in cases.items()}
    assert counts == {"zupt": (50, 0, 0, 0), "odometer": (0, 100, 0, 0), "nhc": (0, 0, 450, 0),
                      "all": (50, 100, 450, 50)}
    for c in cases.values():
        assert not np.array_equal(c.expected, pure.expected) and not np.array_equal(c.expected, case.expected)
    return cases


@pytest.fixture(scope="module")
def fmu(fmu_dir):
    return fmu_dir / "AidedINS.fmu"  # the session build (tests/conftest.py)


def step_inputs(case, k):
    """Interval k's inputs: Reals (INPUTS then AID_REAL) and Integers (fix_valid, fix_count, then AID_INT)."""
    reals = [*case.inputs[k], *case.aid[k, list(AID_REAL.values())]]
    ints = [int(case.flags[k, 0]), int(case.flags[:k + 1, 1].sum()), *case.aid[k, list(AID_INT.values())].astype(int)]
    return reals, [int(i) for i in ints]


def tagged_inputs(case, k, lag):
    """Time-tagged mode, doStep k of K + lag: interval k's increments and aiding (tag (k + 1) h; past the
    run the last tag again, which waits), the fix navigate applies after interval k (fix_time, fix_count
    growing), and fix_horizon (k + 1 - lag) h - latency: intervals up to k - lag are integrated, the next
    ``lag`` wait in the ring.  Returns {name: value}."""
    n = len(case.inputs)
    values = {"increment_end_time": min(k + 1, n) * STEP,
              "fix_horizon": (k + 1 - lag) * STEP - case.params["latency"]}
    if k < n:
        reals, ints = step_inputs(case, k)
        values.update(zip(INPUTS[:6] + list(AID_REAL), reals[:6] + reals[12:]))
        values.update(zip(AID_INT, ints[2:]))
    given = case.fixes[:, 0] <= min(k, n - 1)
    values["fix_count"] = int(given.sum())
    due = np.flatnonzero(case.fixes[:, 0] == k)
    if k < n and len(due):
        j = int(due[0])
        assert len(due) == 1
        values.update(zip(INPUTS[6:], case.fixes[j, 2:8].tolist()))
        values.update(fix_valid=int(case.fixes[j, 1]), fix_time=float(case.fix_time[j]))
    return values


def _run(fmu, case, state_at=None, lag=None, out_names=OUT):
    """The FMU through FMPy, one doStep per interval (``lag`` None: untagged; else time-tagged with ``lag``
    intervals waiting, lag more doSteps at the end).  Returns the rows after every doStep and fixes_used
    (time-tagged: the rows and their nav_time), or with ``state_at`` the rows after doStep state_at on,
    those again from the FMU state taken there, and those of another instance given the serialized state."""
    params = case.params
    slave = Slave(fmu, "ai")
    n = len(case.inputs) + (lag or 0)

    def steps(s, start, end, out):
        for k in range(start, end):
            if lag is None:
                reals, ints = step_inputs(case, k)
                s.fmu.setReal([s.vr[n] for n in INPUTS + list(AID_REAL)], reals)
                s.fmu.setInteger([s.vr[n] for n in ["fix_valid", "fix_count", *AID_INT]], ints)
            else:
                s.set(**tagged_inputs(case, k, lag))
            s.fmu.doStep(k * STEP, STEP)
            out.append(s.get(*out_names) + ([] if lag is None else s.get("nav_time")))

    try:
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        out = []
        steps(slave, 0, state_at or n, out)
        if state_at is None:
            return np.array(out), slave.fmu.getInteger([slave.vr["fixes_used"]])[0]
        state = slave.fmu.getFMUstate()
        blob = slave.fmu.serializeFMUstate(state)
        steps(slave, state_at, n, out)
        slave.fmu.setFMUstate(state)
        again = []
        steps(slave, state_at, n, again)
        other = Slave(fmu, "ai2")
        try:
            other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
            there = []
            steps(other, state_at, n, there)
        finally:
            other.free()
        return out, again, there
    finally:
        slave.free()


def test_fmu_equals_navigate_bit_for_bit(fmu, case):
    got, used = _run(fmu, case)
    assert np.array_equal(got, case.expected)
    assert used == case.flags[:, 0].sum() > 10
    assert got[-1, OUT.index("sigma_pos_e")] < case.params["gnss_pos_std_e"]  # the fixes bound the position


def test_state_round_trip_repeats_the_rest(fmu, case):
    out, again, there = _run(fmu, case, state_at=180)
    assert again == out[180:] and there == out[180:]


def test_fmu_with_zaru_equals_navigate_bit_for_bit(fmu, zaru_case):
    got, used = _run(fmu, zaru_case)
    assert np.array_equal(got, zaru_case.expected)
    assert used == zaru_case.flags[:, 0].sum() > 10


def test_state_round_trip_in_a_stop_with_zaru(fmu, zaru_case):
    out, again, there = _run(fmu, zaru_case, state_at=30)
    assert again == out[30:] and there == out[30:]


@pytest.mark.parametrize("name", list(AIDINGS))
def test_fmu_with_each_aiding_equals_navigate_bit_for_bit(fmu, aid_cases, name):
    c = aid_cases[name]
    got, used = _run(fmu, c)
    assert np.array_equal(got, c.expected)
    assert used == c.flags[:, 0].sum() and (used > 10) == (name == "all")


@pytest.mark.parametrize("name, lag", [("gnss", 0), ("gnss", 2), ("all", 0), ("all", 2)])
def test_time_tagged_mode_equals_navigate_bit_for_bit(fmu, case, aid_cases, name, lag):
    """Time-tagged: the rows at each nav_time equal navigate's, also with two intervals (their increments
    and aiding rows) waiting in the ring for fix_horizon."""
    c = case if name == "gnss" else aid_cases[name]
    got, used = _run(fmu, c, lag=lag)
    got = np.array(got)
    k = np.arange(len(got))
    np.testing.assert_array_equal(got[:, -1], np.maximum(k + 1 - lag, 0) * STEP)
    assert np.array_equal(got[lag:, :-1], c.expected)
    assert used == c.flags[:, 0].sum() > 10


@pytest.mark.parametrize("lag", [None, 2])
@pytest.mark.parametrize("state_at", [40, 305])
def test_state_round_trip_with_every_aiding(fmu, aid_cases, state_at, lag):
    """An FMU state taken in the stop (ZUPT, ZARU) or while moving (NHC; an odometer reading at interval 304,
    waiting in the ring when time-tagged) repeats the rest, in the same and in another instance."""
    c = aid_cases["all"]
    assert c.aid[state_at - 1, [0, 9]].all() if state_at == 40 else c.aid[304, [4, 6]].all()
    out, again, there = _run(fmu, c, state_at=state_at, lag=lag)
    assert again == out[state_at:] and there == out[state_at:]
    whole = _run(fmu, c, lag=lag)[0]
    assert [list(r) for r in whole] == [list(r) for r in out]


def _refused(fmu, case, values, lag=None):
    """doStep 0 with the inputs of interval 0 and ``values`` on top: the FMI error status and the log."""
    from fmpy.fmi1 import FMICallException

    slave = Slave(fmu, "bad_aid")
    try:
        slave.set(**case.params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        slave.set(**{**(tagged_inputs(case, 0, lag) if lag is not None else {}), **values})
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, STEP)
        return [m for status, _, m in slave.log if status == 3]
    finally:
        slave.free()


@pytest.mark.parametrize("lag", [None, 0])
@pytest.mark.parametrize("values, text", [
    ({"zaru": 2}, "input zaru = 2 at t = 0 s must be 0 or 1"),
    ({"zupt": -1}, "input zupt = -1 at t = 0 s must be 0 or 1"),
    ({"odo_valid": 3}, "input odo_valid = 3 at t = 0 s must be 0 or 1"),
    ({"nhc": 2}, "input nhc = 2 at t = 0 s must be 0 or 1"),
    ({"zupt": 1, "zupt_v_n": float("nan")}, "input zupt_v_n = nan at t = 0 s is not finite (zupt is 1)"),
    ({"odo_valid": 1, "odo_speed": float("inf")}, "input odo_speed = inf at t = 0 s is not finite (odo_valid is 1)"),
    ({"nhc": 1, "nhc_v_z": float("nan")}, "input nhc_v_z = nan at t = 0 s is not finite (nhc is 1)"),
])
def test_bad_aiding_input_is_refused(fmu, case, values, text, lag):
    errors = _refused(fmu, case, values, lag)
    assert any(text in m for m in errors), errors


FLAG_OF = {"zupt_v_e": "zupt", "zupt_v_n": "zupt", "zupt_v_u": "zupt", "odo_speed": "odo_valid", "nhc_v_x": "nhc",
           "nhc_v_z": "nhc"}


@pytest.mark.parametrize("lag", [None, 0])
def test_a_value_under_a_clear_flag_is_not_read(fmu, aid_cases, lag):
    """NaN in zupt_v_*, odo_speed and nhc_v_* whenever their flag is 0: not read, the run equals navigate's."""
    c = aid_cases["all"]
    slave = Slave(fmu, "clear_flags")
    try:
        slave.set(**c.params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        got, cleared = [], 0
        for k in range(len(c.inputs)):
            if lag is None:
                reals, ints = step_inputs(c, k)
                slave.fmu.setReal([slave.vr[n] for n in INPUTS], reals[:12])
                values = {**dict(zip(AID_REAL, reals[12:])), **dict(zip(["fix_valid", "fix_count", *AID_INT], ints))}
            else:
                values = tagged_inputs(c, k, lag)
            for name, flag in FLAG_OF.items():
                if not values[flag]:
                    values[name] = float("nan")
                    cleared += 1
            slave.set(**values)
            slave.fmu.doStep(k * STEP, STEP)
            got.append(slave.get(*OUT))
        assert np.array_equal(np.array(got), c.expected) and cleared > 1000
    finally:
        slave.free()


def test_state_of_the_previous_version_is_refused(fmu, case):
    """A serialized state of state version 5 (no stillness detector) is refused naming why."""
    from fmpy.fmi1 import FMICallException

    slave = Slave(fmu, "old_state")
    try:
        slave.set(**case.params)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        assert int.from_bytes(blob[12:16], "little") == 6
        blob[12:16] = (5).to_bytes(4, "little")
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.deSerializeFMUstate(bytes(blob))
        assert any("state version differs" in m for status, _, m in slave.log if status == 3), slave.log
    finally:
        slave.free()


def test_c_host_empty_environment_no_allocation(fmu, case, tmp_path):
    """The Reals through the C host (fix_count and fix_valid stay as set once: here every step carries a
    fix only when its fix_count grows, so the host run applies none and equals a pure INS run of FMPy)."""
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import COUNTER_SRC, HOST_SRC, _cc

    params, inputs = case.params, case.inputs
    host = tmp_path / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(host)])
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    zipfile.ZipFile(fmu).extractall(tmp_path / "f")
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rows_file = tmp_path / "rows.bin"
    inputs.astype("=f8").tofile(rows_file)
    ops = [f"r{vr[k]}={v!r}" for k, v in params.items()]
    ops += ["in=" + ",".join(str(vr[n]) for n in INPUTS), f"rows={rows_file}", "out=" + ",".join(str(vr[n])
                                                                                               for n in OUT)]
    cmd = [str(host), str(tmp_path / "f" / "binaries" / "linux64" / "AidedINS.so"), md.guid, str(len(inputs)),
           repr(STEP), *ops]
    proc = subprocess.run([*cmd, "allocs"], capture_output=True, text=True, timeout=120,
                          env={"LD_PRELOAD": str(counter)})
    assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]
    proc = subprocess.run([*cmd, "roundtrip=100"], capture_output=True, text=True, timeout=120, env={})
    assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:]

    def rows(tag):
        return {int(p[1]): [int(h, 16) for h in p[2:]] for p in (line.split() for line in proc.stdout.splitlines())
                if p and p[0] == tag}

    out, again = rows("OUT"), rows("AGAIN")
    no_fix = case._replace(flags=np.zeros_like(case.flags), expected=None)
    pure, used = _run(fmu, no_fix)
    assert used == 0
    assert [out[k] for k in range(1, len(inputs) + 1)] == pure.view(np.uint64).tolist()
    assert again and all(again[k] == out[k] for k in again)


@pytest.mark.parametrize("params, text", [
    ({"step": 0.0}, "step"),
    ({"arw": -1.0}, "arw"),
    ({"cov_every": 2.5}, "cov_every"),
    ({"gnss_pos_std_n": 0.0}, "gnss_pos_std_n"),
    ({"use_velocity": 2}, "use_velocity"),
    ({"zaru_std": -1e-4}, "zaru_std"),
    ({"zaru_std": float("nan")}, "zaru_std"),
    ({"lat0": 1.6}, "lat0"),
    ({"state_lever_arm": 2}, "state_lever_arm"),
    ({"state_scale_factors": -1}, "state_scale_factors"),
    ({"gyro_sf0_std": 0.0}, "gyro_sf0_std"),
    ({"sf_tau": -1.0}, "sf_tau"),
    ({"gnss_pos_gm_tau": 0.0}, "gnss_pos_gm_tau"),
    ({"gnss_vel_gm_std_u": float("nan")}, "gnss_vel_gm_std_u"),
    ({"zupt_source": 2}, "zupt_source = 2 must be 0"),
    ({"zupt_source": 1, "zvd_window": 1, "zvd_vrw": 1e-3, "zvd_arw": 1e-4}, "zvd_window = 1 must be 2 .. 4096"),
    ({"zupt_source": 1, "zvd_arw": 1e-4}, "zvd_vrw = 0 must be positive"),
    ({"zupt_source": 1, "zvd_vrw": 1e-3, "zvd_arw": float("nan")}, "zvd_arw"),
    ({"zupt_source": 1, "zvd_vrw": 1e-3, "zvd_arw": 1e-4, "zvd_gamma": -1.0}, "zvd_gamma = -1 must be positive"),
])
def test_bad_parameters_are_refused(fmu, params, text):
    check_parameter_error(fmu, params, text)


@pytest.fixture(scope="module")
def fmu3(tmp_path_factory):
    """The FMI 3.0 AidedINS (linux x86-64), validated by FMPy."""
    from fmpy.validation import validate_fmu

    path = build_native_fmu("AidedINS", "aided_ins_slave.py", tmp_path_factory.mktemp("fmi3"), fmi=3, win64=False,
                            aarch64=False)
    assert validate_fmu(str(path)) == []
    return path


@pytest.mark.parametrize("name", ["gnss", "zaru", *AIDINGS])
def test_fmi3_variant_equals_navigate(fmu3, case, zaru_case, aid_cases, name):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    c = {"gnss": case, "zaru": zaru_case, **aid_cases}[name]
    md = read_model_description(str(fmu3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu3)), modelIdentifier="AidedINS", instanceName="ai3")
    fmu.instantiate()
    try:
        fmu.setFloat64([vr[k] for k in c.params], list(c.params.values()))
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        got = []
        for k in range(len(c.inputs)):
            reals, ints = step_inputs(c, k)
            fmu.setFloat64([vr[n] for n in INPUTS + list(AID_REAL)], reals)
            fmu.setInt32([vr[n] for n in ["fix_valid", "fix_count", *AID_INT]], ints)
            fmu.doStep(k * STEP, STEP)
            got.append(fmu.getFloat64([vr[n] for n in OUT]))
        assert np.array_equal(np.array(got), c.expected)
        fmu.terminate()
    finally:
        fmu.freeInstance()


def test_receiver_into_aided_ins_equals_navigate_with_two_steps_latency(fmu, tmp_path):
    """GNSSReceiver -> AidedINS exchanged at every communication point (Jacobi): a fix valid at t_k leaves
    the receiver after doStep(t_k, h) and is applied in AidedINS's doStep(t_k + h, h), at t_k + 2h.  With
    latency = 2h in both, the chain equals navigate(aiding=('gnss',)) at every step bit for bit."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=35.0, heading_deg=-30.0), SEGMENTS), STEP)
    result = aided.navigate(truth, noise=NOISE, gnss=GNSS, aiding=("gnss",), outages=OUTAGES, settings=SETTINGS,
                            seed=SEED)
    assert GNSS.latency == 2 * STEP
    dtheta, dv, _, _ = aided.corrupt(truth, NOISE, SEED)
    nav0 = aided._initial_state(truth, SETTINGS, np.random.default_rng([SEED, 3018]))
    params = dict(zip(SETTING_NAMES, aided._config(NOISE, SETTINGS, GNSS, STEP).tolist()))
    params.update({f"{n}0": float(v) for n, v in zip(NAV, nav0)})
    params.update({f"gnss_{k}_std_{a}": float(v) for k, std in (("pos", GNSS.pos_std()), ("vel", GNSS.vel_std()))
                   for a, v in zip("enu", std)})
    receiver_fmu = fmu.parent / "GNSSReceiver.fmu"
    receiver = Slave(receiver_fmu, "rx")
    ins = Slave(fmu, "ins")
    truth_in = np.column_stack([truth.nav_rows(), truth.omega_ib_b])
    rx_in = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "omega_ib_x", "omega_ib_y",
             "omega_ib_z"]
    fix = [f"fix_{n}" for n in NAV[:6]]
    try:
        receiver.set(rate_hz=GNSS.rate_hz, seed=SEED, outages="3:4", **dict(zip(
            ["lever_x", "lever_y", "lever_z", "pos_white_e", "pos_white_n", "pos_white_u", "pos_gm_e", "pos_gm_n",
             "pos_gm_u", "pos_gm_tau", "vel_white_e", "vel_white_n", "vel_white_u", "vel_gm_e", "vel_gm_n",
             "vel_gm_u", "vel_gm_tau"], GNSS.array().tolist())))
        ins.set(**params)
        for s in (receiver, ins):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        got = []
        for k in range(truth.n_steps):
            fix_values = receiver.get(*fix)
            fix_ints = receiver.fmu.getInteger([receiver.vr["fix_valid"], receiver.vr["fix_count"]])
            receiver.fmu.setReal([receiver.vr[n] for n in rx_in], list(truth_in[k]))
            ins.fmu.setReal([ins.vr[n] for n in INPUTS], [*dtheta[k], *dv[k], *fix_values])
            ins.fmu.setInteger([ins.vr["fix_valid"], ins.vr["fix_count"]], list(fix_ints))
            receiver.fmu.doStep(k * STEP, STEP)
            ins.fmu.doStep(k * STEP, STEP)
            got.append(ins.get(*NAV))
        assert np.array_equal(np.array(got), result.nav)
        rows = aided.fix_rows(gnss.simulate(truth, GNSS, SEED, OUTAGES), GNSS, STEP)
        applied = int(np.sum((rows[:, 1] > 0) & (rows[:, 0] < truth.n_steps)))  # the last fix falls after the run
        assert ins.fmu.getInteger([ins.vr["fixes_used"]])[0] == applied > 10
    finally:
        receiver.free()
        ins.free()


# every optional state, the filter configured with a lever arm 0.3 m off the receiver's
STATES = ("sf", "lever", "gnss-gm")
STATE_SETTINGS_CASE = aided.FilterSettings(out_every=1, lever_arm=(0.0, 0.6, 1.1))


@pytest.fixture(scope="module")
def states_case(aid_cases):
    c = make_case(("gnss", "zupt", "zaru"), STATES, STATE_SETTINGS_CASE)
    assert c.expected.shape[1] == len(OUT) + len(STATE_OUT)
    assert np.abs(c.expected[-1, len(OUT):]).min() > 0  # every block estimated (none is 0)
    return c


def test_fmu_with_the_optional_states_equals_navigate_bit_for_bit(fmu, states_case):
    got, used = _run(fmu, states_case, out_names=OUT + STATE_OUT)
    assert np.array_equal(got, states_case.expected)
    assert used == states_case.flags[:, 0].sum() > 10
    out, again, there = _run(fmu, states_case, state_at=120, out_names=OUT + STATE_OUT)
    assert again == out[120:] and there == out[120:]
    assert [list(r) for r in got] == [list(r) for r in out]


def test_fmi3_with_the_optional_states_equals_navigate(fmu3, states_case):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    c = states_case
    md = read_model_description(str(fmu3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu3)), modelIdentifier="AidedINS", instanceName="ai3s")
    fmu.instantiate()
    try:
        ints = {k: v for k, v in c.params.items() if k in STATE_SWITCHES}
        reals = {k: v for k, v in c.params.items() if k not in ints}
        fmu.setFloat64([vr[k] for k in reals], list(reals.values()))
        fmu.setInt32([vr[k] for k in ints], list(ints.values()))
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        got = []
        for k in range(len(c.inputs)):
            r, i = step_inputs(c, k)
            fmu.setFloat64([vr[n] for n in INPUTS + list(AID_REAL)], r)
            fmu.setInt32([vr[n] for n in ["fix_valid", "fix_count", *AID_INT]], i)
            fmu.doStep(k * STEP, STEP)
            got.append(fmu.getFloat64([vr[n] for n in OUT + STATE_OUT]))
        assert np.array_equal(np.array(got), c.expected)
        fmu.terminate()
    finally:
        fmu.freeInstance()


DETECTED = ("gnss", "zupt", "zaru", "nhc")


@pytest.fixture(scope="module")
def detect_case(aid_cases):
    """navigate(gnss, zupt, zaru, nhc; zupt_detect 'imu', the car's vibration) as FMU inputs: the vibrating
    increments, the inputs zupt and zaru 1 at every step with the ZUPT jitter of every step (per_step_aiding with
    every step a stop, the same draws), zupt_source 1 and the detector's settings; the detector finds the first
    second's stop late by its window (26 of 50 steps: 24 .. 49), no moving step, and the rows differ from the
    truth's stops'."""
    from sarins_fmu import zero_velocity as zv

    vibration = zv.VIBRATION["car"]
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=35.0, heading_deg=-30.0), SEGMENTS), STEP)
    result = aided.navigate(truth, noise=NOISE, gnss=GNSS, aiding=DETECTED, outages=OUTAGES, settings=SETTINGS,
                            seed=SEED, zupt_detect="imu", vibration=vibration)
    base = make_case(DETECTED)
    dtheta, dv, _, _ = aided.corrupt(truth, NOISE, SEED)
    vib_theta, vib_v = zv.vibrate(truth, vibration, SEED)
    found = zv.detect(dtheta + vib_theta, dv + vib_v, STEP, NOISE.vrw, NOISE.arw)
    still = truth.stationary()
    assert 0 < found.stationary.sum() == result.zupt_steps < still.sum() and not np.any(found.stationary & ~still)
    rng = np.random.default_rng([SEED, 3018])
    aided._initial_state(truth, SETTINGS, rng)
    aid = aided.per_step_aiding(truth, DETECTED, SETTINGS, None, rng, SEED, stops=np.ones(truth.n_steps, bool))
    inputs = base.inputs.copy()
    inputs[:, :3], inputs[:, 3:6] = dtheta + vib_theta, dv + vib_v
    sigma = np.sqrt(np.diagonal(result.cov, axis1=1, axis2=2)[:, :9])
    expected = np.column_stack([result.nav, result.bias_g, result.bias_a, sigma])
    assert not np.array_equal(expected, base.expected)
    params = {**base.params, "zupt_source": 1, "zvd_window": found.samples, "zvd_gamma": found.gamma,
              "zvd_vrw": NOISE.vrw, "zvd_arw": NOISE.arw}
    return base._replace(params=params, inputs=inputs, expected=expected, aid=aid)


@pytest.mark.parametrize("lag", [None, 2])
def test_detected_stops_equal_navigate_bit_for_bit(fmu, detect_case, lag):
    """zupt_source 1: the FMU's causal detector (zvd.h) gives navigate(..., zupt_detect='imu')'s rows, untagged
    and time-tagged (two intervals waiting in the ring); a state taken in the detected stop (interval 40 of
    24 .. 49) or while moving repeats the rest, in the same and in another instance."""
    rows = _run(fmu, detect_case, lag=lag)[0]
    if lag is None:
        np.testing.assert_array_equal(rows, detect_case.expected)
    else:
        np.testing.assert_array_equal(rows[:, -1], np.maximum(np.arange(len(rows)) + 1 - lag, 0) * STEP)
        np.testing.assert_array_equal(rows[lag:, :-1], detect_case.expected)
    for state_at in (40, 120):
        out, again, there = _run(fmu, detect_case, state_at=state_at, lag=lag)
        assert again == out[state_at:] and there == out[state_at:]


def test_fmi3_detected_stops_equal_navigate(fmu3, detect_case):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    c = detect_case
    md = read_model_description(str(fmu3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu3)), modelIdentifier="AidedINS", instanceName="ai3z")
    fmu.instantiate()
    try:
        ints = {k: v for k, v in c.params.items() if k in ("zupt_source", "zvd_window")}
        fmu.setFloat64([vr[k] for k in c.params if k not in ints], [v for k, v in c.params.items() if k not in ints])
        fmu.setInt32([vr[k] for k in ints], [int(v) for v in ints.values()])
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        got = []
        for k in range(len(c.inputs)):
            reals, flags = step_inputs(c, k)
            fmu.setFloat64([vr[n] for n in INPUTS + list(AID_REAL)], reals)
            fmu.setInt32([vr[n] for n in ["fix_valid", "fix_count", *AID_INT]], flags)
            fmu.doStep(k * STEP, STEP)
            got.append(fmu.getFloat64([vr[n] for n in OUT]))
        np.testing.assert_array_equal(np.array(got), c.expected)
        fmu.terminate()
    finally:
        fmu.freeInstance()
