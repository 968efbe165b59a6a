"""Every option is honoured or refused (issue 21): an option that does not
apply in a combination is refused with exit 2 and one line naming it, before
any work, instead of being ignored without a word."""

import pytest

from sarins.cli import build_parser, given, main
from sarins_fmu.identify.axial import default_model_path

IGNORED = [
    # (argv, option the message must name)
    (["allan", "--write-preset", "{tmp}/unit.json"], "--write-preset"),  # a fitted preset needs --log
    (["allan", "--axes", "frd"], "--axes"),
    (["replay", "{log}", "--seed", "3"], "--seed"),  # the seed of the --imu comparison
    (["allan", "--log", "{log}", "--hours", "2"], "--hours"),
    (["allan", "--log", "{log}", "--imu", "nav-rlg"], "--imu"),
    (["allan", "--log", "{log}", "--seed", "4"], "--seed"),
    (["navigate", "--correction-from-hours", "0.005"], "--correction-from-hours"),
    (["demo", "--model", "cold", "--model-file", "{model}"], "--model"),
    (["identify", "predict", "--model", "{model}", "--data", "{csv}", "--local-lat-deg", "30"], "--local-lat-deg"),
    (["campaign", "online-rls", "--out", "{tmp}/c", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
     "--workers"),
    (["campaign", "axial-rbf", "--out", "{tmp}/c", "--sweep", "quick", "--sweep-only", "--engine", "cosim"],
     "--engine"),
    (["campaign", "axial-rbf", "--out", "{tmp}/c", "--sweep", "quick", "--sweep-only", "--no-live"], "--no-live"),
    (["campaign", "axial-rbf", "--out", "{tmp}/c", "--sweep", "quick", "--sweep-only", "--calibrate"],
     "--calibrate"),
    (["campaign", "mems-calibration", "--out", "{tmp}/c", "--ablation-models", "rbf"], "--ablation-models"),
    (["campaign", "mems-calibration", "--out", "{tmp}/c", "--models", "traditional", "--rnn-steps", "5"],
     "--rnn-steps"),
    (["campaign", "mems-calibration", "--out", "{tmp}/c", "--models", "traditional,rbf", "--grnn-patterns", "5"],
     "--grnn-patterns"),
    (["campaign", "mems-calibration", "--out", "{tmp}/c", "--models", "grnn", "--rbf-samples", "5"],
     "--rbf-samples"),
    (["campaign", "mems-calibration", "--out", "{tmp}/c", "--models", "traditional,grnn", "--device", "cpu"],
     "--device"),
    (["build-fmus", "--out", "{tmp}/fmus", "--only", "IMUCompensator"], "--only IMUCompensator"),
]


@pytest.fixture
def paths(tmp_path):
    csv = tmp_path / "x.csv"
    csv.write_text("lat_error_deg,drift_dph\n0.01,0.001\n0.02,0.002\n")
    log = tmp_path / "log.csv"  # never read: the refusal comes first
    log.write_text("")
    return {"tmp": str(tmp_path), "csv": str(csv), "log": str(log), "model": str(default_model_path("hot"))}


@pytest.mark.parametrize("argv,option", IGNORED, ids=[" ".join(a[:3]) + " " + o for a, o in IGNORED])
def test_an_option_that_does_not_apply_is_refused(argv, option, paths, capsys):
    argv = [a.format(**paths) for a in argv]
    try:
        rc = main(argv)
    except SystemExit as exc:
        rc = exc.code
    out, err = capsys.readouterr()
    assert rc == 2, (rc, out, err)
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    command = " ".join(argv[:2]) if argv[0] in ("campaign", "identify") else argv[0]
    assert lines[0].startswith(f"sarins {command}: error: "), lines[0]
    assert option in lines[0], lines[0]


def test_given_lists_only_options_written_on_the_command_line():
    parser = build_parser()
    args = parser.parse_args(["campaign", "mems-calibration", "--workers=2", "--rnn-steps", "5", "--no-progress"])
    assert given(args, "workers", "rnn_steps", "no_progress", "seed", "profile", "grnn_patterns") == [
        "workers", "rnn_steps", "no_progress"]
    assert given(parser.parse_args(["allan"]), "rate_hz", "log") == []
