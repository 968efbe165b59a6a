"""``sarins campaign NAME ...``: the papers' experiment campaigns.

Each campaign lives in its own module (``CAMPAIGNS`` maps the command-line
name to it) exposing

* ``HELP``: one line for ``sarins campaign --help``;
* ``add_arguments(parser)``: campaign-specific options (may add nothing);
* ``run(args) -> int``: runs the campaign; bad input raises ``ValueError``
  (reported by ``sarins`` as one line, exit status 2).

The options every campaign shares (``--profile``, ``--workers``,
``--scheduler``, ``--out``, ``--no-progress``) are added and checked here,
before any work: ``--scheduler`` needs Dask installed and excludes
``--workers``, ``--out`` must be a
folder, and one campaign at a time holds it (a second one on the same
``--out`` is refused with exit status 2 and the holder's pid; it does not
wait).  A task that fails, or an FMU call that fails, ends the campaign
with exit status 1; Ctrl-C and SIGTERM stop it and its workers (130/143).  A campaign
module that cannot be imported (it is missing or an optional dependency is
absent at import time) is not offered.
"""

from __future__ import annotations

import importlib

from pathlib import Path

from . import RunError, UsageError, bounded_int, refuse_unless

CAMPAIGNS = {
    "axial-rbf": "sarins.axial_rbf.campaign",  # seed 000: RBF identification of the axial drift
    "online-rls": "sarins.online_rls.campaign",  # seed 002: temperature model updated online (FF-RLS)
    "mems-calibration": "sarins.mems_calibration.campaign",  # seed 003: MEMS IMU dynamic calibration
    "aided-nav": "sarins.aided_nav.campaign",  # issue 30: GNSS/INS aided navigation, NEES and outages
}


def _add_common(parser, name: str) -> None:
    parser.add_argument("--profile", choices=("quick", "paper"), default="quick",
                        help="quick: minutes, for tests; paper: the paper's protocol (default quick)")
    parser.add_argument("--workers", type=bounded_int(1, 1024), default=None,
                        help="local worker processes, each single-threaded (default: all cores; 1 runs in this "
                             "process)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="Dask distributed scheduler address, e.g. tcp://host:8786 (needs "
                             "'sarins-fmu[distributed]'; start workers with --nthreads 1)")
    parser.add_argument("--out", default=f"results/{name}", metavar="DIR",
                        help=f"output directory; finished experiments there are not redone (default results/{name})")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def register(subparsers) -> None:
    """Add ``campaign`` with one sub-command per importable campaign module."""
    parser = subparsers.add_parser("campaign", help="run a paper's experiment campaign (parallel, resumable)")
    sub = parser.add_subparsers(dest="campaign", required=True, parser_class=type(parser))
    for name, module_name in CAMPAIGNS.items():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and module_name.startswith(exc.name):
                continue  # this campaign is not part of this installation
            raise
        p = sub.add_parser(name, help=module.HELP, description=module.HELP)
        _add_common(p, name)
        module.add_arguments(p)
        p.set_defaults(func=run, campaign_run=module.run)


def run(args) -> int:
    """Check the shared options, lock ``--out`` and run the campaign."""
    from orchestration.errors import FMUCallError
    from sarins.campaign import TaskFailed, exclusive, remove_stale_temporaries

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out} exists and is not a folder")
    refuse_unless(args, {"workers": "--workers"}, not args.scheduler,
                  "does not apply with --scheduler (the Dask cluster's workers run the tasks)")
    if args.scheduler:
        import importlib.util

        try:
            found = importlib.util.find_spec("distributed") is not None
        except (ImportError, ValueError):  # a None entry in sys.modules
            found = False
        if not found:
            raise UsageError("--scheduler needs Dask's distributed scheduler, which is not installed: "
                             "pip install 'sarins-fmu[distributed]'")
    with exclusive(out):
        remove_stale_temporaries(out)  # what a killed run left half-written (under the lock: nobody writes)
        try:
            return args.campaign_run(args)
        except (TaskFailed, FMUCallError) as exc:
            raise RunError(str(exc)) from None
