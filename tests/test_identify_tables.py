"""Tests of sarins_fmu.identify.tables and the packaged seed-000 tables."""

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from sarins_fmu.identify.tables import (
    SEED000_SITE_LAT_DEG,
    TableError,
    numeric_column,
    read_table,
    axial_rbf_table2_hot,
    axial_rbf_table4_cold,
    write_table,
)


def test_table2_hot_against_the_paper():
    t = axial_rbf_table2_hot()
    assert len(t["drift_dph"]) == 16
    # (row, latitude reading deg, temperature range degC, drift deg/h) typed from Table 2
    for row, lat, t_min, t_max, drift in [
        (1, 28.2274, 37, 39, 0.0007),
        (3, 28.2162, 55, 55, -0.00076),
        (7, 28.2474, 48, 49, 0.0034),
        (10, 28.1966, 49, 52, -0.00339),
        (16, 28.1978, 42, 42, -0.00301),
    ]:
        i = row - 1
        assert t["sample"][i] == row
        assert t["lat_deg"][i] == lat
        assert (t["temp_min_c"][i], t["temp_max_c"][i]) == (t_min, t_max)
        assert t["drift_dph"][i] == drift
    assert SEED000_SITE_LAT_DEG == 28.222
    assert_allclose(t["lat_error_deg"], t["lat_deg"] - 28.222, atol=1e-12)
    assert_array_equal(t["temp_c"], (t["temp_min_c"] + t["temp_max_c"]) / 2)
    assert_array_equal(t["temp_change_c"], t["temp_max_c"] - t["temp_min_c"])


def test_table4_cold_against_the_paper():
    t = axial_rbf_table4_cold()
    assert len(t["drift_dph"]) == 6
    # (row, align range, align diff, calib range, calib diff, lat, true drift, hot RBF)
    for row, a_min, a_max, a_diff, c_min, c_max, c_diff, lat, drift, hot in [
        (1, 12, 35, 23, 25, 35, 10, 28.2413, 0.00165, 0.0027),
        (3, 42, 62, 20, 53, 62, 9, 28.2028, -0.00330, -0.0027),
        (6, 46, 59, 13, 53, 59, 6, 28.1980, -0.00345, -0.0031),
    ]:
        i = row - 1
        got = [t[k][i] for k in ("align_temp_min_c", "align_temp_max_c", "align_temp_diff_c",
                                 "calib_temp_min_c", "calib_temp_max_c", "calib_temp_diff_c",
                                 "lat_deg", "drift_dph", "hot_rbf_drift_dph")]
        assert got == [a_min, a_max, a_diff, c_min, c_max, c_diff, lat, drift, hot]
    assert_array_equal(t["align_temp_diff_c"], t["align_temp_max_c"] - t["align_temp_min_c"])
    assert_array_equal(t["calib_temp_diff_c"], t["calib_temp_max_c"] - t["calib_temp_min_c"])
    assert_array_equal(t["temp_change_c"], t["align_temp_diff_c"])
    assert_array_equal(t["temp_c"], (t["calib_temp_min_c"] + t["calib_temp_max_c"]) / 2)
    assert_allclose(t["lat_error_deg"], t["lat_deg"] - 28.222, atol=1e-12)


def test_write_read_round_trip(tmp_path):
    table = {"n": np.array([1.0, 2.0]), "x": np.array([0.1, -1e-300]), "s": np.array(["a", "b"])}
    write_table(tmp_path / "t.csv", table)
    back = read_table(tmp_path / "t.csv")
    assert list(back) == ["n", "x", "s"]
    assert_array_equal(back["x"], table["x"])
    assert_array_equal(back["s"], table["s"])
    assert (tmp_path / "t.csv").read_text().splitlines()[1].startswith("1,")


@pytest.mark.parametrize(
    "text, message",
    [
        ("", "empty"),
        ("a,b\n", "no data rows"),
        ("a,a\n1,2\n", "duplicate"),
        ("a,\n1,2\n", "blank column"),
        ("a,b\n1,2\n3\n", "line 3 has 1 fields"),
        ("a,b\n1,2\n\n3,4\n", "line 3 is blank"),
    ],
)
def test_bad_tables(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(TableError, match=message):
        read_table(path)


def test_numeric_column_errors(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("a,b,c\n1,x,nan\n2,3,4\n")
    t = read_table(path)
    assert_array_equal(numeric_column(t, "a", path), [1.0, 2.0])
    with pytest.raises(TableError, match="column 'b' line 2: 'x' is not a number"):
        numeric_column(t, "b", path)
    with pytest.raises(TableError, match="column 'c' line 2: value is not finite"):
        numeric_column(t, "c", path)
    with pytest.raises(TableError, match="no column 'd'"):
        numeric_column(t, "d", path)
    with pytest.raises(TableError, match="no such file"):
        read_table(tmp_path / "absent.csv")
