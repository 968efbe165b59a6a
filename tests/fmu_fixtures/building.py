"""Build the fixture FMUs once per session: the FMI 2.0 slaves with ``pythonfmu build``,
the FMI 3.0 ones (``fmi3/``, C) with the system C compiler."""
from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

HERE = Path(__file__).parent
SLAVES = ("Ramp", "Gain", "Faulty", "Feed")
FMI3_MODELS = {"Burst3": "burst3.c", "Sum3": "sum3.c"}  # FMU name -> model source in fmi3/
C_FLAGS = ("-std=c11", "-shared", "-fPIC", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror")


def build_fixture_fmus(destination: Path) -> dict[str, Path]:
    """Build every fixture slave into ``destination``; reuse FMUs already there.

    Returns
    -------
    dict
        ``{slave name: FMU path}``, plus ``'RampFixedStep'``: the Ramp built
        with ``canHandleVariableCommunicationStepSize=false``.
    """
    destination.mkdir(parents=True, exist_ok=True)
    fmus = {}
    for name in SLAVES:
        fmu = destination / f"{name}.fmu"
        if not fmu.is_file():
            subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f",
                            str(HERE / f"{name}.py"), "-d", str(destination)],
                           check=True, capture_output=True, cwd=destination)
        fmus[name] = fmu
    fixed = destination / "fixed_step" / "Ramp.fmu"
    if not fixed.is_file():
        fixed.parent.mkdir(exist_ok=True)
        subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f",
                        str(HERE / "Ramp.py"), "-d", str(fixed.parent), "--no-variable-step"],
                       check=True, capture_output=True, cwd=fixed.parent)
    fmus["RampFixedStep"] = fixed
    return fmus


def fmi3_headers() -> Path:
    """The folder of the FMI 3.0 headers FMPy ships (``fmi3Functions.h``, ...)."""
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def build_fmi3_fixture_fmus(destination: Path, compiler: str = "gcc") -> dict[str, Path]:
    """Compile the FMI 3.0 fixtures (glue3.c + model) into FMUs in ``destination``.

    Each FMU holds ``modelDescription.xml`` and ``binaries/<FMPy's platform tuple>/<name>.so``
    built with ``compiler`` and :data:`C_FLAGS`; FMUs already there are reused.

    Raises
    ------
    FileNotFoundError
        If ``compiler`` is not on the PATH.
    subprocess.CalledProcessError
        If a fixture does not compile.
    """
    from fmpy import platform_tuple, sharedLibraryExtension

    if shutil.which(compiler) is None:
        raise FileNotFoundError(f"C compiler '{compiler}' not found")
    destination.mkdir(parents=True, exist_ok=True)
    source = HERE / "fmi3"
    fmus = {}
    for name, model in FMI3_MODELS.items():
        fmu = destination / f"{name}.fmu"
        if not fmu.is_file():
            library = destination / "build" / f"{name}{sharedLibraryExtension}"
            library.parent.mkdir(exist_ok=True)
            subprocess.run([compiler, *C_FLAGS, f"-I{fmi3_headers()}", str(source / "glue3.c"),
                            str(source / model), "-o", str(library), "-lm"],
                           check=True, capture_output=True, text=True)
            partial = fmu.with_suffix(".part")
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
                archive.write(source / f"{name}.xml", "modelDescription.xml")
                archive.write(library, f"binaries/{platform_tuple}/{name}{sharedLibraryExtension}")
            partial.replace(fmu)
        fmus[name] = fmu
    return fmus
