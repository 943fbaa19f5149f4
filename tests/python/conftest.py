"""Fixtures for the Python module's tests: the bundled sample converted
once per run, and the sluice command for reference values.

The paths come from ctest (tests/CMakeLists.txt): a missing one fails the
run instead of skipping it."""
import os
import pathlib

import pytest


def _required(name):
    value = os.environ.get(name)
    if not value:
        raise RuntimeError(f"{name} is not set: run these tests through ctest (python.module)")
    return value


@pytest.fixture(scope="session")
def sluice_exe():
    exe = pathlib.Path(_required("SLUICE_EXE"))
    assert exe.is_file(), f"no sluice command at {exe}"
    return exe


@pytest.fixture(scope="session")
def sample_dir():
    d = pathlib.Path(_required("SLUICE_SAMPLE_DIR"))
    assert (d / "dam_break_3d.pvd").is_file(), f"the bundled sample is missing from {d}"
    return d


@pytest.fixture(scope="session")
def converted(tmp_path_factory, sample_dir):
    """The bundled PySPH dam break as .sluice, converted through the module."""
    import sluice

    out = tmp_path_factory.mktemp("sample") / "dam.sluice"
    sluice.convert(str(sample_dir / "dam_break_3d.pvd"), out, attributes=["rho", "p"])
    return out
