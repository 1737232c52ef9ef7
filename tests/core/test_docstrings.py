"""Public callables document every parameter in a numpydoc Parameters section (STYLE.md).

Checked: each package's exports (its ``__all__``), the command-line entry points (every public
function of the ``cli`` modules) and every public module of every package
(:data:`DOCUMENTED_PACKAGES`); ``python -m tests.helpers.numpydoc -v`` counts them per package
and names any parameter left undocumented.
"""
from __future__ import annotations

import importlib

import pytest

from tests.helpers.numpydoc import (PACKAGES, documented_parameters, public_callables, public_modules,
                                   undocumented_parameters)

EXPORTING_PACKAGES = ("visland.detection", "visland.tracking", "visland.render")

CLI_MODULES = ("visland.cli", "visland.footage_cli", "visland.render.cli", "visland.detection.cli",
               "visland.tracking.cli", "visland.estimation.cli", "visland.datasets.cli",
               "visland.datasets.generate_cli")

#: Every package documents every public function and class of every public module (a new module
#: is checked as soon as it exists).
DOCUMENTED_PACKAGES = PACKAGES


def _callables(module_names):
    for module_name in module_names:
        yield from public_callables(importlib.import_module(module_name))


def _package_callables(package_names):
    for package_name in package_names:
        for module in public_modules(package_name):
            yield from public_callables(module)


@pytest.mark.parametrize("qualname, obj", [
    *_callables(EXPORTING_PACKAGES), *_callables(CLI_MODULES), *_package_callables(DOCUMENTED_PACKAGES)],
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


# every observer's algorithm is cited: its module's docstring ends with a numpydoc References
# section naming the seed document it implements (STYLE.md: cite the seed equation or paper)

def _observer_modules():
    from visland.estimation.registry import OBSERVER_NAMES, make_observer
    return sorted({type(make_observer(name)).__module__ for name in OBSERVER_NAMES})


@pytest.mark.parametrize("module_name", _observer_modules())
def test_an_observer_module_cites_its_seed_in_a_references_section(module_name):
    import inspect
    import re
    lines = inspect.cleandoc(importlib.import_module(module_name).__doc__ or "").splitlines()
    assert "References" in lines and lines[lines.index("References") + 1].startswith("---"), (
        f"{module_name}: its docstring has no References section")
    references = "\n".join(lines[lines.index("References") + 2:])
    assert re.search(r"\(seeds? 00\d", references), f"{module_name}: its References name no seed document"
    assert re.search(r"[Ee]q\. ?\(?\d|[Aa]nnex \d", references), f"{module_name}: its References name no equation"
