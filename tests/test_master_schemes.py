"""Coupling schemes on FMUs with true direct feedthrough: strict Jacobi, Gauss-Seidel order
from declared output dependencies, algebraic loops only where they are real."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from fmu_fixtures.fixtures import fixture_fmus  # noqa: F401 (fixture)
from orchestration import (AlgebraicLoopWarning, Component, Connection, Master, System,
                           simulate_system)

pytestmark = pytest.mark.integration

H, STOP, K1, K2 = 0.25, 2.0, 2.0, 3.0


def chain(fmus) -> System:
    """ramp (y = t) -> f1 (y = 2 u, read-time feedthrough) -> f2 (y = 3 u)."""
    return System("chain", [Component("ramp", fmus["Ramp"], {"slope": 1.0}),
                            Component("f1", fmus["Feed"], {"k": K1}),
                            Component("f2", fmus["Feed"], {"k": K2})],
                  [Connection.between("ramp.y", "f1.u"), Connection.between("f1.y", "f2.u")])


def lag_in_steps(result, name: str, gain: float) -> int:
    """The L for which ``name`` at row n equals gain * ramp at row n - L (rows n >= 3)."""
    t, y = result["time"], result[name]
    for lag in range(4):
        if np.allclose(y[3:], gain * t[3 - lag:t.size - lag], rtol=0, atol=1e-12):
            return lag
    raise AssertionError(f"{name}: no lag of 0..3 steps fits")


def test_two_feedthrough_links_lag_two_steps_under_jacobi_and_none_under_gauss_seidel(
        fixture_fmus):
    with Master(chain(fixture_fmus), scheme="jacobi",
                record=["ramp.y", "f1.y", "f2.y"]) as master:
        jacobi = master.simulate(STOP, H)
    seidel = simulate_system(chain(fixture_fmus), STOP, H, scheme="gauss-seidel",
                             record=["ramp.y", "f1.y", "f2.y"])
    assert_allclose(jacobi["ramp.y"], jacobi["time"])
    assert lag_in_steps(jacobi, "f1.y", K1) == 1
    assert lag_in_steps(jacobi, "f2.y", K1 * K2) == 2  # was 1: links read and set one by one
    assert lag_in_steps(seidel, "f1.y", K1) == 0
    assert lag_in_steps(seidel, "f2.y", K1 * K2) == 0
    assert jacobi.meta["algebraic_loop"] == seidel.meta["algebraic_loop"] == []


def test_cycle_through_a_state_output_is_no_algebraic_loop(fixture_fmus):
    """f1.y depends on f1.u; f2.x is a state: the cycle f1 -> f2 -> f1 is cut at f2, which
    is stepped first, and f1 then reads f2's state of the same instant."""
    system = System("state_cycle", [Component("f1", fixture_fmus["Feed"], {"k": K1, "b": 1.0}),
                                    Component("f2", fixture_fmus["Feed"])],
                    [Connection.between("f1.y", "f2.u"), Connection.between("f2.x", "f1.u")])
    with warnings.catch_warnings():
        warnings.simplefilter("error", AlgebraicLoopWarning)
        result = simulate_system(system, 1.0, H, record=["f1.u", "f1.y", "f2.x"])
    assert result.meta["order"] == ["f2", "f1"]
    assert result.meta["broken_connections"] == ["f1.y -> f2.u"]
    assert result.meta["algebraic_loop"] == []
    assert_array_equal(result["f1.u"], result["f2.x"])
    assert_allclose(result["f1.y"], K1 * result["f1.u"] + 1.0)
    # x' = 2 x + 1 with f1.y read at the start of each step: x_n = ((1 + 2 h)^n - 1) / 2
    n = np.arange(result.size)
    assert_allclose(result["f2.x"], ((1.0 + K1 * H) ** n - 1.0) / 2.0, rtol=1e-14)


def test_cycle_through_feedthrough_outputs_is_an_algebraic_loop(fixture_fmus):
    system = System("loop", [Component("f1", fixture_fmus["Feed"], {"k": 0.5}),
                             Component("f2", fixture_fmus["Feed"], {"k": 0.5})],
                    [Connection.between("f1.y", "f2.u"), Connection.between("f2.y", "f1.u")])
    with pytest.warns(AlgebraicLoopWarning, match=r"f1\.y -> f2\.u.*f2 -> f1"):
        master = Master(system)
    with master:
        result = master.simulate(0.5, H)
    assert sorted(result.meta["algebraic_loop"]) == ["f1.y -> f2.u", "f2.y -> f1.u"]
