import math

import pytest

from sarins_fmu.site import SITE_LAT_DEG

LAT_DEG = SITE_LAT_DEG  # seed 000's site


@pytest.fixture
def lat():
    return math.radians(LAT_DEG)


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    """Every FMU built once per test session, with the project's systems
    (``<name>.ssp``) beside them.  Tests write only new files here."""
    from fmus.build import build_fmus
    from sarins.systems import write_systems

    out = tmp_path_factory.mktemp("fmus")
    build_fmus(out)
    write_systems(out)
    return out


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
