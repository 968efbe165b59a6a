"""Pytest fixtures shared by the master's test modules (import them by name)."""
from __future__ import annotations

import pytest

from .building import build_fixture_fmus, build_fmi3_fixture_fmus


@pytest.fixture(scope="session")
def fixture_fmus(tmp_path_factory) -> dict:
    """``{'Ramp': path, 'Gain': path, 'Faulty': path, 'Feed': path, ...}`` built once per session."""
    return build_fixture_fmus(tmp_path_factory.getbasetemp() / "fixture_fmus")


@pytest.fixture()
def ramp_gain(fixture_fmus):
    """A ramp (slope 2, offset 1) feeding a gain (k 3) on all three value types."""
    from orchestration import Component, Connection, System

    return System("ramp_gain",
                  [Component("ramp", fixture_fmus["Ramp"], {"slope": 2.0, "offset": 1.0}),
                   Component("gain", fixture_fmus["Gain"], {"k": 3.0})],
                  [Connection.between("ramp.y", "gain.u"),
                   Connection.between("ramp.count", "gain.n_in"),
                   Connection.between("ramp.positive", "gain.flag_in")])


@pytest.fixture(scope="session")
def fmi3_fmus(tmp_path_factory) -> dict:
    """``{'Burst3': path, 'Sum3': path}``: the FMI 3.0 C fixtures, compiled once per session
    (the tests using them are skipped where gcc is missing)."""
    import subprocess

    try:
        return build_fmi3_fixture_fmus(tmp_path_factory.getbasetemp() / "fmi3_fixture_fmus")
    except FileNotFoundError as error:
        pytest.skip(f"FMI 3.0 fixtures not built: {error}")
    except subprocess.CalledProcessError as error:
        raise RuntimeError(f"FMI 3.0 fixtures do not compile:\n{error.stderr}") from None
