"""Which parameters of a public callable its numpydoc docstring documents (STYLE.md, numpydoc).

A parameter is documented when its name heads an entry of the docstring's ``Parameters``
section (``name : type``, or ``a, b : type`` for several); a class's parameters are those of its
constructor, documented in the class docstring (``Parameters``, or ``Attributes`` for a
dataclass whose fields are its constructor's parameters) or in ``__init__``'s, or in those of
a base class (every observer takes ``params`` as :class:`visland.estimation.base.Observer`
documents it). ``*args`` and
``**kwargs`` are not required. Used by ``tests/core/test_docstrings.py`` and by
``python -m tests.helpers.numpydoc`` (the counts per package).
"""
from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import sys
from dataclasses import is_dataclass

#: The packages of the public API, in dependency order.
PACKAGES = ("visland", "visland.render", "visland.detection", "visland.tracking", "visland.estimation",
            "visland.datasets")

_SECTION_RULE = re.compile(r"^\s*-{3,}\s*$")


def documented_parameters(docstring: str | None, sections=("Parameters", "Other Parameters")) -> set[str]:
    """The names heading entries of the ``sections`` of a numpydoc docstring."""
    if not docstring:
        return set()
    lines = inspect.cleandoc(docstring).splitlines()
    names: set[str] = set()
    inside = False
    for i, line in enumerate(lines):
        if i + 1 < len(lines) and _SECTION_RULE.match(lines[i + 1]) and line.strip():
            inside = line.strip() in sections
            continue
        if not inside or _SECTION_RULE.match(line) or not line.strip() or line.startswith((" ", "\t")):
            continue
        head = line.split(" : ", 1)[0].rstrip(":").strip()
        for name in head.split(","):
            names.add(name.strip().lstrip("*"))
    return names


def required_parameters(obj) -> list[str]:
    """The parameters a docstring must document: the signature's, less self/cls, *args, **kwargs."""
    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [name for name, parameter in signature.parameters.items()
            if name not in ("self", "cls")
            and parameter.kind not in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD)]


def undocumented_parameters(obj) -> list[str]:
    """The parameters of ``obj`` its docstring(s) do not document, in signature order.

    For a class, the docstrings of the class and of its bases (and of their ``__init__``) count:
    a parameter or field inherited from a documented base is documented.
    """
    if not inspect.isclass(obj):
        documented = documented_parameters(inspect.getdoc(obj))
    else:
        documented = set()
        for cls in obj.__mro__:
            if cls is object:
                continue
            sections = ("Parameters", "Other Parameters") + (("Attributes",) if is_dataclass(cls) else ())
            documented |= documented_parameters(cls.__doc__, sections)
            init = vars(cls).get("__init__")
            documented |= documented_parameters(getattr(init, "__doc__", None))
    return [name for name in required_parameters(obj) if name not in documented]


def public_callables(module) -> list[tuple[str, object]]:
    """The module's public functions and classes: its ``__all__``, else the public names it defines."""
    if hasattr(module, "__all__"):
        names = list(module.__all__)
    else:
        names = [name for name, value in vars(module).items()
                 if not name.startswith("_") and getattr(value, "__module__", None) == module.__name__]
    found = []
    for name in names:
        value = getattr(module, name)
        if inspect.isfunction(value) or inspect.isclass(value):
            found.append((f"{module.__name__}.{name}", value))
    return found


def public_modules(package_name: str) -> list:
    """The package and its public modules (no leading underscore), imported."""
    package = importlib.import_module(package_name)
    modules = [package]
    for info in pkgutil.iter_modules(package.__path__):
        if not info.name.startswith("_") and not info.ispkg:
            modules.append(importlib.import_module(f"{package_name}.{info.name}"))
    return modules


def main() -> int:
    """Print, per package, how many public callables with parameters document them all."""
    total_documented = total = 0
    seen = set()
    for package_name in PACKAGES:
        documented = count = 0
        for module in public_modules(package_name):
            for qualname, obj in public_callables(module):
                if id(obj) in seen or not required_parameters(obj):
                    continue
                seen.add(id(obj))
                count += 1
                missing = undocumented_parameters(obj)
                documented += not missing
                if missing and "-v" in sys.argv:
                    print(f"  {qualname}: {', '.join(missing)}")
        print(f"{package_name:22s} {documented:4d} of {count:4d} public callables with parameters document them all")
        total_documented += documented
        total += count
    print(f"{'all':22s} {total_documented:4d} of {total:4d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
