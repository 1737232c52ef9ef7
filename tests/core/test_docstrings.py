"""Public callables document every parameter in a numpydoc Parameters section (STYLE.md).

Checked: each package's exports (its ``__all__``), the command-line entry points (every public
function of the ``cli`` modules), every public module of the packages in
:data:`DOCUMENTED_PACKAGES`, and the modules in :data:`DOCUMENTED_MODULES` (add a module once it
is documented, a package once all its modules are). ``python -m tests.helpers.numpydoc -v``
lists what the rest of the tree still lacks.
"""
from __future__ import annotations

import importlib

import pytest

from tests.helpers.numpydoc import documented_parameters, public_callables, public_modules, undocumented_parameters

EXPORTING_PACKAGES = ("visland.detection", "visland.tracking", "visland.render")

CLI_MODULES = ("visland.cli", "visland.footage_cli", "visland.render.cli", "visland.detection.cli",
               "visland.tracking.cli", "visland.estimation.cli", "visland.datasets.cli",
               "visland.datasets.generate_cli")

#: Packages whose every public module documents every public function and class (a new module
#: of theirs is checked as soon as it exists).
DOCUMENTED_PACKAGES = ("visland", "visland.render", "visland.detection", "visland.tracking", "visland.estimation")

#: Modules, in the packages not yet documented throughout, whose whole public API is documented.
DOCUMENTED_MODULES = ("visland.datasets.batch", "visland.datasets.compare", "visland.datasets.generate",
                      "visland.datasets.lard", "visland.datasets.measure", "visland.datasets.pixel_errors",
                      "visland.datasets.process", "visland.datasets.report", "visland.datasets.sources",
                      "visland.datasets.stream")


def _callables(module_names):
    for module_name in module_names:
        yield from public_callables(importlib.import_module(module_name))


def _package_callables(package_names):
    for package_name in package_names:
        for module in public_modules(package_name):
            yield from public_callables(module)


@pytest.mark.parametrize("qualname, obj", [
    *_callables(EXPORTING_PACKAGES), *_callables(CLI_MODULES), *_package_callables(DOCUMENTED_PACKAGES),
    *_callables(DOCUMENTED_MODULES)],
    ids=lambda value: value if isinstance(value, str) else "")
def test_public_callable_documents_its_parameters(qualname, obj):
    missing = undocumented_parameters(obj)
    assert not missing, f"{qualname}: no numpydoc Parameters entry for {', '.join(missing)}"


# the checker itself, on docstrings whose answer is known

def _documented(a, b_m, c=None):
    """Summary.

    Parameters
    ----------
    a, b_m : float
        Two at once.
    c : str, optional
        Mentioned ``a`` here does not count twice.

    Returns
    -------
    x : float
        Not a parameter.
    """


def _prose_only(height_m, roll_rad):
    """Uses ``height_m`` and ``roll_rad`` but has no Parameters section."""


def _one_missing(height_m, roll_rad, *args, **kwargs):
    """Summary.

    Parameters
    ----------
    height_m : float
        Metres.
    """


def test_the_checker_finds_undocumented_parameters():
    assert undocumented_parameters(_documented) == []
    assert undocumented_parameters(_prose_only) == ["height_m", "roll_rad"]
    assert undocumented_parameters(_one_missing) == ["roll_rad"]      # *args, **kwargs not required
    assert documented_parameters(_documented.__doc__) == {"a", "b_m", "c"}     # "x" is under Returns


def test_the_checker_reads_a_dataclass_attributes_section():
    from dataclasses import dataclass

    @dataclass
    class Record:
        """Summary.

        Attributes
        ----------
        t_s : float
            Seconds.
        """
        t_s: float
        v_mps: float

    assert undocumented_parameters(Record) == ["v_mps"]


def test_the_checker_takes_an_inherited_constructors_documentation():
    class Base:
        """Summary.

        Parameters
        ----------
        params : dict, optional
            Documented once, here.
        """

        def __init__(self, params=None):
            self.params = params

    class Child(Base):
        """Inherits the constructor."""

    class Extended(Base):
        """Adds a parameter it does not document."""

        def __init__(self, params=None, gain=1.0):
            super().__init__(params)

    assert undocumented_parameters(Child) == []
    assert undocumented_parameters(Extended) == ["gain"]
