"""Test hooks injected from the tests, never read by the product.

A test that must interrupt a run at a known point (not at a time that depends on the machine's load)
installs one of these wrappers, in its own process with :func:`pytest.MonkeyPatch` or, for a child
process, through :func:`main` (``python tests/hooks.py --kill-after 3 -m sarins campaign ...``):

* :func:`signal_after_steps` -- the co-simulation master sends its own process a signal after its Nth
  communication step (a deterministic Ctrl-C), through the master's public step ``callback``;
* :func:`kill_after_results` -- the campaign runner SIGKILLs its own process (its local workers die with
  it) once a result is stored and the output folder holds at least N results.
"""

from __future__ import annotations

import argparse
import os
import runpy
import signal
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def signal_after_steps(count: int, signame: str = "SIGINT", setattr_=setattr) -> None:
    """Make every ``Master.simulate`` send this process ``signame`` after its ``count``-th step."""
    from orchestration import master as master_module

    signum, real_run = signal.Signals[signame], master_module.Master.simulate

    def run(self, *args, callback=None, **kwargs):
        done = [0]

        def hook(time, master):
            done[0] += 1
            if done[0] == count:
                os.kill(os.getpid(), signum)
            return None if callback is None else callback(time, master)

        return real_run(self, *args, callback=hook, **kwargs)

    setattr_(master_module.Master, "simulate", run)


def kill_after_results(count: int, setattr_=setattr) -> None:
    """Make the campaign runner SIGKILL this process once ``count`` results are stored in its folder."""
    from sarins import campaign

    real_store = campaign._store

    def store(out_dir, task, result, record):
        stored = real_store(out_dir, task, result, record)
        if len(list(Path(out_dir).glob("*.npz"))) >= count:
            os.kill(os.getpid(), signal.SIGKILL)
        return stored

    setattr_(campaign, "_store", store)


def command(*hook_args: str) -> list[str]:
    """The start of a child command line running through :func:`main` with ``hook_args``."""
    return [sys.executable, str(Path(__file__).resolve()), *hook_args]


def main(argv: list[str] | None = None) -> None:
    """``hooks.py [--signal-after N:SIGNAME] [--kill-after N] (-m MODULE | SCRIPT) ARGS...``"""
    parser = argparse.ArgumentParser(prog="hooks.py")
    parser.add_argument("--signal-after", help="N:SIGNAME, a signal after the Nth co-simulation step")
    parser.add_argument("--kill-after", type=int, help="SIGKILL once N campaign results are stored")
    parser.add_argument("-m", dest="module", help="run this module as __main__")
    parser.add_argument("rest", nargs=argparse.REMAINDER)
    args = parser.parse_args(argv)
    sys.path[:0] = [str(ROOT), str(HERE)]
    if args.signal_after:
        count, _, name = args.signal_after.partition(":")
        signal_after_steps(int(count), name or "SIGINT")
    if args.kill_after is not None:
        kill_after_results(args.kill_after)
    if args.module:
        sys.argv = [args.module, *args.rest]
        runpy.run_module(args.module, run_name="__main__", alter_sys=True)
    else:
        sys.argv = list(args.rest)
        runpy.run_path(args.rest[0], run_name="__main__")


if __name__ == "__main__":
    main()
