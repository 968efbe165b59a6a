"""Out-of-process slaves (issue 10 item 2, option c) measured against the native layer (option a).

A measurement prototype, not a product (no FMU, no FMI C API): each slave
runs in a server process of its own, the very pythonfmu slave class the FMU
runs (``fmus.<name>_slave``, created in the server), and the host process
forwards the FMI calls of a step over a Unix socket (``socketpair``) with a
compact binary encoding: a 5-byte header (operation, payload length), value
references as uint32 and values as float64 arrays.  Two variants:

* ``per call``: one round trip per FMI call, as an FMU binary forwarding each
  call would make: Turntable doStep + getReal, IMUThermal setReal + doStep +
  getReal, StrapdownINS setReal + doStep + getReal (8 round trips per step with
  a Python Turntable; 6 now that it is native and runs in the host);
* ``batched``: one round trip per FMU and step carrying setReal + doStep +
  getReal (2 per step now, 3 with a Python Turntable; the most a forwarding layer could batch without
  changing the FMI API).

The Turntable and IMUThermal are native FMUs (no Python slave): every variant
runs them in the host process through FMPy, so the comparison is between ways
of hosting the Python slave (StrapdownINS's in-process face).

Measured in one process, on the Turntable -> IMUThermal -> StrapdownINS chain
(Gauss-Seidel, 1 s step, nav-rlg, 10 min alignment; the navigation phase is
timed): the per-step cost of both variants, of the built FMUs run in process
through FMPy and the native layer (the same calls, ``fmu_runs``-built FMUs),
and of the same slave objects driven in this process without any FMI layer;
the bare round-trip time of the socket.  Outputs of every variant are
compared (they must be bit-identical).  The client here is Python code
calling the socket directly; a real forwarding FMU in an FMPy host would add
FMPy's ctypes call in front of each round trip, so the out-of-process figures
are a lower bound.

Crash counts: ``--runs N`` fresh host processes per variant (native layer
through FMPy; out-of-process, batched, three servers each) run 1200 steps
and exit; every non-zero exit of a host or a server is counted and the
final outputs compared across processes.

Usage: ``python benchmarks/bench_out_of_process.py [--steps 1000] [--rounds 5] [--runs 50]``
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import shutil
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import fmu_runs

HEADER = struct.Struct("<BI")  # operation (request) or status (reply); payload length in bytes
COUNT = struct.Struct("<I")
TIMES = struct.Struct("<dd")
BATCH = struct.Struct("<IIdd")  # n inputs, n outputs, t, h
(DESCRIBE, START_VALUES, SETUP, ENTER_INIT, EXIT_INIT, SET_REAL, GET_REAL, DO_STEP, STEP_BATCHED, TERMINATE,
 FREE, PING) = range(1, 13)
OK, DISCARD, ERROR = 0, 2, 3
CHAIN = ("Turntable", "IMUThermal", "StrapdownINS")
NATIVE_FMUS = ("Turntable", "IMUThermal")  # no Python slave: loaded through FMPy in every variant
SLAVE_CLASSES = {"StrapdownINS": ("fmus.strapdown_ins_slave", "StrapdownINS")}
# the time-tagged motion set and increments of the standard system (sarins.systems' links)
TT_TO_IMU = [f"{q}_{j}" for j in (1, 2, 3) for q in ("angle", "rate", "accel")] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]
IMU_TO_INS = ["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "temp_gyro_z", "increment_end_time"]
RECORD = ["lat_error", "lon_error", "position_error", "nav_time"]
ALIGN = 600.0  # s: alignment of the chain (steps after it are navigation)
PARAMS = {"Turntable": {"align_time": ALIGN}, "IMUThermal": {},
          "StrapdownINS": {"align_time": ALIGN, "coarse_time": 120.0}}
STEP = 1.0


class SlaveError(RuntimeError):
    """A forwarded call returned a status other than OK."""


# ---------------------------------------------------------------- server side

def call_status(slave, result=True) -> tuple[int, bytes]:
    """(status, message) after a slave call: logged errors make it ERROR, a False do_step DISCARD."""
    queue = slave.log_queue
    errors = [m.msg for m in queue if int(m.status) >= ERROR]
    queue.clear()
    if errors:
        return ERROR, "; ".join(errors).encode()
    return (OK if result is not False else DISCARD), b""


class Handler:
    """Serves FMI calls on one slave object; Reals go straight to its float64 buffer."""

    def __init__(self, slave):
        self.slave = slave
        self.buffer = slave._fmi_buffer
        self._slots = {}  # encoded value references -> buffer slots

    def slots(self, vrs: bytes) -> np.ndarray:
        idx = self._slots.get(vrs)
        if idx is None:
            table = self.slave._fmi_slots
            idx = self._slots[vrs] = np.array([table[int(v)] for v in np.frombuffer(vrs, "<u4")], dtype=np.intp)
        return idx

    def status(self, result=True) -> tuple[int, bytes]:
        return call_status(self.slave, result)

    def call(self, op: int, data: memoryview) -> tuple[int, bytes]:
        """One request: (status, reply payload)."""
        try:
            return self._call(op, data)
        except Exception as exc:  # noqa: BLE001  (reported to the host as an error status)
            self.slave.log_queue.clear()
            return ERROR, f"{type(exc).__name__}: {exc}".encode()

    def _call(self, op, data):
        slave = self.slave
        if op == SET_REAL:
            (n,) = COUNT.unpack_from(data)
            self.buffer[self.slots(bytes(data[4:4 + 4 * n]))] = np.frombuffer(data, "<f8", n, 4 + 4 * n)
            return OK, b""
        if op == GET_REAL:
            (n,) = COUNT.unpack_from(data)
            return OK, self.buffer[self.slots(bytes(data[4:4 + 4 * n]))].tobytes()
        if op == DO_STEP:
            return self.status(slave.do_step(*TIMES.unpack_from(data)))
        if op == STEP_BATCHED:
            n_in, n_out, t, h = BATCH.unpack_from(data)
            at = BATCH.size
            if n_in:
                self.buffer[self.slots(bytes(data[at:at + 4 * n_in]))] = np.frombuffer(data, "<f8", n_in,
                                                                                       at + 4 * n_in)
            at += 12 * n_in
            status, message = self.status(slave.do_step(t, h))
            if status != OK:
                return status, message
            return OK, self.buffer[self.slots(bytes(data[at:at + 4 * n_out]))].tobytes()
        if op == PING:
            return OK, b""
        return self._control(op, data)

    def _control(self, op, data):
        slave = self.slave
        if op == DESCRIBE:
            return OK, json.dumps({v.name: vr for vr, v in slave.vars.items()}).encode()
        if op == START_VALUES:  # [[vr, value], ...] through pythonfmu's typed setters
            for vr, value in json.loads(bytes(data)):
                setter = {str: slave.set_string, int: slave.set_integer, float: slave.set_real}[type(value)]
                setter([vr], [value])
            return self.status()
        if op == SETUP:
            return self.status(slave.setup_experiment(TIMES.unpack_from(data)[0], None, None))
        if op == ENTER_INIT:
            return self.status(slave.enter_initialization_mode())
        if op == EXIT_INIT:
            return self.status(slave.exit_initialization_mode())
        if op == TERMINATE:
            return self.status(slave.terminate())
        return ERROR, f"unknown operation {op}".encode()


def recv_exact(sock: socket.socket, view: memoryview) -> bool:
    """Fill ``view`` from ``sock``; False on end of stream before any byte."""
    got = 0
    while got < len(view):
        n = sock.recv_into(view[got:])
        if n == 0:
            if got == 0:
                return False
            raise ConnectionError("connection closed inside a message")
        got += n
    return True


def serve(fd: int, name: str) -> None:
    """Server process main loop: one slave, requests until FREE or the host goes away."""
    module, cls = SLAVE_CLASSES[name]
    handler = Handler(getattr(importlib.import_module(module), cls)(instance_name=name, resources=None,
                                                                     visible=False))
    sock = socket.socket(fileno=fd)
    buf = bytearray(1 << 16)
    view = memoryview(buf)
    while recv_exact(sock, view[:HEADER.size]):
        op, n = HEADER.unpack_from(buf)
        if n and not recv_exact(sock, view[:n]):
            break
        if op == FREE:
            sock.sendall(HEADER.pack(OK, 0))
            break
        status, payload = handler.call(op, view[:n])
        sock.sendmsg([HEADER.pack(status, len(payload)), payload])
    sock.close()


# ---------------------------------------------------------------- host side

class RemoteSlave:
    """Host-side proxy of a slave served by another process (one round trip per method call)."""

    def __init__(self, name: str):
        host_end, server_end = socket.socketpair()
        self.proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--serve", name,
                                      str(server_end.fileno())], pass_fds=[server_end.fileno()])
        server_end.close()
        self.sock = host_end
        self.name = name
        self._buf = bytearray(1 << 16)
        self._view = memoryview(self._buf)
        self.vr = json.loads(bytes(self._call(DESCRIBE)))

    def encode(self, names) -> bytes:
        """The named variables' value references as sent (uint32)."""
        return np.asarray([self.vr[n] for n in names], dtype="<u4").tobytes()

    def _call(self, op: int, *parts: bytes) -> memoryview:
        self.sock.sendmsg([HEADER.pack(op, sum(len(p) for p in parts)), *parts])
        recv_exact(self.sock, self._view[:HEADER.size])
        status, n = HEADER.unpack_from(self._buf)
        if n:
            recv_exact(self.sock, self._view[:n])
        if status != OK:
            raise SlaveError(f"{self.name}: status {status}: {bytes(self._view[:n]).decode(errors='replace')}")
        return self._view[:n]

    def start_values(self, values: dict) -> None:
        self._call(START_VALUES, json.dumps([[self.vr[k], v] for k, v in values.items()]).encode())

    def setup(self, start: float) -> None:
        self._call(SETUP, TIMES.pack(start, 0.0))

    def enter_init(self) -> None:
        self._call(ENTER_INIT)

    def exit_init(self) -> None:
        self._call(EXIT_INIT)

    def set_real(self, vrs: bytes, values: np.ndarray) -> None:
        self._call(SET_REAL, COUNT.pack(len(vrs) // 4), vrs, values.tobytes())

    def get_real(self, vrs: bytes) -> np.ndarray:
        return np.frombuffer(self._call(GET_REAL, COUNT.pack(len(vrs) // 4), vrs), "<f8").copy()

    def do_step(self, t: float, h: float) -> None:
        self._call(DO_STEP, TIMES.pack(t, h))

    def step(self, vrs_in: bytes, values, t: float, h: float, vrs_out: bytes) -> np.ndarray:
        """setReal + doStep + getReal in one round trip."""
        head = BATCH.pack(len(vrs_in) // 4, len(vrs_out) // 4, t, h)
        data = b"" if values is None else values.tobytes()
        return np.frombuffer(self._call(STEP_BATCHED, head, vrs_in, data, vrs_out), "<f8").copy()

    def ping(self) -> None:
        self._call(PING)

    def free(self) -> int:
        """Terminate and free; the server's exit code."""
        try:
            self._call(TERMINATE)
        finally:
            self.sock.sendall(HEADER.pack(FREE, 0))
            self.sock.recv(HEADER.size)
            self.sock.close()
        return self.proc.wait(timeout=60)


class DirectSlave:
    """The same slave class in this process, called directly: Reals through buffer slots, no FMI
    layer, no encoding (the slave's own work plus the least a host must do per call)."""

    def __init__(self, name: str):
        module, cls = SLAVE_CLASSES[name]
        self.name = name
        self.slave = getattr(importlib.import_module(module), cls)(instance_name=name, resources=None,
                                                                    visible=False)
        self.buffer = self.slave._fmi_buffer
        self.vr = {v.name: vr for vr, v in self.slave.vars.items()}

    def encode(self, names) -> np.ndarray:
        return np.array([self.slave._fmi_slots[self.vr[n]] for n in names], dtype=np.intp)

    def _check(self, result=True) -> None:
        status, message = call_status(self.slave, result)
        if status != OK:
            raise SlaveError(f"{self.name}: status {status}: {message.decode(errors='replace')}")

    def start_values(self, values: dict) -> None:
        for k, v in values.items():
            setattr(self.slave, k, v)

    def setup(self, start):
        self._check(self.slave.setup_experiment(start, None, None))

    def enter_init(self):
        self._check(self.slave.enter_initialization_mode())

    def exit_init(self):
        self._check(self.slave.exit_initialization_mode())

    def set_real(self, slots, values) -> None:
        self.buffer[slots] = values

    def get_real(self, slots):
        return self.buffer[slots]  # a copy (fancy indexing)

    def do_step(self, t, h):
        self._check(self.slave.do_step(t, h))

    def step(self, slots_in, values, t, h, slots_out):
        if len(slots_in):
            self.buffer[slots_in] = values
        self._check(self.slave.do_step(t, h))
        return self.buffer[slots_out]

    def free(self) -> int:
        self._check(self.slave.terminate())
        return 0


class FmpySlave:
    """A built FMU in this process through FMPy's FMU2Slave and the native layer."""

    def __init__(self, fmu: Path, name: str):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        md = read_model_description(str(fmu))
        self.name = name
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self._types = {v.name: v.type for v in md.modelVariables}
        self.folder = extract(str(fmu))
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.folder,
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate()

    def encode(self, names) -> list:
        return [self.vr[n] for n in names]

    def start_values(self, values: dict) -> None:
        for k, v in values.items():
            {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger, "String": self.fmu.setString}[
                self._types[k]]([self.vr[k]], [v])

    def setup(self, start):
        self.fmu.setupExperiment(startTime=start)

    def enter_init(self):
        self.fmu.enterInitializationMode()

    def exit_init(self):
        self.fmu.exitInitializationMode()

    def set_real(self, vrs: list, values) -> None:
        self.fmu.setReal(vrs, values)

    def get_real(self, vrs: list):
        return np.asarray(self.fmu.getReal(vrs), dtype=float)  # as the other proxies return them

    def do_step(self, t, h):
        self.fmu.doStep(t, h)

    def step(self, vrs_in, values, t, h, vrs_out):
        if vrs_in:
            self.fmu.setReal(vrs_in, values)
        self.fmu.doStep(t, h)
        return self.get_real(vrs_out)

    def free(self) -> int:
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.folder, ignore_errors=True)
        return 0


class Chain:
    """Turntable -> IMUThermal -> StrapdownINS, Gauss-Seidel, over three slave proxies."""

    def __init__(self, kind: str, fmu_dir: Path, params: dict = PARAMS):
        make = {"remote": RemoteSlave, "direct": DirectSlave}.get(kind)
        self.slaves = [make(n) if make and n not in NATIVE_FMUS else FmpySlave(fmu_dir / f"{n}.fmu", n)
                       for n in CHAIN]
        tt, imu, ins = self.slaves
        self.links = [(tt.encode(TT_TO_IMU), imu.encode(TT_TO_IMU)), (imu.encode(IMU_TO_INS), ins.encode(IMU_TO_INS))]
        self.none = tt.encode([])
        self.record = ins.encode(RECORD)
        for s in self.slaves:
            s.start_values(params[s.name])
            s.setup(0.0)
            s.enter_init()
        (tt_out, imu_in), (imu_out, ins_in) = self.links
        imu.set_real(imu_in, tt.get_real(tt_out))
        ins.set_real(ins_in, imu.get_real(imu_out))
        for s in self.slaves:
            s.exit_init()
        self.k = 0

    def run_per_call(self, n: int) -> list:
        tt, imu, ins = self.slaves
        (tt_out, imu_in), (imu_out, ins_in) = self.links
        rows = []
        for _ in range(n):
            t = self.k * STEP
            tt.do_step(t, STEP)
            imu.set_real(imu_in, tt.get_real(tt_out))
            imu.do_step(t, STEP)
            ins.set_real(ins_in, imu.get_real(imu_out))
            ins.do_step(t, STEP)
            rows.append(ins.get_real(self.record))
            self.k += 1
        return rows

    def run_batched(self, n: int) -> list:
        tt, imu, ins = self.slaves
        (tt_out, imu_in), (imu_out, ins_in) = self.links
        rows = []
        for _ in range(n):
            t = self.k * STEP
            motion = tt.step(self.none, None, t, STEP, tt_out)
            increments = imu.step(imu_in, motion, t, STEP, imu_out)
            rows.append(ins.step(ins_in, increments, t, STEP, self.record))
            self.k += 1
        return rows

    def free(self) -> list[int]:
        return [s.free() for s in self.slaves]


VARIANTS = {  # name: (chain kind, stepping method)
    "slaves called directly (no FMI layer)": ("direct", "run_per_call"),
    "native layer, in process (FMPy)": ("fmpy", "run_per_call"),
    "out of process, per call (6 round trips)": ("remote", "run_per_call"),
    "out of process, batched (2 round trips)": ("remote", "run_batched"),
}
NATIVE, BATCHED = list(VARIANTS)[1], list(VARIANTS)[3]
IN_PROCESS = "in-process run (run_static, no FMUs)"


def per_step_costs(fmu_dir: Path, steps: int, rounds: int) -> None:
    """Interleaved rounds of ``steps`` navigation steps per variant (and of the in-process run);
    median us/step; outputs compared with the native layer's."""
    chains = {name: Chain(kind, fmu_dir) for name, (kind, _) in VARIANTS.items()}
    rows = {name: [] for name in VARIANTS}
    for name, (_, method) in VARIANTS.items():  # alignment (and any compilation) untimed
        rows[name] += getattr(chains[name], method)(int(ALIGN) + 100)
    in_process_per_step(100)  # the library's kernels compiled / loaded
    cost = {name: [] for name in [*VARIANTS, IN_PROCESS]}
    for _ in range(rounds):
        for name, (_, method) in VARIANTS.items():
            t0 = time.perf_counter()
            rows[name] += getattr(chains[name], method)(steps)
            cost[name].append((time.perf_counter() - t0) / steps * 1e6)
        cost[IN_PROCESS].append(in_process_per_step(steps))
    pings = round_trips(chains[BATCHED].slaves[1], 2000)
    codes = {name: chain.free() for name, chain in chains.items()}
    ref = np.array(rows[NATIVE], dtype=float)
    base, inproc = statistics.median(cost[NATIVE]), statistics.median(cost[IN_PROCESS])
    print(f"per step ({rounds} interleaved rounds of {steps} navigation steps, median; Turntable -> IMUThermal -> "
          "StrapdownINS, 1 s, nav-rlg at 200 Hz)")
    for name in cost:
        med = statistics.median(cost[name])
        notes = [f"rounds {min(cost[name]):.0f}-{max(cost[name]):.0f} us"]
        if name in rows:
            notes.append("outputs " + ("bit-identical" if np.array_equal(np.array(rows[name], float), ref)
                                       else "DIFFER"))
        if name in VARIANTS and VARIANTS[name][0] == "remote":
            notes.append(f"server exit codes {codes[name]}")
        print(f"  {name:42s} {med:6.0f} us = {med / base:4.2f}x the native layer = {med / inproc:4.1f}x the "
              f"in-process run ({'; '.join(notes)})")
    print(f"  bare round trip (empty request and reply, {len(pings)}x): median {statistics.median(pings):.1f} us")


def round_trips(remote: RemoteSlave, n: int) -> list:
    """Microseconds of ``n`` empty round trips to a server."""
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        remote.ping()
        out.append((time.perf_counter() - t0) * 1e6)
    return out


def in_process_per_step(nav_steps: int) -> float:
    """Microseconds per 1 s step of the same chain run in process by the library (``run_static``:
    the same alignment, then ``nav_steps`` of navigation)."""
    from sarins_fmu.experiments import run_static

    t0 = time.perf_counter()
    run_static(align_hours=ALIGN / 3600, nav_hours=nav_steps / 3600, seed=0)
    return (time.perf_counter() - t0) / (ALIGN + nav_steps) * 1e6


def crash_child(kind: str, fmu_dir: Path, steps: int) -> None:
    """One fresh host process: the chain for ``steps`` steps; prints the last row and the servers' exit codes."""
    chain = Chain(kind, fmu_dir)
    rows = chain.run_batched(steps) if kind == "remote" else chain.run_per_call(steps)
    codes = chain.free()
    print("RESULT", json.dumps([float(x) for x in rows[-1]]), "SERVERS", json.dumps(codes))


def crash_counts(fmu_dir: Path, runs: int, steps: int, env: dict) -> None:
    """``runs`` fresh host processes per variant: non-zero exits of hosts and servers, distinct results."""
    every = set()
    for label, kind, servers in (("native layer, in process (FMPy host)", "fmpy", 0),
                                 ("out of process, batched (host + 2 servers)", "remote", len(SLAVE_CLASSES))):
        bad_hosts, bad_servers, results = [], 0, set()
        t0 = time.time()
        for _ in range(runs):
            proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--crash-child", kind,
                                   str(fmu_dir), str(steps)], capture_output=True, text=True, env=env, timeout=600)
            line = next((x for x in proc.stdout.splitlines() if x.startswith("RESULT ")), None)
            if proc.returncode != 0 or line is None:
                bad_hosts.append(proc.returncode)
                continue
            result, codes = line[len("RESULT "):].split(" SERVERS ")
            bad_servers += sum(c != 0 for c in json.loads(codes))
            results.add(result)
        print(f"  {label:44s} hosts {len(bad_hosts)}/{runs} non-zero exits"
              + (f" {bad_hosts}" if bad_hosts else "")
              + (f", servers {bad_servers}/{runs * servers}" if servers else "")
              + f"; {len(results)} distinct final outputs; {(time.time() - t0) / runs:.1f} s per process")
        every |= results
    print(f"  final outputs of both variants: {'identical' if len(every) == 1 else 'DIFFER'}")


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--serve":
        serve(int(sys.argv[3]), sys.argv[2])
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--crash-child":
        crash_child(sys.argv[2], Path(sys.argv[3]), int(sys.argv[4]))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1000, help="timed steps per round and variant")
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--runs", type=int, default=50, help="fresh processes per variant for the crash count")
    parser.add_argument("--run-steps", type=int, default=1200, help="steps of each crash-count process")
    args = parser.parse_args()
    sys.path.insert(0, str(fmu_runs.ROOT))
    from fmus.build import build_fmus

    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} (1, 5, 15 min) at the start")
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = Path(tmp) / "fmus"
        build_fmus(fmu_dir, list(CHAIN))
        os.environ["SARINS_FMU_CACHE"] = str(Path(tmp) / "cache")  # this process's FMUs and the children's
        env = fmu_runs.host_env(os.environ)
        per_step_costs(fmu_dir, args.steps, args.rounds)
        if args.runs:
            print(f"crash count, {args.runs} fresh processes each, {args.run_steps} steps, then exit:")
            crash_counts(fmu_dir, args.runs, args.run_steps, env)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} at the end")


if __name__ == "__main__":
    main()
