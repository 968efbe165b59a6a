"""The shared comparison table (sarins.comparison): percentile definition and rows."""

import pytest

from sarins.comparison import MIN_RUNS, Claim, comparison_lines, percentile_of


@pytest.mark.parametrize("value, sample, expected", [
    (2.5, [1, 2, 3, 4], 50.0),  # between the two middle values
    (2.0, [1, 2, 3, 4], 37.5),  # (1 below + 1/2 tie) / 4
    (0.0, [1, 2, 3, 4], 0.0),  # below every run
    (9.0, [1, 2, 3, 4], 100.0),  # above every run
    (3.0, [1, 2, 3, 4, 5], 50.0),  # the median of an odd sample
    (1.0, [1, 1, 1, 1], 50.0),  # all ties
    (-47.0, [-80, -50, -40, -30, -10, 0, 5, 10, 20, 30], 20.0),  # 2 of 10 below
])
def test_percentile_of_hand_computed_cases(value, sample, expected):
    assert percentile_of(value, sample) == expected


def test_percentile_of_refuses_empty_or_nan():
    with pytest.raises(ValueError, match="empty"):
        percentile_of(1.0, [])
    with pytest.raises(ValueError, match="finite"):
        percentile_of(float("nan"), [1.0])


def test_rows_median_range_percentile_and_untested():
    tested = Claim("error (deg/h)", 0.0003, [0.0001, 0.0002, 0.0004, 0.0005, 0.0006])
    cells = tested.cells()
    assert cells[1] == "0.0003" and cells[2] == "0.0004 (n = 5)" and cells[4] == "40 %"
    assert cells[3] == "0.00012 .. 0.00058"  # np.percentile 5 / 95, linear
    band = Claim("residual (deg/h)", (0.0005, 0.0015), [0.0001 * k for k in range(1, 21)])
    assert band.cells()[4] == "22 .. 72 %"
    few = Claim("CEP change (%)", -47.0, [-10.0, 5.0])
    assert few.cells()[4] == f"not tested: too few runs (2 < {MIN_RUNS})"
    none = Claim("vehicle", -47.0, [], note="the quick profile runs no vehicle test")
    assert none.cells()[2:] == ["-", "-", "not tested: the quick profile runs no vehicle test"]
    text = "\n".join(comparison_lines([tested, few, none], profile="quick"))
    assert "| claim | paper value | ours (median) | ours 5-95 % | paper's percentile in ours |" in text
    assert "**The quick profile is too small to test:** CEP change (%); vehicle." in text


def test_a_row_text_with_a_cell_separator_is_refused():
    with pytest.raises(ValueError, match="Markdown cell"):
        Claim("|error| (deg/h)", 0.0003, [1.0])
