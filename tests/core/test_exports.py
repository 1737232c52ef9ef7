"""The packages' lazy exports (visland.exports): each resolves, matches its TYPE_CHECKING import,
and the command line builds without the heavy libraries."""
from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

LAZY_PACKAGES = ("visland.detection", "visland.tracking", "visland.render")


@pytest.mark.parametrize("package_name", LAZY_PACKAGES)
def test_every_export_is_the_object_of_its_module(package_name):
    package = importlib.import_module(package_name)
    assert package.__all__, f"{package_name} exports nothing"
    for name, module_name in package._EXPORTS.items():
        defined = getattr(importlib.import_module(module_name), name)
        assert getattr(package, name) is defined, f"{package_name}.{name}"
        assert name in dir(package)
    with pytest.raises(AttributeError, match="no attribute 'not_an_export'"):
        getattr(package, "not_an_export")


@pytest.mark.parametrize("package_name", LAZY_PACKAGES)
def test_type_checking_block_names_the_same_exports(package_name):
    # "go to definition" reads the TYPE_CHECKING imports: they must be the exports, from the same modules
    package = importlib.import_module(package_name)
    tree = ast.parse(Path(package.__file__).read_text())
    imported = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for statement in node.body:
                for alias in statement.names:
                    imported[alias.asname or alias.name] = statement.module
    assert imported == package._EXPORTS


def test_building_the_command_line_loads_no_heavy_library():
    code = ("import sys, visland.cli; visland.cli.build_parser(); "
            "print(sorted(m for m in ('numpy', 'scipy', 'cv2', 'trimesh', 'pyrender', 'OpenGL', 'dask', "
            "'matplotlib', 'filterpy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
