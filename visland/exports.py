"""Package exports that load on first use (PEP 562): the one scheme every visland package uses.

Why: every ``visland`` command builds its parser from each stage's light ``cli`` module, which
imports its package's ``__init__``; an eager ``from .detector import detect_runway`` there would
load OpenCV, SciPy and NumPy for ``visland --help``. Measured on the reference machine (median
of 7 cold starts, ``/work/data/health/startup.sh``): ``visland --help`` 0.37 s when
``visland.detection`` imported ``DetectorParams`` (and with it NumPy) eagerly, against 0.06 s
for a bare ``python -c pass``.

A package lists its exports once, as ``{name: module}``, and repeats them under
``if TYPE_CHECKING:`` as plain imports, so that readers and editors ("go to definition") find
each name where it is defined::

    from typing import TYPE_CHECKING
    from visland.exports import lazy_exports

    if TYPE_CHECKING:
        from visland.detection.detector import detect_runway

    _EXPORTS = {"detect_runway": "visland.detection.detector"}
    __all__ = list(_EXPORTS)
    __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

``tests/core/test_exports.py`` checks that every export resolves to the object of that name
in its module, that the ``TYPE_CHECKING`` block names the same exports, and that building the
command line loads none of NumPy, OpenCV, SciPy, trimesh or pyrender.
"""
from __future__ import annotations

import importlib
import sys
from typing import Callable

__all__ = ["lazy_exports"]


def lazy_exports(package_name: str, exports: dict[str, str]) -> tuple[Callable, Callable]:
    """The module-level ``__getattr__`` and ``__dir__`` of a package with lazy exports.

    Parameters
    ----------
    package_name : str
        The package's ``__name__`` (for example ``"visland.detection"``).
    exports : dict of str to str
        Exported name -> absolute name of the module that defines it. A name is imported from
        its module on first access and then cached in the package's namespace, so later
        accesses cost nothing.

    Returns
    -------
    getattr : callable
        ``__getattr__(name)`` for the package: the exported object, or ``AttributeError``
        naming the package and the attribute.
    dir : callable
        ``__dir__()`` for the package: its globals and every export, sorted.
    """
    def __getattr__(name: str):
        module_name = exports.get(name)
        if module_name is None:
            raise AttributeError(f"module {package_name!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module_name), name)
        setattr(sys.modules[package_name], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package_name])) | set(exports))

    return __getattr__, __dir__
