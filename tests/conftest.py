import math
import os
import shutil
import tempfile
from pathlib import Path

import pytest

# Hermetic: the tests (and every process they start, which inherits this environment) write nothing
# outside temporary folders.  HOME, the XDG folders and the FMUs' library cache point into one folder
# made for this session and removed at its end, before anything below can look them up.
HERMETIC_ROOT = Path(tempfile.mkdtemp(prefix="sarins-tests-"))
HERMETIC_ENV = {
    "HOME": HERMETIC_ROOT / "home",
    "XDG_CACHE_HOME": HERMETIC_ROOT / "cache",
    "XDG_CONFIG_HOME": HERMETIC_ROOT / "config",
    "XDG_DATA_HOME": HERMETIC_ROOT / "data",
    "SARINS_FMU_CACHE": HERMETIC_ROOT / "cache" / "sarins-fmu",
    "MPLCONFIGDIR": HERMETIC_ROOT / "config" / "matplotlib",
}
for _name, _folder in HERMETIC_ENV.items():
    _folder.mkdir(parents=True, exist_ok=True)
    os.environ[_name] = str(_folder)

from sarins_fmu.site import SITE_LAT_DEG  # noqa: E402 (after the environment is set)


def pytest_unconfigure(config):
    shutil.rmtree(HERMETIC_ROOT, ignore_errors=True)


def progress_line(config, text: str) -> None:
    """One line on the terminal now, even while pytest captures output (e.g. 'building the FMUs')."""
    capman = config.pluginmanager.getplugin("capturemanager")
    reporter = config.pluginmanager.getplugin("terminalreporter")
    if reporter is None:
        return
    if capman is None:
        reporter.write_line(text)
        return
    with capman.global_and_fixture_disabled():
        reporter.ensure_newline()
        reporter.write_line(text)

LAT_DEG = SITE_LAT_DEG  # seed 000's site


@pytest.fixture
def lat():
    return math.radians(LAT_DEG)


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory, pytestconfig):
    """Every FMU built once per test session, with the project's systems
    (``<name>.ssp``) beside them.  Tests write only new files here.  Linux x86-64 binaries only,
    but for the Turntable (every platform the build ships, when the cross compilers are there):
    the other platforms' binaries of every FMU are checked by the slow tests, which build their own."""
    from fmus.build import DEFAULT_NAMES, build_fmus
    from sarins.systems import write_systems

    out = tmp_path_factory.mktemp("fmus")
    progress_line(pytestconfig, f"building the session's FMUs in {out} ...")
    build_fmus(out, ["Turntable"])
    build_fmus(out, [n for n in DEFAULT_NAMES if n != "Turntable"], cross=False)
    write_systems(out)
    progress_line(pytestconfig, "built: " + ", ".join(sorted(p.stem for p in out.glob("*.fmu"))))
    return out


@pytest.fixture(scope="session")
def fmu3_dir(tmp_path_factory, pytestconfig):
    """The FMI 3.0 Turntable, IMUThermal and StrapdownINS (linux x86-64 only: quick), built once per
    session; a skip without a C compiler.  Tests write only new files here."""
    from fmus import SLAVES
    from fmus.native_fmu import build_native_fmu

    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler (gcc/cc)")
    out = tmp_path_factory.mktemp("fmus3")
    progress_line(pytestconfig, f"building the session's FMI 3.0 FMUs in {out} ...")
    for name in ("Turntable", "IMUThermal", "StrapdownINS"):
        build_native_fmu(name, SLAVES[name], out, fmi=3, win64=False, aarch64=False)
    return out


@pytest.fixture(scope="session")
def wine_env(tmp_path_factory):
    """Environment for running win64 programs under wine: one prefix per session (its first start
    costs about 20 s), in the session's temporary folder; a skip when mingw-w64 or wine is missing."""
    import subprocess

    from fmus.native_fmu import MINGW

    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    env = dict(os.environ, WINEPREFIX=str(tmp_path_factory.mktemp("wineprefix")), WINEDEBUG="-all")
    subprocess.run(["wine", "wineboot", "--init"], env=env, capture_output=True, timeout=600, check=True)
    return env


# The two real ADIS16405 static records (shared/data/adis16405, outside the repo: their licence keeps them
# out of the product); a test that needs them skips, saying where it looked, when they are not there.
REAL_DATA = __import__("pathlib").Path(__file__).resolve().parents[1].parent / "shared" / "data" / "adis16405"
REAL_UNITS = ("unit1", "unit2")


@pytest.fixture(scope="session")
def real_adis():
    """unit -> ImuLog of the real records, read once per session by the product's reader (axes frd:
    z down, as the records' README says; x taken forward), or a skip naming the folder."""
    import warnings

    from sarins_fmu.imu_log import ReadOptions, read_log

    if not all((REAL_DATA / f"{u}.csv.gz").is_file() for u in REAL_UNITS):
        pytest.skip(f"the real ADIS16405 records are not in {REAL_DATA} (shared/data, never copied into the repo)")
    logs = {}
    for unit in REAL_UNITS:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            logs[unit] = read_log(REAL_DATA / f"{unit}.csv.gz", ReadOptions(axes="frd", lat_deg=51.08, height_m=1100.0))
        logs[unit].caught = [str(w.message) for w in caught]
    return logs
