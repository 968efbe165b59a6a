"""One FMI 2.0 or 3.0 co-simulation FMU instance, driven through FMPy's ``FMU2Slave`` /
``FMU3Slave``.

:class:`FMUInstance` wraps the low-level FMPy object: it installs a logger
callback that keeps the FMU's recent log messages, turns every failed call
into an :class:`~orchestration.errors.FMUCallError` that names the component,
the call and the simulated time, and frees itself according to the FMI
state machine (terminate + free when healthy, free only after an error,
nothing after a fatal status).

FMI 3.0 FMUs are instantiated for co-simulation without event mode, early
return or intermediate update (``eventModeUsed = earlyReturnAllowed = false``,
no intermediate-update callback): an FMU that declares clocks needs event
mode and is refused when it is read (:func:`read_description`).
"""
from __future__ import annotations

import shutil
import weakref
import zipfile
from collections import deque
from pathlib import Path

from . import fmilog
from .archive import extract_archive
from .binaries import BinaryError, check_shared_library
from .errors import FMUCallError, FMUFatalError, FMUInstantiateError, SystemFileError, status_label
from .fmitypes import is_fmi3, normalize_fmi3

__all__ = ["read_description", "FMUInstance", "UnpackedFMU", "FMI_FATAL"]

FMI_ERROR = 3
FMI_FATAL = 4
LOG_MESSAGES_KEPT = 50
MAX_DESCRIPTION_BYTES = 64 * 2**20  # modelDescription.xml read at most (the largest of ours: < 1 MiB)
MAX_VARIABLES = 100_000  # variables in one model description (ours: < 1,000); parsing 10**6 takes minutes


def read_description(path: Path, component: str | None = None, shown: Path | None = None, *,
                     fmi3: bool = False):
    """Read and check the model description of a co-simulation FMU.

    Parameters
    ----------
    path : Path
        FMU file (or unzipped FMU folder).
    component : str, optional
        Component name, for error messages.
    shown : Path, optional
        The FMU file to name in messages when ``path`` is its extracted folder.
    fmi3 : bool
        Accept FMI 3.0 FMUs too (the master does; the container builder and
        the third-party importers take FMI 2.0 only).  An FMI 3.0 FMU with
        clocks is refused (they need event mode); its enumerations become
        ``Int64`` variables (:func:`orchestration.fmitypes.normalize_fmi3`).

    Returns
    -------
    fmpy.model_description.ModelDescription

    Raises
    ------
    SystemFileError
        If the file is missing, not an FMU, of an unsupported FMI version,
        not co-simulation, or an FMI 3.0 FMU with clocks.
    """
    from fmpy import read_model_description

    path = Path(path)
    name = str(path if shown is None else shown)
    if not path.exists():
        raise SystemFileError("FMU file not found", file=name, component=component)
    try:
        _check_description_budget(path, name, component)
    except (zipfile.BadZipFile, OSError) as error:
        raise SystemFileError(f"not a readable FMU: {error}", file=name, component=component) from None
    try:
        description = read_model_description(str(path), validate=False)
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise SystemFileError(f"not a readable FMU: {error}", file=name,
                              component=component) from None
    except Exception as error:  # fmpy raises bare Exception on malformed XML
        raise SystemFileError(f"not a readable FMU: {' '.join(str(error).split())}", file=name,
                              component=component) from None
    version = description.fmiVersion
    if version != "2.0" and not (fmi3 and is_fmi3(description)):
        supported = "FMI 2.0 and 3.0 co-simulation only" if fmi3 else "FMI 2.0 co-simulation only"
        raise SystemFileError(f"FMI version {version} is not supported ({supported})",
                              file=name, component=component)
    if description.coSimulation is None:
        raise SystemFileError("the FMU does not support co-simulation", file=name,
                              component=component)
    if is_fmi3(description):
        clocks = [v.name for v in description.modelVariables
                  if v.type == "Clock" or getattr(v, "clocks", None)]
        if clocks:
            raise SystemFileError(f"FMI 3.0 clocks are not supported (they need event mode, "
                                  f"which the master does not drive): {', '.join(clocks[:5])}",
                                  file=name, component=component)
        normalize_fmi3(description)
    _check_value_references(description, name, component)
    return description


