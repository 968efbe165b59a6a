"""sarins: the application layer of sarins-fmu (command line, demo, campaigns,
the project's co-simulation systems).

Imports go one way: ``sarins`` -> ``fmus``, ``orchestration`` ->
``sarins_fmu``; the physics package ``sarins_fmu`` imports none of them.
"""

from sarins_fmu import __version__

__all__ = ["__version__"]
