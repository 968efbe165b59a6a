"""The main job (``sarins demo``): seed 000's identified static system, co-simulated.

Turntable -> IMUThermal -> StrapdownINS -> RBFIdentifier FMUs under the
generic master: align, navigate ``identify_hours``, identify the axial drift
with the shipped RBF model, subtract it and navigate ``nav_hours`` more.  The
same run is repeated in process without compensation for comparison, and the
true drift (deterministic z-gyro drift of the simulated unit, time mean over
the navigation after identification) is computed from the recorded gyro
temperature.
"""

from __future__ import annotations

import csv
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fmus.build import build_fmus
from orchestration import simulate_system
from sarins.systems import IDENTIFIED_STATIC_FMUS, standard_static_identified
from sarins_fmu import imu as imu_mod
from sarins_fmu.experiments import run_static
from sarins_fmu.identify.axial import default_model_path
from sarins_fmu.site import SITE_LAT_DEG
from sarins_fmu.units import DEG_TO_RAD, DPH_TO_RPS, HOUR, NM


#: navigation time (h) at which the shipped identifier models were trained
MODEL_IDENTIFY_HOURS = 12.0


def demo_parameters(*, lat_deg: float, align_hours: float, imu: str, start: str, rotation: str, seed: int,
                    axial_drift_dph: float | None = None) -> dict:
    """FMU start values of the standard system for the run options (SI)."""
    lat = lat_deg * DEG_TO_RAD
    align = align_hours * HOUR
    imu_start = {"preset": imu, "lat": lat, "thermal_start": start, "seed": seed}
    if axial_drift_dph is not None:  # a constant azimuth drift, no thermal terms (ImuModel.with_axial_drift)
        imu_start.update({"axial_drift_a": 0.0, "axial_drift_b": 0.0, "axial_drift_c": axial_drift_dph * DPH_TO_RPS,
                          "axial_drift_dtdt": 0.0, "gyro_bias_z": 0.0, "gyro_bias_tc1_z": 0.0,
                          "gyro_bias_tc2_z": 0.0, "aging_sigma_a": 0.0, "aging_sigma_b": 0.0,
                          "aging_sigma_c": 0.0})
    return {"turntable": {"scheme": rotation, "align_time": align},
            "imu": imu_start, "ins": {"lat0": lat, "align_time": align}}


def true_axial_drift_dph(model: imu_mod.ImuModel, time_s: np.ndarray, temp_gyro_z: np.ndarray,
                         start_s: float, end_s: float) -> float:
    """Time mean (deg/h) of the unit's deterministic z-gyro drift over
    ``[start_s, end_s]`` (run time), from a recorded gyro temperature."""
    dt = float(time_s[1] - time_s[0])
    eps = imu_mod.deterministic_axial_drift(model, temp_gyro_z, dt)
    sel = (time_s >= start_s) & (time_s <= end_s)
    return float(np.mean(eps[sel])) / DPH_TO_RPS


class Phases:
    """The demo's phases announced on ``stream`` (stderr), each with its duration when it ends, and a
    progress indication for the two long ones.

    The estimate of the time left uses only the steps done since the first step and the wall time
    since then (the set-up before the first step, FMU loading and kernel compilation, is a phase of
    its own), so it is right from its first update.  On a terminal one line is rewritten about twice a
    second; otherwise a line is written every 10 %.  ``clock``: seconds, monotonic (tests pass their own).
    """

    def __init__(self, stream=None, *, enabled: bool = True, clock=time.monotonic):
        self.stream = sys.stderr if stream is None else stream
        self.enabled, self.clock = enabled, clock
        self.name, self.t_phase = None, None
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def _write(self, text: str, end: str = "\n") -> None:
        if self.enabled:
            self.stream.write(text + end)
            self.stream.flush()

    def start(self, name: str, detail: str = "") -> None:
        """End the current phase (its duration) and announce ``name``."""
        self.end()
        self.name, self.t_phase = name, self.clock()
        self._write(f"sarins demo: {name}{': ' + detail if detail else ''} ...")

    def end(self) -> None:
        if self.name is not None:
            self._write(f"sarins demo: {self.name}: done in {self.clock() - self.t_phase:.1f} s")
        self.name = None

    def progress(self, total: int, unit: str = "steps") -> "Progress":
        return Progress(self, total, unit)


