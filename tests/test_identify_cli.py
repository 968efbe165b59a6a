"""Tests of the `sarins identify` subcommands (sarins.cli.identify)."""

import argparse
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins.cli import main
from sarins.cli.identify import DEFAULT_GOAL, register
from sarins_fmu.identify.rbf import RBFNetwork
from sarins_fmu.identify.tables import (
    TABLE2_HOT,
    TABLE4_COLD,
    packaged_table_path,
    read_table,
    write_table,
)

HOT = str(packaged_table_path(TABLE2_HOT))
COLD = str(packaged_table_path(TABLE4_COLD))
GOAL = 0.0003**2  # (deg/h)^2: seed 000's training error 0.0003 deg/h as an RMS


def _train(tmp_path, *extra, data=HOT, name="hot.json"):
    out = tmp_path / name
    rc = main(["identify", "train", "--data", data, "--out", str(out), *extra])
    return rc, out


def test_train_table2_reaches_goal(tmp_path, capsys):
    rc, model = _train(
        tmp_path, "--inputs", "lat_error_deg", "--target", "drift_dph", "--spread", "2",
        "--goal", repr(GOAL), "--curve", str(tmp_path / "curve.csv"),
    )
    assert rc == 0
    assert "goal 9e-08 reached" in capsys.readouterr().out
    net = RBFNetwork.load(model)
    assert net.input_names == ("lat_error_deg",)
    assert net.target_name == "drift_dph"
    assert net.metadata["local_lat_deg"] == 28.222
    assert net.settings.spread == 2.0
    assert net.training_curve_[-1] <= GOAL < net.training_curve_[0]
    table = read_table(HOT)
    residual = net.predict(table["lat_error_deg"]) - table["drift_dph"]
    assert np.sqrt(np.mean(residual**2)) <= 0.0003
    curve = read_table(tmp_path / "curve.csv")
    assert_allclose(curve["mse"], net.training_curve_, rtol=1e-15)
    assert DEFAULT_GOAL == pytest.approx(GOAL)


def test_hot_network_reproduces_papers_hot_rbf_column(tmp_path, capsys):
    """Table 4's last column is what the paper's hot-start RBF said for the cold samples."""
    rc, model = _train(tmp_path, "--spread", "2")
    assert rc == 0
    out = tmp_path / "pred.csv"
    assert main(["identify", "predict", "--model", str(model), "--data", COLD, "--out", str(out)]) == 0
    pred = read_table(out)
    assert np.abs(pred["drift_dph_pred"] - pred["hot_rbf_drift_dph"]).max() < 0.0005
    assert "error vs 'drift_dph'" in capsys.readouterr().out


def test_latitude_reading_converted_to_error(tmp_path):
    table = read_table(HOT)
    readings = tmp_path / "readings.csv"
    write_table(readings, {"lat_deg": table["lat_deg"], "drift_dph": table["drift_dph"]})
    rc_a, a = _train(tmp_path, "--spread", "1", "--goal", "0", "--max-neurons", "4", name="a.json")
    rc_b, b = _train(tmp_path, "--spread", "1", "--goal", "0", "--max-neurons", "4",
                     data=str(readings), name="b.json")
    assert rc_a == rc_b == 0
    net_a, net_b = RBFNetwork.load(a), RBFNetwork.load(b)
    assert net_b.input_names == ("lat_error_deg",)
    x = table["lat_error_deg"]
    assert_allclose(net_b.predict(x), net_a.predict(x), rtol=1e-9, atol=1e-12)
    # predict converts readings too, with the site latitude stored in the model
    out = tmp_path / "p.csv"
    assert main(["identify", "predict", "--model", str(a), "--data", str(readings), "--out", str(out)]) == 0
    assert_allclose(read_table(out)["drift_dph_pred"], net_a.predict(x), rtol=1e-9, atol=1e-12)
    # another site latitude shifts the errors (within the training range; 28.3 deg would leave it)
    assert main(["identify", "predict", "--model", str(a), "--data", str(readings),
                 "--local-lat-deg", "28.225", "--out", str(out)]) == 0
    assert_allclose(read_table(out)["drift_dph_pred"], net_a.predict(table["lat_deg"] - 28.225), rtol=1e-9)
    assert main(["identify", "predict", "--model", str(a), "--data", str(readings), "--local-lat-deg", "28.3"]) == 2


