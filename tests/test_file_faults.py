"""Files the toolkit must not trust or must not block on (issue 21, files).

SSP component sources confined to the archive or system folder; size
budgets for every reader; outputs that are not regular files; corrupted NPZ
logs; schedule options out of range; SSD schema and connector types; an
interrupted co-simulation keeps its rows; a full disk names the file.
Subprocesses are used wherever the old behaviour was a hang or a huge
allocation (each with a timeout, and an address-space limit where memory
is at stake).
"""
from __future__ import annotations

import csv
import errno
import os
import pathlib
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from file_faults import (fifo, good_log, many_variables, npy_header, npz_bomb, rewrite_fmu, same_value_reference,
                         sparse_file, ssd_text, system_folder)
from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from hooks import command as hook_command
from hooks import signal_after_steps
from orchestration import Master, SystemFileError, read_system, write_ssp
from orchestration.errors import IncompatibleConnectionError
from sarins.cli import main

pytestmark = pytest.mark.integration

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT = 120  # s per subprocess: a case that blocks (a FIFO opened, a bomb inflated) fails here
MEMORY_LIMIT = 3 * 2**30  # address space of a subprocess fed a bomb: inflating it fails, not the machine


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def cli(*args, env: dict | None = None, limit_memory: bool = False, hooks: tuple = ()) -> subprocess.CompletedProcess:
    """``python -m sarins ARGS`` with this checkout first on the path (through ``tests/hooks.py``
    when ``hooks`` names test hooks to install)."""
    start = [*hook_command(*hooks), "-m"] if hooks else [sys.executable, "-m"]
    return subprocess.run([*start, "sarins", *map(str, args)], capture_output=True, text=True,
                          timeout=TIMEOUT, env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})},
                          preexec_fn=_limit_memory if limit_memory else None)


def run_main(argv) -> int:
    """``sarins.cli.main`` with argparse's exit (bad option values) returned as a status."""
    try:
        return main([str(a) for a in argv])
    except SystemExit as stop:
        return stop.code


def one_clean_line(text: str) -> str:
    lines = [line for line in text.splitlines() if line.strip()]
    assert len(lines) == 1, text
    assert "Traceback" not in text and "internal error" not in text, text
    return lines[0]


# ------------------------------------------------------------------ 1. sources confined
@pytest.fixture()
def outside(tmp_path):
    """An FMU path outside the system folder that blocks whoever opens it."""
    return fifo(tmp_path / "outside" / "Turntable.fmu")


def _escaping_sources(folder: Path, outside: Path) -> dict[str, str]:
    link = folder / "link.fmu"
    link.symlink_to(outside)
    folder_link = folder / "elsewhere"
    folder_link.symlink_to(outside.parent, target_is_directory=True)
    return {"dot-dot": "../outside/Turntable.fmu",
            "deep dot-dot": "sub/../" + "../" * 12 + str(outside).lstrip("/"),
            "absolute": str(outside),
            "file URI": outside.as_uri(),
            "file URI with host": "file://otherhost" + str(Path(folder) / "Ramp.fmu"),
            "http URI": "http://example.org/Ramp.fmu",
            "symlink to a file": "link.fmu",
            "symlink to a folder": "elsewhere/Turntable.fmu",
            "etc passwd": "/etc/passwd",
            "empty": ""}


@pytest.mark.parametrize("case", ["dot-dot", "deep dot-dot", "absolute", "file URI", "file URI with host",
                                  "http URI", "symlink to a file", "symlink to a folder", "etc passwd", "empty"])
def test_a_source_outside_the_system_folder_is_refused_naming_the_component(case, fixture_fmus, tmp_path,
                                                                            outside):
    folder = tmp_path / "system"
    system_folder(folder, fixture_fmus)
    source = _escaping_sources(folder, outside)[case]
    (folder / "SystemStructure.ssd").write_text(ssd_text(ramp=source))
    with pytest.raises(SystemFileError, match="component 'ramp'.*source") as caught:
        read_system(folder)  # read_system opens no FMU: the refusal comes before any open
    assert "\n" not in str(caught.value)