class Progress:
    """Steps done out of ``total``, with the time left from the rate since the first step."""

    def __init__(self, phases: Phases, total: int, unit: str):
        self.phases, self.total, self.unit = phases, int(total), unit
        self.first = None  # (steps, wall time) at the first update
        self.last_shown, self.next_share = None, 0.1

    def estimate(self, done: int, now: float) -> float | None:
        """Seconds left: (total - done) / rate, the rate since the first update; None before a rate exists."""
        if self.first is None or done <= self.first[0] or now <= self.first[1]:
            return None
        rate = (done - self.first[0]) / (now - self.first[1])
        return (self.total - done) / rate

    def update(self, done: int) -> None:
        now = self.phases.clock()
        if self.first is None:
            self.first = (done, now)
            return
        if done >= self.total:
            return
        share = done / self.total
        if self.phases.tty:
            if self.last_shown is not None and now - self.last_shown < 0.5:
                return
            end = "\r"
        else:
            if share < self.next_share:
                return
            self.next_share = (int(share * 10) + 1) / 10.0
            end = "\n"
        self.last_shown = now
        left = self.estimate(done, now)
        text = f"  {share * 100:5.1f} % ({done}/{self.total} {self.unit})"
        if left is not None:
            text += f", about {_duration(left)} left"
        self.phases._write(text, end=end)

    def close(self) -> None:
        if self.phases.tty and self.last_shown is not None:
            self.phases._write("")


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def run_demo(*, lat_deg: float = SITE_LAT_DEG, align_hours: float = 4.0, identify_hours: float = MODEL_IDENTIFY_HOURS,
             nav_hours: float = 72.0, imu: str = "nav-rlg", rotation: str = "forward-reverse", start: str = "hot",
             seed: int = 0, axial_drift_dph: float | None = None, model: str = "hot",
             model_file: str | None = None, fmu_dir="build/fmus", progress: bool = True,
             phases: Phases | None = None) -> dict:
    """Co-simulate the identified static system and compare; returns a dict
    (SI units unless the key says otherwise) with the recorded series under
    ``"cosim"`` and the in-process reference under ``"reference"``.  ``phases``
    (default: on stderr, silent with ``progress=False``) announces each phase."""
    phases = Phases(enabled=progress) if phases is None else phases
    if model_file is None and abs(identify_hours - MODEL_IDENTIFY_HOURS) > 1e-9:
        raise ValueError(f"the shipped {model} model was trained on the latitude error at "
                         f"{MODEL_IDENTIFY_HOURS:g} h of navigation; --identify-hours {identify_hours:g} "
                         "needs a --model-file trained at that time")
    t0 = time.perf_counter()
    phases.start("building the FMUs", str(fmu_dir))
    fmu_dir = build_fmus(fmu_dir, IDENTIFIED_STATIC_FMUS, cross=False)[0].parent  # for this machine: what the demo runs
    params = demo_parameters(lat_deg=lat_deg, align_hours=align_hours, imu=imu, start=start, rotation=rotation,
                             seed=seed, axial_drift_dph=axial_drift_dph)
    model_path = model_file or str(default_model_path(model))
    ident = {"model_file": model_path, "trigger_time": identify_hours * HOUR}
    hours = align_hours + identify_hours + nav_hours
    system = standard_static_identified(fmu_dir, hours=hours, identifier=ident, **params)
    record = ["ins.lat_error", "ins.position_error", "ins.nav_time", "imu.temp_gyro_z", "identifier.axial_drift"]
    steps = int(round(hours * HOUR))
    phases.start("loading", "loading the FMUs (native C: Turntable, IMUThermal, StrapdownINS, RBFIdentifier)")
    bar = phases.progress(steps)

    def on_step(t, master):
        if bar.first is None:
            phases.start("co-simulating", f"{hours:g} h in {steps} steps of 1 s (Turntable -> IMUThermal -> "
                         "StrapdownINS -> RBFIdentifier)")
        bar.update(int(round(t)))

    try:
        result = simulate_system(system, hours * HOUR, 1.0, record=record, progress=False, callback=on_step)
    finally:
        bar.close()
    phases.start("in-process reference", "the same run without compensation, no FMUs")
    ref_bar = phases.progress(steps)
    reference = run_static(lat_deg=lat_deg, align_hours=align_hours, nav_hours=identify_hours + nav_hours,
                           rotation=rotation, imu=imu, axial_drift_dph=axial_drift_dph, start=start, seed=seed,
                           on_increments=lambda times, *_: ref_bar.update(int(round(times[-1]))))
    ref_bar.close()
    phases.end()
    unit = imu_mod.preset(imu)
    if axial_drift_dph is not None:
        unit = unit.with_axial_drift(axial_drift_dph * DPH_TO_RPS)
    t_ident = (align_hours + identify_hours) * HOUR
    true_dph = true_axial_drift_dph(unit, result["time"], result["imu.temp_gyro_z"], t_ident, hours * HOUR)
    identified_dph = float(result["identifier.axial_drift"][-1]) / DPH_TO_RPS
    return {"fmu_dir": str(fmu_dir), "model_file": model_path, "hours": hours, "cosim": result,
            "reference": reference, "true_drift_dph": true_dph, "identified_drift_dph": identified_dph,
            "identification_error_dph": identified_dph - true_dph, "wall_seconds": time.perf_counter() - t0}