def _check_description_budget(path: Path, name: str, component: str | None) -> None:
    """Refuse a model description over :data:`MAX_DESCRIPTION_BYTES` or with more than
    :data:`MAX_VARIABLES` variables before it is parsed (counted as ``valueReference`` attributes)."""
    if path.is_dir():
        file = path / "modelDescription.xml"
        if not file.is_file():
            return  # FMPy's own message
        size = file.stat().st_size
        read = file.read_bytes
    else:
        with zipfile.ZipFile(path) as archive:
            try:
                info = archive.getinfo("modelDescription.xml")
            except KeyError:
                return
        size = info.file_size

        def read():
            with zipfile.ZipFile(path) as archive, archive.open("modelDescription.xml") as fh:
                return fh.read(MAX_DESCRIPTION_BYTES + 1)
    if size > MAX_DESCRIPTION_BYTES:
        raise SystemFileError(f"modelDescription.xml has {size} bytes, more than the limit of "
                              f"{MAX_DESCRIPTION_BYTES} (MAX_DESCRIPTION_BYTES); refused", file=name, component=component)
    count = read().count(b"valueReference")
    if count > MAX_VARIABLES:
        raise SystemFileError(f"modelDescription.xml declares {count} variables, more than the limit of "
                              f"{MAX_VARIABLES} (MAX_VARIABLES); refused", file=name, component=component)


def _check_value_references(description, name: str, component: str | None) -> None:
    """Refuse value references the standard does not allow: FMI 3.0, any shared one; FMI 2.0, an alias
    set (same type, same value reference) with more than one parameter or input (FMI 2.0.x 2.2.7)."""
    fmi3 = is_fmi3(description)
    groups: dict = {}
    for v in description.modelVariables:
        key = v.valueReference if fmi3 else (_base_type(v.type), v.valueReference)
        groups.setdefault(key, []).append(v)
    for key, members in groups.items():
        if len(members) < 2:
            continue
        names = ", ".join(f"'{v.name}'" for v in members[:4])
        vr = key if fmi3 else key[1]
        if fmi3:
            raise SystemFileError(f"valueReference {vr} is used by {len(members)} variables ({names}); FMI 3.0 "
                                  "needs one per variable", file=name, component=component)
        settable = [v for v in members if v.causality in ("parameter", "input") and v.variability != "constant"]
        if len(settable) > 1:
            raise SystemFileError(f"valueReference {vr} is shared by {len(settable)} {key[0]} parameters or inputs "
                                  f"({names}); an FMI 2.0 alias set may hold one", file=name, component=component)


def _base_type(kind: str) -> str:
    """FMI 2.0 base type of a variable (an Enumeration is an Integer)."""
    return "Integer" if kind == "Enumeration" else kind


