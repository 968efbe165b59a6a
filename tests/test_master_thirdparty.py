"""Third-party FMUs (OpenModelica-built) and third-party engines (Ecos, libcosim, FMPy's
container FMU) against the master, comparing like with like (scheme stated per test)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from fmu_fixtures.thirdparty import ensure_libtbb, has_module, openmodelica_fmus
from orchestration import (AlgebraicLoopWarning, Component, Connection, Master, System,
                           build_container_fmu, simulate_system, write_ssp)

pytestmark = pytest.mark.integration

EXACT = dict(rtol=1e-12, atol=1e-12)


@pytest.fixture(scope="session")
def om_fmus(request, tmp_path_factory):
    """OpenModelica-built FMUs shipped by the gemseo-fmu wheel (see fmu_fixtures.thirdparty)."""
    cache = getattr(request.config, "cache", None)
    folder = cache.mkdir("openmodelica_fmus") if cache is not None else \
        tmp_path_factory.mktemp("openmodelica_fmus")
    found = openmodelica_fmus(folder)
    if isinstance(found, str):
        pytest.skip(found)
    return found


@pytest.fixture(scope="session")
def ecospy_ready():
    if not has_module("ecospy"):
        pytest.skip("ecospy is not installed (it is in the test extra: pip install -e '.[test]')")
    reason = ensure_libtbb()
    if reason:
        pytest.skip(f"ecospy cannot load: {reason}")
    from orchestration.importers.ecos import load_ecospy

    return load_ecospy()


@pytest.fixture(scope="session")
def libcosimpy_ready():
    if not has_module("libcosimpy"):
        pytest.skip("libcosimpy is not installed (it is in the test extra)")


def mass_spring(om_fmus) -> System:
    """Two OpenModelica subsystems coupled both ways (a cycle)."""
    return System("mass_spring",
                  [Component("sub1", om_fmus["MassSpringSubSystem1"],
                             {"k1": 1.0, "k2": 2.0, "m1": 1.0}),
                   Component("sub2", om_fmus["MassSpringSubSystem2"],
                             {"k2": 2.0, "k3": 3.0, "m2": 2.0})],
                  [Connection.between("sub1.x1", "sub2.x1"),
                   Connection.between("sub2.x2", "sub1.x2")],
                  start_time=0.0, stop_time=2.0, step_size=0.01)


def quiet(function, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AlgebraicLoopWarning)
        return function(*args, **kwargs)


# --- OpenModelica FMUs under the master -------------------------------------------
def test_openmodelica_ramp_and_add_with_a_pythonfmu_source(om_fmus, fixture_fmus):
    system = System("mixed", [
        Component("om_ramp", om_fmus["ramp"], {"ramp.height": 2.0, "ramp.duration": 1.0}),
        Component("py_ramp", fixture_fmus["Ramp"], {"slope": 0.5}),
        Component("om_add", om_fmus["add"], {"add.k1": 1.0, "add.k2": -3.0})],
        [Connection.between("om_ramp.out", "om_add.u1"),
         Connection.between("py_ramp.y", "om_add.u2")])
    result = simulate_system(system, 2.0, 0.125, scheme="gauss-seidel")
    t = result["time"]
    om_ramp = 2.0 * np.clip(t, 0.0, 1.0)
    assert_allclose(result["om_ramp.out"], om_ramp, atol=1e-12)
    assert_allclose(result["om_add.y"][1:], (om_ramp - 3.0 * 0.5 * t)[1:], atol=1e-12)
    assert result.meta["order"] == ["om_ramp", "py_ramp", "om_add"]


def test_openmodelica_subsystems_jacobi_equal_the_monolithic_model(om_fmus):
    """The OpenModelica FMUs integrate with explicit Euler at the communication step, so
    the Jacobi coupling of the two halves is the monolithic Euler model, to round-off."""
    coupled = quiet(simulate_system, mass_spring(om_fmus), scheme="jacobi")
    whole = simulate_system(System("whole", [Component(
        "m", om_fmus["MassSpringSystem"], {"k1": 1.0, "k2": 2.0, "k3": 3.0, "m1": 1.0,
                                           "m2": 2.0})]), 2.0, 0.01)
    for name in ("x1", "v1"):
        assert_allclose(coupled[f"sub1.{name}"], whole[f"m.{name}"], **EXACT)
    for name in ("x2", "v2"):
        assert_allclose(coupled[f"sub2.{name}"], whole[f"m.{name}"], **EXACT)


def test_openmodelica_subsystems_gauss_seidel_breaks_the_loop(om_fmus):
    """x1 and x2 are state outputs (their declared dependencies hold no input): the cycle
    of components is cut in the stepping order, but it is no algebraic loop, so no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", AlgebraicLoopWarning)
        result = simulate_system(mass_spring(om_fmus), scheme="gauss-seidel")
    jacobi = quiet(simulate_system, mass_spring(om_fmus), scheme="jacobi")
    assert result.meta["broken_connections"] == ["sub2.x2 -> sub1.x2"]
    assert result.meta["algebraic_loop"] == []
    # sub1 steps first and reads sub2 at t in both schemes: same first step
    assert_allclose(result["sub1.x1"][:2], jacobi["sub1.x1"][:2], **EXACT)
    for name in ("sub1.x1", "sub2.x2"):
        assert not np.allclose(result[name], jacobi[name], rtol=1e-9)
        assert_allclose(result[name], jacobi[name], atol=0.05)