@dataclass(frozen=True)
class DemoFiles:
    """What :func:`write_results` wrote."""

    folder: Path
    series: Path
    figure: Path


SERIES_EVERY = 60  # s: one CSV row per minute of the 1 s run


def _target(folder: Path, name: str) -> Path:
    path = folder / name
    if path.exists() and not path.is_file():
        raise ValueError(f"{path} exists and is not a regular file")
    return path


def write_results(out: dict, folder, *, identify_hours: float) -> DemoFiles:
    """Write the demo's series (CSV, one row a minute) and a PNG figure of the horizontal position
    error with (co-simulated) and without (in-process reference) compensation into ``folder``.

    CSV columns (navigation time from the end of the alignment): ``nav_time_s``,
    ``position_error_compensated_m``, ``position_error_uncompensated_m``, ``lat_error_compensated_rad``,
    ``temp_gyro_z_degC``, ``identified_drift_rad_s`` (the identifier's output, 0 before it fires).
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder} exists and is not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    series, figure = _target(folder, "series.csv"), _target(folder, "position_error.png")
    res, ref = out["cosim"], out["reference"]
    nav = np.asarray(res["ins.nav_time"], float)
    rows = np.flatnonzero((nav >= 0.0) & (np.round(nav) % SERIES_EVERY == 0))
    uncomp = np.interp(nav[rows], ref.time, ref.position_error)
    columns = {"nav_time_s": nav[rows], "position_error_compensated_m": res["ins.position_error"][rows],
               "position_error_uncompensated_m": uncomp, "lat_error_compensated_rad": res["ins.lat_error"][rows],
               "temp_gyro_z_degC": res["imu.temp_gyro_z"][rows],
               "identified_drift_rad_s": res["identifier.axial_drift"][rows]}
    with open(series, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(columns)
        for k in range(len(rows)):
            w.writerow([f"{columns[c][k]:.10g}" for c in columns])
    _plot(res, ref, identify_hours, figure)
    return DemoFiles(folder, series, figure)


def _plot(res, ref, identify_hours: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nav = np.asarray(res["ins.nav_time"], float)
    shown = nav >= 0.0
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(ref.time[ref.time >= 0] / HOUR, ref.position_error[ref.time >= 0] / NM, color="0.5",
            label="without compensation (in process)")
    ax.plot(nav[shown] / HOUR, res["ins.position_error"][shown] / NM, color="C0",
            label="with the identified drift subtracted (co-simulated)")
    ax.axvline(identify_hours, color="C3", linestyle="--", linewidth=1, label=f"identification at {identify_hours:g} h")
    ax.set_xlabel("navigation time [h]")
    ax.set_ylabel("horizontal position error [nmi]")
    ax.set_title("sarins demo: position error with and without axial-drift compensation")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


NEXT_COMMANDS = (
    ("build the FMUs with the project's systems (.ssp) beside them", "sarins build-fmus --out build/fmus --system"),
    ("co-simulate the plain standard system (16 h)",
     "sarins cosim build/fmus/standard_static.ssp --stop-time 57600 --step 1 --output build/run.csv"),
    ("seed 000's identification campaign, hot and cold start", "sarins campaign axial-rbf --profile quick"),
    ("seed 002's online temperature-model update", "sarins campaign online-rls --profile quick"),
    ("seed 003's MEMS dynamic calibration", "sarins campaign mems-calibration --profile quick"),
)
