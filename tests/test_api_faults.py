"""Bad input to the Python API and a wrong environment: a clear ValueError (or one line and exit 2 from the
command), never a traceback from deep inside, never a silently wrapped or NaN result."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sarins_fmu.core import imu, ins, schedule

ROOT = Path(__file__).resolve().parents[1]


def _wrong_libraries(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("not a library\n")
    libm = next((p for p in ("/lib/x86_64-linux-gnu/libm.so.6", "/usr/lib/x86_64-linux-gnu/libm.so.6",
                             "/lib64/libm.so.6") if Path(p).is_file()), None)
    cases = {"text file": (text, "cannot be loaded as a shared library"),
             "folder": (tmp_path, "which is not a file"),
             "missing path": (tmp_path / "nowhere" / "_sarins_core.so", "which is not a file")}
    if libm:
        cases["libm"] = (Path(libm), "is not the sarins C physics core")
    return cases


@pytest.mark.parametrize("case", ["text file", "folder", "missing path", "libm"])
def test_a_wrong_core_library_is_named_in_one_line(case, tmp_path):
    cases = _wrong_libraries(tmp_path)
    if case not in cases:
        pytest.skip("no libm found at the usual Debian paths")
    path, words = cases[case]
    env = {**os.environ, "SARINS_CORE_LIB": str(path), "PYTHONPATH": str(ROOT)}
    env.pop("SARINS_DEBUG", None)
    done = subprocess.run([sys.executable, "-m", "sarins", "navigate", "--nav-hours", "0.01"], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sarins: error: SARINS_CORE_LIB names ") and words in lines[0]
    assert str(path) in lines[0]
    api = subprocess.run([sys.executable, "-c", "import sarins_fmu.core.imu"], capture_output=True, text=True,
                         env=env, timeout=120)
    assert api.returncode == 1 and "CoreNotBuilt: SARINS_CORE_LIB names" in api.stderr and words in api.stderr


def _increment_args(k=2):
    z = np.zeros
    return dict(axes=[[0.0, 0.0, 1.0]], angle0=z((k, 1)), rate0=z((k, 1)), accel=z((k, 1)), w_t=z((k, 3)),
                f_t=z((k, 3)), h=0.01, n_sub=2, g_sf=z((k, 3)), g_mis=z((3, 3)), g_bias=z((k, 3)), g_quad=z(3),
                g_lowrate=z(3), g_lowrate_width=np.ones(3), g_sens=z((3, 3)), a_sf=z((k, 3)), a_mis=z((3, 3)),
                a_bias=z((k, 3)), a_quad=z(3))


@pytest.mark.parametrize("bad, words", [
    ({"h": math.inf}, "h (interval, s) must be finite and > 0"),
    ({"h": math.nan}, "h (interval, s) must be finite and > 0"),
    ({"h": 0.0}, "h (interval, s) must be finite and > 0"),
    ({"n_sub": 2**64 + 2}, "n_sub (minor steps per interval) must be in 1 .. 9223372036854775807"),
    ({"n_sub": 2**63}, "n_sub (minor steps per interval) must be in 1 .. "),
    ({"n_sub": 0}, "n_sub (minor steps per interval) must be in 1 .. "),
    ({"n_sub": 2.5}, "n_sub (minor steps per interval) must be a whole number"),
])
def test_increments_refuse_what_the_core_cannot_carry(bad, words):
    good = imu.increments(**_increment_args())
    assert np.all(np.isfinite(good[0])) and np.all(np.isfinite(good[1]))
    with pytest.raises(ValueError) as caught:
        imu.increments(**{**_increment_args(), **bad})
    assert words in str(caught.value)


def test_n_sub_past_int64_is_not_wrapped_to_a_small_count():
    """2**64 + 2 would reach the C int64_t as 2: the same numbers as n_sub = 2 without a word."""
    with pytest.raises(ValueError, match="n_sub"):
        imu.increments(**{**_increment_args(), "n_sub": 2**64 + 2})


@pytest.mark.parametrize("args, words", [
    ((0.0, [], [0.0], [0.0]), "times must be a 1-D array"),
    (([[0.0, 1.0]], [[1.0]], [0.0], [0.0]), "times must be a 1-D array"),
    (([0.0, 1.0], [[1.0]], 0.0, [0.0]), "angle0 must be a 1-D array"),
    (([0.0, 1.0], [[1.0], [2.0]], [0.0], [0.0]), "accel must have shape (1, 1)"),
])
def test_schedule_integrate_says_which_input_is_wrong(args, words):
    angle, rate = schedule.integrate([0.0, 2.0], [[1.0]], [0.0], [0.0])
    assert angle[-1, 0] == pytest.approx(2.0) and rate[-1, 0] == pytest.approx(2.0)  # closed form a t^2/2, a t
    with pytest.raises(ValueError) as caught:
        schedule.integrate(*args)
    assert words in str(caught.value)


@pytest.mark.parametrize("config", [None, 3.0, object(), {"lat": 0.5}])
def test_ins_config_array_refuses_what_is_not_an_ins_config(config):
    with pytest.raises(ValueError, match="INS settings need an InsConfig"):
        ins.config_array(config)


def test_ins_config_array_names_a_setting_that_is_not_a_number():
    from sarins_fmu.ins import InsConfig

    good = InsConfig(lat=0.5)
    assert ins.config_array(good)[0] == 0.5
    bad = InsConfig(lat=0.5)
    object.__setattr__(bad, "step", "fast")
    with pytest.raises(ValueError, match="INS setting step must be a number"):
        ins.config_array(bad)
