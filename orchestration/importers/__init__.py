"""Run a system under third-party co-simulation engines, for cross-checks.

Each importer takes the same system (SSP file or :class:`~orchestration.System`)
and returns a :class:`~orchestration.recorder.ResultArray` shaped like the
master's (``time`` then ``component.variable`` fields) whose ``meta`` names
the tool and the coupling scheme it uses.

- :func:`simulate_with_ecos` - Ecos (``ecospy``), Jacobi: its
  ``fixed_step_algorithm`` steps every model (in parallel) on inputs set
  before the step.
- :func:`simulate_with_libcosim` - libcosim (``libcosimpy``, Open
  Simulation Platform), Jacobi as well.
"""
from .ecos import simulate_with_ecos
from .libcosim import simulate_with_libcosim

__all__ = ["simulate_with_ecos", "simulate_with_libcosim"]