def test_sources_inside_the_folder_still_load(fixture_fmus, tmp_path):
    folder = tmp_path / "my system"
    system_folder(folder, fixture_fmus)
    (folder / "sub dir").mkdir()
    (folder / "Ramp.fmu").rename(folder / "sub dir" / "Ramp.fmu")
    for source in ("sub%20dir/Ramp.fmu", "sub dir/../sub dir/Ramp.fmu", (folder / "sub dir" / "Ramp.fmu").as_uri(),
                   str(folder / "sub dir" / "Ramp.fmu")):
        (folder / "SystemStructure.ssd").write_text(ssd_text(ramp=source))
        system = read_system(folder)
        assert system.fmu_path(system.component("ramp")) == (folder / "sub dir" / "Ramp.fmu").resolve()
    with Master(folder) as master:
        assert len(master.simulate(1.0, 0.5)) == 3


@pytest.mark.parametrize("source", ["../../outside/Turntable.fmu", "ABSOLUTE"])
def test_cosim_refuses_an_escaping_source_in_an_ssp_before_opening_it(source, ramp_gain, tmp_path, outside):
    """The FIFO outside would block ``sarins cosim`` for ever if anything opened it."""
    import zipfile

    archive = write_ssp(ramp_gain, tmp_path / "evil.ssp")
    with zipfile.ZipFile(archive) as old:
        ssd = old.read("SystemStructure.ssd").decode()
        members = {n: old.read(n) for n in old.namelist() if n != "SystemStructure.ssd"}
    source = str(outside) if source == "ABSOLUTE" else source
    with zipfile.ZipFile(archive, "w") as new:
        new.writestr("SystemStructure.ssd", ssd.replace('source="resources/Ramp.fmu"', f'source="{source}"'))
        for name, data in members.items():
            new.writestr(name, data)
    scratch = tmp_path / "scratch"  # the archive is extracted into scratch/<folder>: "../../outside" is the FIFO
    scratch.mkdir()
    done = cli("cosim", archive, "--stop-time", "1", "--step", "0.5", "--no-progress", env={"TMPDIR": str(scratch)})
    assert done.returncode == 2, done.stderr
    line = one_clean_line(done.stderr)
    assert f"component 'ramp': source '{source}'" in line and "archive" in line


# ------------------------------------------------------------------ 2. size budgets
@pytest.mark.parametrize("command", [["allan", "--json", "--log"], ["replay"]])
def test_an_8_mb_npz_log_expanding_to_8_gib_is_refused_with_the_limit(command, tmp_path):
    bomb = npz_bomb(tmp_path / "bomb.npz", 8192)
    assert bomb.stat().st_size < 9 * 2**20
    done = cli(*command, bomb, limit_memory=True)
    assert done.returncode == 2, done.stderr
    line = one_clean_line(done.stderr)
    assert str(bomb) in line and "8 GiB" in line and "limit of 2 GiB" in line and "MAX_LOG_BYTES" in line


def test_a_csv_log_over_the_budget_is_refused_before_it_is_read(tmp_path):
    from sarins_fmu.imu_log import MAX_LOG_BYTES

    big = sparse_file(tmp_path / "big.csv", MAX_LOG_BYTES + 1, b"# sarins-imu-log 1\n# lat_deg: 28\n")
    done = cli("allan", "--log", big, "--json", limit_memory=True)
    assert done.returncode == 2, done.stderr
    assert "limit of 2 GiB" in one_clean_line(done.stderr)


def test_model_files_over_the_budget_are_refused(tmp_path, monkeypatch):
    from sarins_fmu.identify import modelfile

    path = modelfile.save_model_file(tmp_path / "m.npz", "tag", 1, {}, {"w": np.zeros(40_000)})
    assert modelfile.load_model_file(path, "tag", {1}, lambda meta, arrays: arrays["w"]).shape == (40_000,)
    monkeypatch.setattr(modelfile, "MAX_NPZ_BYTES", 100_000)
    with pytest.raises(modelfile.ModelFileError, match=r"m\.npz.*more than the limit of 97\.66 KiB.*MAX_NPZ_BYTES"):
        modelfile.load_model_file(path, "tag", {1}, lambda meta, arrays: arrays["w"])
    json_path = modelfile.save_model_file(tmp_path / "m.json", "tag", 1, {}, {"w": np.zeros(40_000)})
    monkeypatch.setattr(modelfile, "MAX_JSON_BYTES", 100_000)
    with pytest.raises(modelfile.ModelFileError, match=r"m\.json.*more than the limit.*MAX_JSON_BYTES"):
        modelfile.load_model_file(json_path, "tag", {1}, lambda meta, arrays: arrays["w"])


