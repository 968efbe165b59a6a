"""The C physics core: built by pip install, loaded through its ctypes binding."""

import ctypes

from sarins_fmu import core


def test_core_is_built_and_of_this_abi():
    path = core.library_path()
    assert path.is_file() and path.parent.name == "core"
    assert core.LIB.sarins_core_abi() == core.ABI


def test_core_links_no_python():
    # a plain C library: it loads with no Python module init and exports none
    lib = ctypes.CDLL(str(core.library_path()))
    assert not hasattr(lib, "PyInit__sarins_core")
