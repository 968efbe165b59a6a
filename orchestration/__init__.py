"""Generic fixed-step co-simulation master for FMI 2.0 and FMI 3.0 co-simulation FMUs.

Systems are described in SSP 1.0 (``.ssp`` archives or ``SystemStructure.ssd``
with the FMUs beside it) or built in python (:class:`System`); the master
(:class:`Master`, :func:`simulate_system`) runs them with FMPy's low-level
``FMU2Slave`` / ``FMU3Slave`` API (FMI 3.0 arrays and structural parameters
included; no event mode, clocks or intermediate update) under a Gauss-Seidel or Jacobi coupling scheme and returns a
numpy structured array (``time`` first, then ``component.variable`` fields).
This package knows nothing about the FMUs it runs.

Main entry points
-----------------
- :func:`read_system`, :func:`write_ssd`, :func:`write_ssp`, :class:`System`,
  :class:`Component`, :class:`Connection` - system files (SSP 1.0).
- :class:`Master`, :func:`simulate_system` - the fixed-step master.
- :func:`write_csv` - results to CSV.
- :func:`build_container_fmu` - the system as one FMI 2.0 container FMU.
- :mod:`orchestration.interrupt` - clean stops on SIGINT/SIGTERM.
- :mod:`orchestration.importers` - the same system under Ecos or libcosim.
"""
from .container import build_container_fmu
from .errors import (AlgebraicLoopWarning, DefaultStepWarning, FMUCallError, FMUFatalError,
                     ImporterUnavailableError, IncompatibleConnectionError,
                     OrchestrationError, OrchestrationWarning, RealTimeLagWarning,
                     ScheduleError, StartValueError, SystemDescriptionError, SystemFileError,
                     UnconnectedInputWarning, UnknownComponentError, UnknownVariableError)
from .master import SCHEMES, Master, simulate_system
from .recorder import ResultArray, write_csv
from .ssp_reader import read_system
from .ssp_writer import write_ssd, write_ssp
from .interrupt import Interrupted
from .system import Component, Connection, Hop, System

__all__ = [
    "AlgebraicLoopWarning", "Component", "Connection", "DefaultStepWarning", "FMUCallError",
    "FMUFatalError", "Hop", "Interrupted",
    "ImporterUnavailableError", "IncompatibleConnectionError", "Master",
    "OrchestrationError", "OrchestrationWarning", "RealTimeLagWarning", "ResultArray",
    "SCHEMES", "ScheduleError", "StartValueError", "System", "SystemDescriptionError",
    "SystemFileError", "UnconnectedInputWarning", "UnknownComponentError",
    "UnknownVariableError", "build_container_fmu", "read_system", "simulate_system",
    "write_csv", "write_ssd", "write_ssp",
]