def test_a_stored_result_over_the_budget_is_not_reused(tmp_path, monkeypatch):
    from sarins import results

    path = tmp_path / "task.npz"
    record = {"task": "t"}
    results.save_result(path, {"series": np.zeros(40_000)}, record)
    assert results.load_valid(path, record)["series"].shape == (40_000,)
    monkeypatch.setattr(results, "MAX_RESULT_BYTES", 100_000)
    with pytest.raises(results.StoredResultError, match="more than the limit.*MAX_RESULT_BYTES"):
        results.load_valid(path, record)


def test_an_ssd_over_the_budget_and_an_fmu_description_bomb_are_refused(fixture_fmus, tmp_path):
    from orchestration.ssp_reader import MAX_XML_BYTES

    big = sparse_file(tmp_path / "big.ssd", MAX_XML_BYTES + 1, b"<?xml version='1.0'?>\n")
    with pytest.raises(SystemFileError, match="more than the limit.*MAX_XML_BYTES"):
        read_system(big)
    folder = tmp_path / "system"
    system_folder(folder, fixture_fmus)
    npz_bomb(folder / "Ramp.fmu", 600, member="modelDescription.xml")  # read before extraction until now
    with pytest.raises(SystemFileError, match=r"Ramp\.fmu.*component 'ramp'.*more than the limit of 536870912"):
        Master(folder)


# ------------------------------------------------------------------ 3. outputs that are not files
def test_navigate_write_log_to_a_fifo_exits_2_at_once(tmp_path):
    target = fifo(tmp_path / "fifo.csv")
    done = cli("navigate", "--align-hours", "0.2", "--nav-hours", "0.01", "--write-log", target)
    assert done.returncode == 2, done.stderr
    line = one_clean_line(done.stderr)
    assert "--write-log" in line and "FIFO" in line and str(target) in line


@pytest.mark.parametrize("kind", ["fifo", "folder", "missing folder"])
def test_cosim_output_that_is_not_a_regular_file_exits_2(kind, ramp_gain, tmp_path):
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    target = {"fifo": lambda: fifo(tmp_path / "out.csv"), "folder": lambda: tmp_path,
              "missing folder": lambda: tmp_path / "no" / "out.csv"}[kind]()
    done = cli("cosim", archive, "--stop-time", "1", "--step", "0.5", "--output", target, "--no-progress")
    assert done.returncode == 2, done.stderr
    assert "--output" in one_clean_line(done.stderr)


@pytest.mark.parametrize("command", ["allan --plot", "identify train --out", "identify train --curve",
                                     "identify predict --out"])
def test_other_outputs_refuse_a_fifo(command, tmp_path):
    target = fifo(tmp_path / "out")
    data = tmp_path / "data.csv"
    data.write_text("a,y\n" + "".join(f"{i},{2 * i}\n" for i in range(5)))
    model = tmp_path / "model.json"
    assert cli("identify", "train", "--data", data, "--inputs", "a", "--target", "y", "--out", model).returncode == 0
    argv = {"allan --plot": ["allan", "--hours", "0.5", "--plot", target],
            "identify train --out": ["identify", "train", "--data", data, "--inputs", "a", "--target", "y",
                                     "--out", target],
            "identify train --curve": ["identify", "train", "--data", data, "--inputs", "a", "--target", "y",
                                       "--out", tmp_path / "m2.json", "--curve", target],
            "identify predict --out": ["identify", "predict", "--model", model, "--data", data, "--out", target],
            }[command]
    done = cli(*argv)
    assert done.returncode == 2, done.stderr
    line = one_clean_line(done.stderr)
    assert command.split()[-1] in line and "FIFO" in line


@pytest.mark.parametrize("command", ["allan --plot", "cosim --output"])
def test_an_output_that_is_a_symlink_is_refused_and_the_file_it_points_to_kept(command, ramp_gain, tmp_path, capsys):
    outside = tmp_path / "elsewhere" / "precious.txt"
    outside.parent.mkdir()
    outside.write_text("keep me\n")
    link = tmp_path / "out" / ("allan.png" if command.startswith("allan") else "run.csv")
    link.parent.mkdir()
    link.symlink_to(outside)
    argv = (["allan", "--hours", "0.05", "--plot", link] if command.startswith("allan") else
            ["cosim", write_ssp(ramp_gain, tmp_path / "rg.ssp"), "--stop-time", "1", "--step", "0.5", "--output",
             link, "--no-progress"])
    assert run_main(argv) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert command.split()[-1] in line and "symbolic link" in line and str(link) in line
    assert outside.read_text() == "keep me\n" and link.is_symlink()