class UnpackedFMU:
    """An FMU file extracted once and shared by all instances of it.

    Parameters
    ----------
    path : Path
        FMU file.
    component : str
        Name of the first component using it (error messages).

    The archive is extracted with the limits of
    :func:`orchestration.archive.extract_archive` (size, member count, no
    member outside the folder) before its model description is read from
    the extracted folder, so the description is within the limits too.
    """

    def __init__(self, path: Path, component: str):
        self.path = Path(path)
        if not self.path.is_file():
            raise SystemFileError("FMU file not found" if not self.path.exists() else
                                  "not a regular file", file=str(self.path), component=component)
        self.unzipdir = str(extract_archive(self.path, kind="fmu", component=component))
        self._finalizer = weakref.finalize(self, shutil.rmtree, self.unzipdir, True)
        try:
            self.description = read_description(Path(self.unzipdir), component, shown=self.path,
                                                fmi3=True)
        except BaseException:
            self.remove()
            raise
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.fmi3 = is_fmi3(self.description)
        try:
            self._check_binary(component)
        except BaseException:
            self.remove()
            raise

    def _check_binary(self, component: str) -> None:
        """Refuse this platform's shared library when loading it would crash the process
        (:func:`orchestration.binaries.check_shared_library`); a missing one is left to FMPy's message."""
        from fmpy import platform, platform_tuple, sharedLibraryExtension

        identifier = self.description.coSimulation.modelIdentifier if self.description.coSimulation else None
        if not identifier:
            return
        folder = platform_tuple if self.fmi3 else platform
        library = Path(self.unzipdir) / "binaries" / folder / f"{identifier}{sharedLibraryExtension}"
        if not library.is_file():
            return
        try:
            check_shared_library(library)
        except BinaryError as exc:
            raise SystemFileError(f"binaries/{folder}/{library.name} cannot be loaded: {exc}",
                                  file=str(self.path), component=component) from None

    def remove(self) -> None:
        """Delete the extracted folder (also done when the object is garbage collected)."""
        self._finalizer()


