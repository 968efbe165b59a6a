import math

import pytest

LAT_DEG = 28.222  # seed 000's site


@pytest.fixture
def lat():
    return math.radians(LAT_DEG)