# --- Ecos (Jacobi) ---------------------------------------------------------------
@pytest.mark.parametrize("via", ["ssp", "structure"])
def test_ecos_equals_master_jacobi_on_pythonfmu_slaves(ecospy_ready, ramp_gain, tmp_path,
                                                       via):
    from orchestration.importers import simulate_with_ecos

    path = write_ssp(ramp_gain, tmp_path / "ramp_gain.ssp")
    ours = simulate_system(path, 2.0, 0.125, scheme="jacobi")
    theirs = simulate_with_ecos(path, 2.0, 0.125, via=via)
    assert theirs.meta["scheme"] == ours.meta["scheme"] == "jacobi"
    assert theirs.dtype == ours.dtype
    for name in ours.dtype.names:
        assert_allclose(theirs[name], ours[name], **EXACT, err_msg=name)


def test_ecos_equals_master_jacobi_on_openmodelica_fmus(ecospy_ready, om_fmus, tmp_path):
    from orchestration.importers import simulate_with_ecos

    path = write_ssp(mass_spring(om_fmus), tmp_path / "mass_spring.ssp")
    ours = quiet(simulate_system, path, scheme="jacobi")
    theirs = simulate_with_ecos(path)
    assert theirs.meta["via"] == "ssp"
    for name in ours.dtype.names:
        assert_allclose(theirs[name], ours[name], **EXACT, err_msg=name)


def test_ecos_is_jacobi_not_gauss_seidel(ecospy_ready, ramp_gain):
    from orchestration.importers import simulate_with_ecos

    theirs = simulate_with_ecos(ramp_gain, 1.0, 0.25)
    seidel = simulate_system(ramp_gain, 1.0, 0.25, scheme="gauss-seidel")
    assert not np.allclose(theirs["gain.y"], seidel["gain.y"])


# --- libcosim (Jacobi) -------------------------------------------------------------
def test_libcosim_equals_master_jacobi(libcosimpy_ready, om_fmus, fixture_fmus):
    from orchestration.importers import simulate_with_libcosim

    ours = quiet(simulate_system, mass_spring(om_fmus), scheme="jacobi")
    theirs = simulate_with_libcosim(mass_spring(om_fmus))
    assert theirs.meta["scheme"] == "jacobi"
    for name in ours.dtype.names:
        assert_allclose(theirs[name], ours[name][1:], **EXACT, err_msg=name)
    real_bool = System("rb", [Component("ramp", fixture_fmus["Ramp"], {"offset": -0.3}),
                              Component("gain", fixture_fmus["Gain"], {"k": 2.0})],
                       [Connection.between("ramp.y", "gain.u"),
                        Connection.between("ramp.positive", "gain.flag_in")])
    ours = quiet(simulate_system, real_bool, 1.0, 0.125, scheme="jacobi")
    theirs = simulate_with_libcosim(real_bool, 1.0, 0.125)
    for name in ("gain.y", "gain.x", "gain.flag_out", "ramp.y"):
        assert_array_equal(theirs[name], ours[name][1:], err_msg=name)


# --- FMPy container FMU (Jacobi, no initial output->input copy) --------------------
def test_container_fmu_of_openmodelica_subsystems(om_fmus, tmp_path):
    from fmpy import read_model_description, simulate_fmu

    system = mass_spring(om_fmus)
    fmu = build_container_fmu(write_ssp(system, tmp_path / "ms.ssp"), tmp_path / "ms.fmu")
    description = read_model_description(str(fmu))
    assert description.fmiVersion == "2.0" and description.coSimulation is not None
    outputs = ["sub1.x1", "sub1.v1", "sub2.x2", "sub2.v2"]
    theirs = simulate_fmu(str(fmu), stop_time=2.0, output_interval=0.01, output=outputs)
    ours = quiet(simulate_system, system, scheme="jacobi")
    for name in outputs:
        assert_allclose(theirs[name], ours[name], **EXACT, err_msg=name)
    # the same container runs under the master as a one-component system
    alone = simulate_system(System("c", [Component("box", fmu)]), 2.0, 0.01)
    assert_allclose(alone["box.sub2.x2"], ours["sub2.x2"], **EXACT)


def test_container_fmu_of_pythonfmu_slaves(ramp_gain, tmp_path):
    """The container copies connections at the start of each step but not after
    initialisation, so the gain's first step sees its input's start value (0)."""
    from fmpy import simulate_fmu

    fmu = build_container_fmu(ramp_gain, tmp_path / "rg.fmu", step_size=0.125)
    theirs = simulate_fmu(str(fmu), stop_time=1.0, output_interval=0.125,
                          output=["ramp.y", "gain.y", "gain.n_out"])
    ours = simulate_system(ramp_gain, 1.0, 0.125, scheme="jacobi")
    assert_allclose(theirs["ramp.y"], ours["ramp.y"], **EXACT)
    assert theirs["gain.y"][1] == 0.0
    assert_allclose(theirs["gain.y"][2:], ours["gain.y"][2:], **EXACT)
    assert_array_equal(theirs["gain.n_out"], ours["gain.n_out"])


def test_master_order_is_kept_when_rerun(om_fmus):
    with Master(mass_spring(om_fmus), scheme="jacobi") as master:
        first = master.simulate(0.5, 0.01)
        second = master.simulate(0.5, 0.01)
    assert_array_equal(first.view(np.ndarray), second.view(np.ndarray))


def test_missing_importers_say_what_to_install(monkeypatch, ramp_gain):
    import sys

    from orchestration import ImporterUnavailableError
    from orchestration.importers import simulate_with_ecos, simulate_with_libcosim

    monkeypatch.setitem(sys.modules, "ecospy", None)
    monkeypatch.setitem(sys.modules, "libcosimpy", None)
    with pytest.raises(ImporterUnavailableError, match="pip install ecospy"):
        simulate_with_ecos(ramp_gain, 1.0, 0.5)
    with pytest.raises(ImporterUnavailableError, match="pip install libcosimpy"):
        simulate_with_libcosim(ramp_gain, 1.0, 0.5)

