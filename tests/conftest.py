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
