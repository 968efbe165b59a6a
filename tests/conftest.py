import fcntl
import math
import os
import shutil
import tempfile
from pathlib import Path

import pytest

# Hermetic: the tests (and every process they start, which inherits this environment) write nothing
# outside temporary folders.  HOME, the XDG folders and the FMUs' library cache point into one folder
# made for this session and removed at its end, before anything below can look them up.  Under
# pytest-xdist the controller makes it and its workers (started after, with its environment) share it.
_ROOT_VAR = "SARINS_TESTS_HERMETIC_ROOT"
# the system's temporary folder, before the redirection below (the session folder is made in it)
SYSTEM_TMP = Path(os.environ.setdefault("SARINS_TESTS_SYSTEM_TMP", tempfile.gettempdir()))
if os.environ.get("PYTEST_XDIST_WORKER") and os.environ.get(_ROOT_VAR):
    HERMETIC_ROOT, _OWN_ROOT = Path(os.environ[_ROOT_VAR]), False
else:
    HERMETIC_ROOT, _OWN_ROOT = Path(tempfile.mkdtemp(prefix="sarins-tests-")), True
    os.environ[_ROOT_VAR] = str(HERMETIC_ROOT)
HERMETIC_ENV = {
    "HOME": HERMETIC_ROOT / "home",
    "XDG_CACHE_HOME": HERMETIC_ROOT / "cache",
    "XDG_CONFIG_HOME": HERMETIC_ROOT / "config",
    "XDG_DATA_HOME": HERMETIC_ROOT / "data",
    "SARINS_FMU_CACHE": HERMETIC_ROOT / "cache" / "sarins-fmu",
    "MPLCONFIGDIR": HERMETIC_ROOT / "config" / "matplotlib",
    # one object cache for every C build of the run (fmus.cbuild): the core's files compiled once
    "SARINS_CC_CACHE": HERMETIC_ROOT / "cache" / "cc",
    # what tempfile makes (FMPy's extract, pytest's own folders) is removed with the rest at the end
    "TMPDIR": HERMETIC_ROOT / "tmp",
}
for _name, _folder in HERMETIC_ENV.items():
    _folder.mkdir(parents=True, exist_ok=True)
    os.environ[_name] = str(_folder)
tempfile.tempdir = None  # looked up again, in TMPDIR

from sarins_fmu.site import SITE_LAT_DEG  # noqa: E402 (after the environment is set)


def pytest_unconfigure(config):
    if _OWN_ROOT:  # the controller's, after its workers have ended
        shutil.rmtree(HERMETIC_ROOT, ignore_errors=True)


MAX_AUTO_WORKERS = 4


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """Workers for ``-n auto`` (the default in pyproject's addopts): one per usable core, at most
    MAX_AUTO_WORKERS (each holds the FMUs' and numerics' memory); none (in-process, serial, as the slow
    acceptance tests are written for) when slow tests are selected or only one core is usable.  An
    explicit ``-n N`` is used as given."""
    if "slow" in (config.option.markexpr or "").replace("not slow", ""):
        return 0
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return min(cores, MAX_AUTO_WORKERS) if cores > 1 else 0


def built_once(tmp_path_factory, name, steps, last=None):
    """The folder ``name`` filled once per test run by ``steps`` ({key: function(folder)}, independent
    of each other) and then ``last(folder)``: in the session's temporary folder, or, under
    pytest-xdist, in the run's folder shared by the workers, which split the steps between them (a
    file lock per step: a worker builds the steps no other worker holds, then waits for the rest)."""
    steps = dict(steps, **({"last": last} if last else {}))
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        out = tmp_path_factory.mktemp(name)
        for step in steps.values():
            step(out)
        return out
    shared = tmp_path_factory.getbasetemp().parent  # this run's, above the workers' own folders
    out, marks = shared / name, shared / f"{name}.steps"
    out.mkdir(exist_ok=True)
    marks.mkdir(exist_ok=True)

    def run(key, wait):
        with open(marks / f"{key}.lock", "w") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
            except BlockingIOError:  # another worker is on it
                return
            if not (marks / f"{key}.done").exists():
                steps[key](out)
                (marks / f"{key}.done").touch()

    for key in steps:
        if key != "last":
            run(key, wait=False)
    for key in steps:  # the others' steps done (or redone here if they failed), then the last one
        run(key, wait=True)
    return out


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
    """Every FMU built once per test run (shared by pytest-xdist's workers), with the project's systems
    (``<name>.ssp``) beside them.  Tests write only new files here.  Linux x86-64 binaries only,
    but for the Turntable (every platform the build ships, when the cross compilers are there); in a
    run that selects the slow tests every FMU gets every platform, since their win64 and aarch64
    checks take the FMUs from here."""
    from fmus.build import DEFAULT_NAMES, build_fmus
    from sarins.systems import write_systems

    every_platform = "slow" in (pytestconfig.option.markexpr or "").replace("not slow", "")

    def build(name):
        return lambda out: build_fmus(out, [name], cross=None if name == "Turntable" or every_platform else False)

    def last(out):
        write_systems(out)
        progress_line(pytestconfig, "built: " + ", ".join(sorted(p.stem for p in out.glob("*.fmu"))))

    progress_line(pytestconfig, "building the session's FMUs ...")
    names = ["Turntable", *(n for n in DEFAULT_NAMES if n != "Turntable")]  # the longest (cross) build first
    return built_once(tmp_path_factory, "fmus", {n: build(n) for n in names}, last)


@pytest.fixture(scope="session")
def fmu3_dir(tmp_path_factory, pytestconfig):
    """The FMI 3.0 Turntable, IMUThermal and StrapdownINS (linux x86-64 only: quick), built once per
    session; a skip without a C compiler.  Tests write only new files here."""
    from fmus import SLAVES
    from fmus.native_fmu import build_native_fmu

    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler (gcc/cc)")
    def build(name):
        return lambda out: build_native_fmu(name, SLAVES[name], out, fmi=3, win64=False, aarch64=False)

    progress_line(pytestconfig, "building the session's FMI 3.0 FMUs ...")
    return built_once(tmp_path_factory, "fmus3", {n: build(n) for n in ("Turntable", "IMUThermal", "StrapdownINS")})


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