def test_cold_start_inputs_and_name_check(tmp_path, capsys):
    rc, cold = _train(tmp_path, "--inputs", "lat_error_deg,temp_c,temp_change_c", data=COLD, name="cold.json")
    assert rc == 0
    assert RBFNetwork.load(cold).input_names == ("lat_error_deg", "temp_c", "temp_change_c")
    capsys.readouterr()
    # a table without the temperature-change input is refused with its name
    no_change = tmp_path / "no_change.csv"
    t = read_table(HOT)
    write_table(no_change, {"lat_deg": t["lat_deg"], "temp_c": t["temp_c"]})
    rc = main(["identify", "predict", "--model", str(cold), "--data", str(no_change)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1
    assert "no column 'temp_change_c'" in err


def test_predict_to_stdout(tmp_path, capsys):
    _, model = _train(tmp_path)
    capsys.readouterr()
    assert main(["identify", "predict", "--model", str(model), "--data", HOT]) == 0
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert lines[0].endswith(",drift_dph_pred")
    assert len(lines) == 17
    assert "predicted drift_dph for 16 rows" in captured.err


def test_register_in_a_host_parser(tmp_path):
    parser = argparse.ArgumentParser(prog="sarins")
    sub = parser.add_subparsers(dest="command", required=True)
    register(sub)
    args = parser.parse_args(["identify", "train", "--data", HOT, "--out", str(tmp_path / "m.json")])
    assert args.func(args) == 0
    with pytest.raises(SystemExit):
        parser.parse_args(["identify"])


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "no such file"),
        ("", "empty file"),
        ("lat_error_deg,drift_dph\n0.001,abc\n0.002,0.1\n", "line 2: 'abc' is not a number"),
        ("lat_error_deg,drift_dph\n0.001,0.1\n0.002\n", "line 3 has 1 fields"),
        ("lat_error_deg,drift_dph\n0.001,nan\n0.002,0.1\n", "not finite"),
        ("temp_c,drift_dph\n1,0.1\n2,0.2\n", "no column 'lat_error_deg'"),
        ("lat_error_deg,drift_dph\n0.001,0.1\n", "at least 2"),
        ("\x00\x01binary,\xff\n", "error"),
    ],
)
def test_bad_training_csv_one_line_error(tmp_path, capsys, content, message):
    path = tmp_path / "bad.csv"
    if content is not None:
        path.write_text(content, encoding="latin-1")
    rc, model = _train(tmp_path, data=str(path))
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("sarins identify train: error:")
    assert err.count("\n") == 1
    assert message in err
    assert not model.exists()


def test_bad_model_file_one_line_error(tmp_path, capsys):
    bad = tmp_path / "model.json"
    bad.write_text('{"format": "sarins_fmu.identify.rbf", "version": 1}')
    rc = main(["identify", "predict", "--model", str(bad), "--data", HOT])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("sarins identify predict: error: model file")
    assert "model.json" in err and err.count("\n") == 1


def test_bad_options(tmp_path, capsys):
    rc, _ = _train(tmp_path, "--spread", "-1")
    assert rc == 2 and "spread" in capsys.readouterr().err
    rc, _ = _train(tmp_path, "--inputs", "lat_error_deg,,temp_c")
    assert rc == 2 and "--inputs" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["1e308", "-1e308", "0.1", "-0.06"])
def test_predict_refuses_inputs_outside_the_training_range(tmp_path, capsys, value):
    """Table 2's latitude errors span +-0.0254 deg: a row far beyond (or simply 2-4 times beyond) is
    refused with exit 2 naming the CSV line, not answered with an extrapolated drift (issue 21)."""
    rc, model = _train(tmp_path, "--spread", "1", "--goal", "0", "--max-neurons", "4")
    assert rc == 0
    lo, hi = RBFNetwork.load(model).input_range_[:, 0]
    assert (lo, hi) == (-0.0254, 0.0254)  # the training column's least and largest value, stored
    data = tmp_path / "far.csv"
    data.write_text(f"lat_error_deg\n0.01\n{value}\n")
    capsys.readouterr()
    assert main(["identify", "predict", "--model", str(model), "--data", str(data)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sarins identify predict: error: ")
    assert f"{data}: line 3: lat_error_deg" in err[0] and "outside the range the model" in err[0], err[0]
    # just inside the widened range: answered
    data.write_text("lat_error_deg\n0.0254\n-0.0279\n")
    assert main(["identify", "predict", "--model", str(model), "--data", str(data)]) == 0


def test_model_without_a_stored_range_is_bounded_from_its_scaling(tmp_path, capsys):
    """A model file written before the range was stored (the shipped hot model with its range taken out)
    loads, and its range is bounded by Samuelson's inequality (mean +- std sqrt(n - 1)), which contains
    every training input: here the exact range the shipped file stores."""
    import json

    from sarins_fmu.identify.axial import default_model_path

    shipped = RBFNetwork.load(default_model_path("hot"))
    assert shipped.input_range_exact_
    doc = json.loads(default_model_path("hot").read_text())
    for key in ("input_min", "input_max"):
        del doc["arrays"][key]
    old = tmp_path / "old_hot.json"
    old.write_text(json.dumps(doc))
    net = RBFNetwork.load(old)
    assert not net.input_range_exact_
    lo, hi = net.input_range_[:, 0]
    exact_lo, exact_hi = shipped.input_range_[:, 0]
    mean, scale = doc["arrays"]["scaling_mean"]["data"][0], doc["arrays"]["scaling_scale"]["data"][0]
    half = scale * math.sqrt(doc["meta"]["metadata"]["n_samples"] - 1)
    assert (lo, hi) == pytest.approx((mean - half, mean + half), rel=1e-12)
    assert lo <= exact_lo < exact_hi <= hi
    data = tmp_path / "far.csv"
    data.write_text("lat_error_deg\n0.01\n1e308\n")
    assert main(["identify", "predict", "--model", str(old), "--data", str(data)]) == 2
    assert "line 3: lat_error_deg = 1e+308 is outside the range" in capsys.readouterr().err


def test_train_writes_the_binary_model_the_fmu_reads(tmp_path):
    from sarins_fmu.core import nets
    from sarins_fmu.identify.axial import DriftIdentifier

    fmu_model = tmp_path / "hot.bin"
    rc, model = _train(tmp_path, "--spread", "2", "--fmu-model", str(fmu_model))
    assert rc == 0
    assert fmu_model.read_bytes() == DriftIdentifier(model).binary()
    assert nets.AxialModel(fmu_model.read_bytes()).drift_dph(1e-5, 20.0, 0.0) == DriftIdentifier(model).drift_dph(1e-5)
    rc, _ = _train(tmp_path, "--spread", "2", "--fmu-model", str(tmp_path / "missing" / "x.bin"), name="h2.json")
    assert rc == 2