class FMUInstance:
    """A co-simulation slave with error reporting.

    Parameters
    ----------
    name : str
        Instance (component) name.
    unpacked : UnpackedFMU
        The extracted FMU.
    logging_on : bool
        Passed to ``fmi2Instantiate``; keep it on to receive error messages.
    """

    def __init__(self, name: str, unpacked: UnpackedFMU, logging_on: bool = True):
        self.name = name
        self.unpacked = unpacked
        self.description = unpacked.description
        self.variables = unpacked.variables
        self.messages: deque[str] = deque(maxlen=LOG_MESSAGES_KEPT)
        self.time: float | None = None
        self.slave = None
        self._state = "loaded"
        self._logging_on = logging_on
        self.instance_name = None

    def _log(self, status, category: str, text: str) -> None:
        """Sink of :mod:`orchestration.fmilog` for this instance's messages."""
        label = status_label(status)
        self.messages.append(f"[{label}]{f' {category}' if category else ''} {text}")

    # life cycle -----------------------------------------------------------
    @property
    def fmi3(self) -> bool:
        """True for an FMI 3.0 FMU."""
        return self.unpacked.fmi3

    def instantiate(self) -> None:
        """Load the shared library and call ``fmi2Instantiate`` / ``fmi3InstantiateCoSimulation``."""
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        description = self.description
        self.instance_name = fmilog.register(self.name, self._log)
        try:
            self.slave = (FMU3Slave if self.fmi3 else FMU2Slave)(
                guid=description.guid, unzipDirectory=self.unpacked.unzipdir,
                modelIdentifier=description.coSimulation.modelIdentifier,
                instanceName=self.instance_name)
        except Exception as error:  # fmpy raises bare Exception when the library is missing
            raise SystemFileError(f"cannot load the FMU's shared library: {error}",
                                  file=str(self.unpacked.path), component=self.name) from None
        self._state = "library"
        try:
            if self.fmi3:
                # FMI 3.0 passes the formatted message (no variadic proxy): one callback per instance
                self.slave.instantiate(loggingOn=self._logging_on, logMessage=self._log3)
            else:
                self.slave.instantiate(callbacks=fmilog.callbacks(), loggingOn=self._logging_on)
        except Exception:  # fmpy raises bare Exception when fmi2Instantiate returns NULL
            self._state = "error"
            raise FMUInstantiateError(self.name, "fmi3InstantiateCoSimulation" if self.fmi3 else "fmi2Instantiate",
                                      FMI_ERROR, self.time, list(self.messages),
                                      fmu_file=str(self.unpacked.path)) from None
        self._state = "instantiated"
        if self._logging_on:
            self._restrict_logging()

    def _log3(self, environment, status, category, message) -> None:
        """``fmi3LogMessageCallback`` of this instance."""
        self._log(status, category.decode("utf-8", "replace") if category else "",
                  message.decode("utf-8", "replace") if message else "")

    def setup(self, start: float, structural: list[tuple[str, int, list]],
              others: list[tuple[str, int, list]]) -> None:
        """Apply start values and enter Initialization Mode at ``start`` (s).

        Parameters
        ----------
        structural, others : list of (kind, value reference, values)
            Start values (``values`` a list, one element per array element).
            FMI 3.0: structural parameters are set in Configuration Mode,
            the others in Instantiated, then ``fmi3EnterInitializationMode``
            (no tolerance, no stop time).  FMI 2.0: ``fmi2SetupExperiment``
            (no stop time), every start value, ``fmi2EnterInitializationMode``.
        """
        if self.fmi3:
            if structural:
                self.call("enterConfigurationMode")
                for kind, vr, values in structural:
                    self.call(f"set{kind}", [vr], values)
                self.call("exitConfigurationMode")
            for kind, vr, values in others:
                self.call(f"set{kind}", [vr], values)
            self.call("enterInitializationMode", None, start, None)
            return
        # no stop time: FMUs such as OpenModelica's refuse a doStep whose t + h passes a
        # defined stop time by one rounding error
        self.call("setupExperiment", None, start, None)
        for kind, vr, values in structural + others:
            self.call(f"set{kind}", [vr], values)
        self.call("enterInitializationMode")

    def _restrict_logging(self) -> None:
        """Keep only the ``logStatus*`` categories when the FMU declares them.

        Those carry warnings and errors (FMI 2.0 recommends these names);
        chatty categories such as OpenModelica's ``logFmi2Call`` would
        otherwise send a message through python on every call.
        """
        categories = [c.name for c in self.description.logCategories
                      if c.name.startswith("logStatus")]
        if categories:
            try:
                self.slave.setDebugLogging(True, categories)
            except Exception:  # noqa: BLE001 - logging is a courtesy, not a requirement
                pass

    def call(self, function: str, *args):
        """Call an FMPy ``FMU2Slave`` method, turning failures into FMUCallError.

        Parameters
        ----------
        function : str
            Method name of ``FMU2Slave`` (``'doStep'``, ``'setReal'``, ...).
        *args
            Its arguments.
        """
        from fmpy.fmi1 import FMICallException

        try:
            return getattr(self.slave, function)(*args)
        except FMICallException as error:
            self._raise(error.function, error.status)

    def _raise(self, call: str, status: int) -> None:
        if status >= FMI_FATAL:
            self._state = "fatal"
            error_type = FMUFatalError
        else:
            self._state = "error"
            error_type = FMUCallError
        raise error_type(self.name, call, status, self.time, list(self.messages),
                         fmu_file=str(self.unpacked.path))

    def fail(self, call: str, status: int) -> None:
        """Raise the FMUCallError for a failed raw call made by the master's fast loop."""
        self._raise(call, status)

    @property
    def healthy(self) -> bool:
        """True while no call has returned an error status."""
        return self._state in ("instantiated", "initialized")

    def mark_initialized(self) -> None:
        """Record that initialisation completed (terminate is then allowed)."""
        self._state = "initialized"

    def release(self) -> None:
        """Terminate and free as far as the FMI state machine allows; never raises.

        Healthy and initialised: ``fmi2Terminate`` then ``fmi2FreeInstance``.
        After an error status: ``fmi2FreeInstance`` only.  After a fatal
        status: no call at all (the instance is abandoned).
        """
        slave, state = self.slave, self._state
        self._state = "released"
        if slave is None or state in ("released", "fatal"):
            if self.instance_name is not None:
                fmilog.unregister(self.instance_name)
            return
        if state == "initialized":
            try:
                slave.terminate()
            except Exception:  # noqa: BLE001 - release must not raise
                state = "error"
        try:
            if state == "library":
                slave.freeLibrary()
            else:
                slave.freeInstance()
        except Exception:  # noqa: BLE001 - release must not raise
            pass
        self.slave = None
        fmilog.unregister(self.instance_name)
