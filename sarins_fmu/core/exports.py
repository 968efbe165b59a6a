"""The core's public C functions, by name, for linkers that export nothing unless told (MSVC).

GNU ld exports every non-static function of the shared library; MSVC's
linker exports only the names it is given (``setup.py`` passes this list as
``/EXPORT:`` options).  The list is every non-static ``sarins_*`` and ``sm_*`` (the
core's math, smath.h) function declared at the start of a line in the core's headers.  ``setup.py`` runs this file
without importing the package (which is not built yet), so it imports only
the standard library.
"""

from __future__ import annotations

import re
from pathlib import Path

# a declaration at the start of a line, not static (inline helpers): return type words and pointers,
# then sarins_name( or sm_name(
_PROTOTYPE = re.compile(r"^(?!static\b)[A-Za-z_][\w \t*]*?\b((?:sarins|sm)_\w+)\s*\(", re.MULTILINE)


def public_functions(core_dir: str | Path | None = None) -> list[str]:
    """Sorted names of the functions the core's headers declare (``core_dir``: default this folder)."""
    core = Path(core_dir) if core_dir is not None else Path(__file__).resolve().parent
    names: set[str] = set()
    for header in sorted(core.glob("*.h")):
        names.update(_PROTOTYPE.findall(header.read_text(encoding="utf-8")))
    return sorted(names)