@pytest.mark.parametrize("fmi", ["2", "3"])
def test_build_fmus_refuses_to_write_through_a_symlinked_fmu(fmi, tmp_path, capsys):
    """Refused before anything is built: the link's target outside the folder is untouched."""
    outside = tmp_path / "elsewhere.fmu"
    outside.write_bytes(b"not yours")
    out = tmp_path / "d"
    out.mkdir()
    (out / "Turntable.fmu").symlink_to(outside)
    assert run_main(["build-fmus", "--out", out, "--fmi", fmi, "--only", "Turntable"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert "symbolic link" in line and str(out / "Turntable.fmu") in line
    assert outside.read_bytes() == b"not yours" and sorted(p.name for p in out.iterdir()) == ["Turntable.fmu"]


# ------------------------------------------------------------------ 4. corrupted NPZ logs
@pytest.mark.parametrize("damage", ["truncated", "corrupted", "not a zip", "empty"])
def test_a_truncated_or_corrupted_npz_log_exits_2_naming_the_file(damage, tmp_path, capsys):
    path = good_log(tmp_path / "log.npz")
    data = path.read_bytes()
    if damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "corrupted":
        middle = len(data) // 3
        path.write_bytes(data[:middle] + bytes(b ^ 0x5A for b in data[middle:middle + 64]) + data[middle + 64:])
    elif damage == "not a zip":
        path.write_bytes(b"garbage" * 100)
    else:
        path.write_bytes(b"")
    assert main(["allan", "--log", str(path), "--json"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert str(path) in line and "sarins allan: error:" in line


# ------------------------------------------------------------------ 5. schedule options
@pytest.mark.parametrize("options, named", [
    (["--stop-time", "inf", "--step", "0.5"], "--stop-time"),
    (["--stop-time", "nan", "--step", "0.5"], "--stop-time"),
    (["--stop-time", "1e300", "--step", "0.5"], "--stop-time 1e+300, --step 0.5"),
    (["--stop-time", "1", "--step", "1e-300"], "--stop-time 1, --step 1e-300"),
])
def test_cosim_schedule_options_out_of_range_exit_2_naming_the_option(options, named, ramp_gain, tmp_path, capsys):
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    assert run_main(["cosim", archive, *options, "--no-progress"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert named in line, line
    if "1e" in named:
        assert "MAX_STEPS" in line


def test_a_recording_over_its_budget_is_refused_naming_the_options(ramp_gain, tmp_path, capsys, monkeypatch):
    from orchestration import master

    monkeypatch.setattr(master, "MAX_RECORD_BYTES", 2**20)
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    assert main(["cosim", str(archive), "--stop-time", "100000", "--step", "0.001", "--output-every", "2",
                 "--no-progress"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert "--stop-time 100000, --step 0.001, --output-every 2:" in line and "MAX_RECORD_BYTES" in line


# ------------------------------------------------------------------ 6. SSD schema, connector types
def test_an_ssd_failing_the_schema_is_one_line(fixture_fmus, tmp_path, capsys):
    folder = tmp_path / "system"
    system_folder(folder, fixture_fmus, ramp_connectors='<ssd:Connectors><ssd:Connector name="y" kind="sideways"/>'
                  '</ssd:Connectors>', ramp_extra="<ssd:Bogus/>")
    assert main(["cosim", str(folder), "--stop-time", "1", "--step", "0.5"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert "not valid SSP 1.0: ERROR (line" in line and "sideways" in line and "(and 1 more schema error)" in line


@pytest.mark.parametrize("declared", ["String", "Integer", "Boolean"])
def test_a_connector_declared_with_another_type_than_the_fmu_is_refused(declared, fixture_fmus, tmp_path, capsys):
    folder = tmp_path / "system"
    connectors = (f'<ssd:Connectors><ssd:Connector name="y" kind="output"><ssc:{declared}/></ssd:Connector>'
                  '</ssd:Connectors>')
    system_folder(folder, fixture_fmus, ramp_connectors=connectors)
    with pytest.raises(IncompatibleConnectionError,
                       match=f"component 'ramp', variable 'y': connector 'y' is declared {declared} in the "
                             "system file, but the FMU's variable is Real"):
        Master(folder)
    assert main(["cosim", str(folder), "--stop-time", "1", "--step", "0.5"]) == 2
    one_clean_line(capsys.readouterr().err)
    system_folder(folder, fixture_fmus, ramp_connectors=connectors.replace(declared, "Real"))
    Master(folder).close()  # the right type passes


# ------------------------------------------------------------------ 7. interrupted co-simulation
@pytest.mark.parametrize("signame, code", [("SIGINT", 130), ("SIGTERM", 143)])
def test_an_interrupted_cosim_writes_the_rows_so_far_and_says_so(signame, code, ramp_gain, tmp_path):
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    out = tmp_path / "out.csv"
    done = cli("cosim", archive, "--stop-time", "100", "--step", "0.5", "--output", out, "--no-progress",
               hooks=("--signal-after", f"5:{signame}"))
    assert done.returncode == code, done.stderr
    line = one_clean_line(done.stderr)
    # the signal is sent after step 5 and acted on after step 6 (recorded): t = 3 s
    assert f"stopped by {signame}: interrupted at t = 3 s" in line and str(out) in line
    lines = out.read_text().splitlines()
    assert lines[-1] == f"# interrupted by {signame} at t = 3 s: the rows above are the run up to t = 3 s"
    rows = list(csv.reader(lines[:-1]))
    assert rows[0][0] == "time" and [float(r[0]) for r in rows[1:]] == [0.5 * k for k in range(7)]
    assert Path(str(out) + ".units.json").is_file()
    assert signal.Signals[signame]  # the names the hook takes


# ------------------------------------------------------------------ 8. a full disk names the file
def _full_disk_open(suffix: str):
    """``Path.open`` that sends writes of files ending in ``suffix`` to /dev/full (ENOSPC)."""
    real = pathlib.Path.open

    def fake(self, mode="r", *args, **kwargs):
        if "w" in mode and self.name.endswith(suffix):
            return real(pathlib.Path("/dev/full"), mode, *args, **kwargs)
        return real(self, mode, *args, **kwargs)

    return fake


def test_cosim_on_a_full_disk_exits_1_naming_the_file(ramp_gain, tmp_path, capsys, monkeypatch):
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    out = tmp_path / "out.csv"
    monkeypatch.setattr(pathlib.Path, "open", _full_disk_open(".csv"))
    assert main(["cosim", str(archive), "--stop-time", "1", "--step", "0.5", "--output", str(out),
                 "--no-progress"]) == 1
    err = capsys.readouterr().err
    line = one_clean_line(err)
    assert "sarins cosim: failed:" in line and "No space left on device" in line and str(out) in line
    assert not out.exists() and list(tmp_path.glob(".out.csv*")) == []


def test_navigate_write_log_on_a_full_disk_exits_1_naming_the_file(tmp_path, capsys, monkeypatch):
    from sarins_fmu import imu_log

    out = tmp_path / "run.csv"
    monkeypatch.setattr(imu_log, "open", lambda path, mode="r", *a, **k: open("/dev/full", mode, *a, **k),
                        raising=False)
    assert main(["navigate", "--align-hours", "0.2", "--nav-hours", "0.01", "--write-log", str(out)]) == 1
    line = one_clean_line(capsys.readouterr().err)
    assert "No space left on device" in line and str(out) in line


def test_campaign_writes_name_the_file_when_the_disk_is_full(tmp_path):
    from sarins.results import atomic_output

    target = tmp_path / "result.npz"
    with pytest.raises(OSError) as caught:
        with atomic_output(target):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # as write() raises it: no file name
    assert caught.value.errno == errno.ENOSPC and caught.value.filename == str(target)
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_cosim_on_a_full_disk_keeps_its_status_and_says_what_was_lost(ramp_gain, tmp_path, capsys,
                                                                                   monkeypatch):
    archive = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    out = tmp_path / "out.csv"
    monkeypatch.setattr(pathlib.Path, "open", _full_disk_open(".csv"))
    signal_after_steps(5, "SIGTERM", setattr_=monkeypatch.setattr)
    assert main(["cosim", str(archive), "--stop-time", "100", "--step", "0.5", "--output", str(out),
                 "--no-progress"]) == 143
    line = one_clean_line(capsys.readouterr().err)
    assert "interrupted at t = 3 s; the 7 rows recorded so far could not be written" in line and str(out) in line


# ------------------------------------------------------------------ 9. FMU files that do not fit together
def _system_with_ramp(fixture_fmus, tmp_path, **rewrite) -> Path:
    folder = tmp_path / "system"
    system_folder(folder, fixture_fmus)
    rewrite_fmu(Path(fixture_fmus["Ramp"]), folder / "Ramp.fmu", **rewrite)
    return folder


def test_a_truncated_shared_library_is_refused_before_it_is_loaded(fixture_fmus, tmp_path):
    """dlopen maps a truncated ELF file's segments all the same; the first access past the end is SIGBUS."""
    folder = _system_with_ramp(fixture_fmus, tmp_path, library=lambda data: data[:len(data) // 2])
    done = cli("cosim", folder, "--stop-time", "1", "--step", "0.5", "--no-progress")
    assert done.returncode == 2, (done.returncode, done.stderr)
    line = one_clean_line(done.stderr)
    assert "component 'ramp'" in line and "binaries/linux64/Ramp.so cannot be loaded: truncated" in line


def test_a_description_with_a_million_variables_is_refused_by_its_budget(fixture_fmus, tmp_path, capsys):
    folder = _system_with_ramp(fixture_fmus, tmp_path, description=many_variables(10**6))
    assert run_main(["cosim", folder, "--stop-time", "1", "--step", "0.5", "--no-progress"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert "component 'ramp'" in line and "modelDescription.xml" in line and "limit" in line


def test_two_parameters_sharing_a_value_reference_are_refused(fixture_fmus, tmp_path, capsys):
    folder = _system_with_ramp(fixture_fmus, tmp_path, description=same_value_reference("slope", "offset"))
    assert run_main(["cosim", folder, "--stop-time", "1", "--step", "0.5", "--no-progress"]) == 2
    line = one_clean_line(capsys.readouterr().err)
    assert "valueReference 0 is shared by 2 Real parameters or inputs ('slope', 'offset')" in line


def test_a_description_of_another_build_exits_2_with_the_fmus_reason(fmu_dir, tmp_path):
    """A changed GUID: the native FMU refuses fmi2Instantiate; a bad file (2), not a failed run (1)."""
    import re

    from orchestration import Component, System

    def other_guid(text: str) -> str:  # one hex digit of the GUID changed
        return re.sub(r'(guid="\{?)([0-9a-f])', lambda m: m.group(1) + ("1" if m.group(2) == "0" else "0"), text,
                      count=1)

    fmu = rewrite_fmu(fmu_dir / "Turntable.fmu", tmp_path / "Turntable.fmu", description=other_guid)
    archive = write_ssp(System("t", [Component("table", fmu_dir / "Turntable.fmu", {})], []), tmp_path / "t.ssp")
    swapped = tmp_path / "swapped.ssp"
    import zipfile
    with zipfile.ZipFile(archive) as zin, zipfile.ZipFile(swapped, "w") as zout:
        for item in zin.infolist():
            zout.writestr(item, fmu.read_bytes() if item.filename.endswith(".fmu") else zin.read(item.filename))
    done = cli("cosim", swapped, "--stop-time", "2", "--step", "0.01", "--no-progress")
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("sarins cosim: error: ") and "fmi2Instantiate" in done.stderr
    assert "GUID" in done.stderr and "Traceback" not in done.stderr


def test_an_npy_header_claiming_7e9_values_is_refused_not_allocated(tmp_path):
    path = tmp_path / "liar.npz"
    import zipfile
    with zipfile.ZipFile(path, "w") as archive:
        for name in ("time_s.npy", "dtheta_x.npy"):
            archive.writestr(name, npy_header(7_000_000_000 * 8) + bytes(80))
    done = cli("allan", "--json", "--log", path, limit_memory=True)
    assert done.returncode == 2, done.stderr
    line = one_clean_line(done.stderr)
    assert str(path) in line and "header claims shape (7000000000,)" in line and "refused" in line


def test_a_stored_campaign_result_that_is_a_folder_is_named(tmp_path):
    from campaign_tasks import square
    from sarins.campaign import StoredResultError, Task, run_campaign

    (tmp_path / "out" / "sq1.npz").mkdir(parents=True)
    tasks = [Task(f"sq{x}", square, {"x": x, "marker_dir": str(tmp_path), "delay": 0.0},
                  volatile=("marker_dir", "delay")) for x in range(3)]
    with pytest.raises(StoredResultError, match=r"sq1.npz: the stored result of task sq1 is a folder"):
        run_campaign(tasks, tmp_path / "out", workers=1, progress=False)
    assert (tmp_path / "out" / "sq1.npz").is_dir()
