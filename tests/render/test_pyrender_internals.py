"""The pyrender internals that render/glview.py relies on are the ones it was written against.

glview.py subclasses pyrender's private ``Renderer`` (it overrides eight private methods, uses
private attributes, and swaps ``OffscreenRenderer._renderer`` for its own), subclasses
``Texture`` to upload its own mipmaps and ``Camera`` for an exact projection. None of this is
pyrender's public API, so pyproject.toml pins pyrender and PyOpenGL; these tests fail with one
clear sentence when the installed versions or those internals differ, before a render goes
subtly wrong. Nothing here needs an OpenGL context.

When pyrender must be upgraded: read the new pyrender's renderer.py, offscreen.py, texture.py
and camera.py against glview.py, rerun tests/render (byte-identical renders, labels within
half a pixel), then update the pins and the fingerprints below.
"""
import hashlib
import inspect
import re
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest

pyrender = pytest.importorskip("pyrender")
from pyrender.camera import Camera  # noqa: E402
from pyrender.offscreen import OffscreenRenderer  # noqa: E402
from pyrender.platforms.egl import EGLPlatform  # noqa: E402
from pyrender.renderer import Renderer  # noqa: E402
from pyrender.shader_program import ShaderProgram, ShaderProgramCache  # noqa: E402
from pyrender.texture import Texture  # noqa: E402

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"

#: sha256 (first 16 hex digits) of the source of each pyrender piece glview.py depends on, as
#: read in pyrender 0.1.45.
FINGERPRINTS = {
    "pyrender.renderer.Renderer": (Renderer, "4600c23137d5f7e6"),
    "pyrender.offscreen.OffscreenRenderer": (OffscreenRenderer, "5ddd2b7694081c0e"),
    "pyrender.texture.Texture._add_to_context": (Texture._add_to_context, "5bbf2597fb0fe575"),
    "pyrender.camera.Camera": (Camera, "6c3fb29306d45de5"),
    "pyrender.shader_program.ShaderProgramCache": (ShaderProgramCache, "b63dde8e06f200af"),
    # OffscreenView.close replaces it (it terminates the EGL display every view shares)
    "pyrender.platforms.egl.EGLPlatform.delete_context": (EGLPlatform.delete_context, "36b214582e059528"),
    # glview._cache_uniforms wraps it: a program's uniforms are set on the bound program only
    "pyrender.shader_program.ShaderProgram.set_uniform": (ShaderProgram.set_uniform, "760f2de731648eba"),
}

#: Renderer's private methods that glview._ColourRenderer overrides, with their parameters and
#: how Renderer itself calls them (an override that is never called would silently do nothing).
OVERRIDDEN = {
    "_configure_main_framebuffer": ("self", "self._configure_main_framebuffer()"),
    "_delete_main_framebuffer": ("self", "self._delete_main_framebuffer()"),
    "_configure_forward_pass_viewport": ("self, flags", "self._configure_forward_pass_viewport(flags)"),
    "_update_context": ("self, scene, flags", "self._update_context(scene, flags)"),
    "_get_primitive_program": ("self, primitive, flags, program_flags", "self._get_primitive_program("),
    "_get_camera_matrices": ("self, scene", "self._get_camera_matrices(scene)"),
    "_sorted_mesh_nodes": ("self, scene", "self._sorted_mesh_nodes(scene)"),
    "_read_main_framebuffer": ("self, scene, flags", "self._read_main_framebuffer(scene, flags)"),
}

HOW_TO_UPGRADE = ("render/glview.py overrides pyrender's private Renderer; review it against the installed "
                  "pyrender (see this file's docstring) before changing the pin")


def _pinned(name: str) -> str:
    dependencies = tomllib.loads(PYPROJECT.read_text())["project"]["dependencies"]
    pins = [d for d in dependencies if re.match(rf"{name}\s*==", d, re.IGNORECASE)]
    assert pins, f"pyproject.toml must pin {name} with '==' ({HOW_TO_UPGRADE})"
    return pins[0].split("==")[1].strip()


@pytest.mark.parametrize("name", ["pyrender", "PyOpenGL"])
def test_installed_versions_are_the_pinned_ones(name):
    assert version(name) == _pinned(name), (
        f"{name} {version(name)} is installed, glview.py was written for {name} {_pinned(name)}: {HOW_TO_UPGRADE}")


def test_the_overridden_private_methods_exist_and_are_called_as_glview_expects():
    from visland.render.glview import _make_renderer_class
    ours = _make_renderer_class()
    source = inspect.getsource(Renderer)
    for method, (parameters, call) in OVERRIDDEN.items():
        assert method in vars(ours), f"glview._ColourRenderer no longer overrides {method}: update this test's list"
        theirs = getattr(Renderer, method, None)
        assert theirs is not None, f"pyrender's Renderer has no {method} any more: {HOW_TO_UPGRADE}"
        signature = ", ".join(inspect.signature(theirs).parameters)
        assert signature == parameters, (
            f"pyrender's Renderer.{method}({signature}) is not ({parameters}) any more: {HOW_TO_UPGRADE}")
        assert call in source, f"pyrender's Renderer no longer calls {call}...: {HOW_TO_UPGRADE}"
    # glview's overrides read and write these attributes of the base renderer
    renderer = Renderer(8, 8)
    for attribute in ("_main_fb", "_main_cb", "_main_db", "_main_fb_ms", "_main_cb_ms", "_main_db_ms",
                      "_main_fb_dims", "_program_cache", "_mesh_textures", "viewport_width", "viewport_height"):
        assert hasattr(renderer, attribute), f"pyrender's Renderer has no attribute {attribute} any more: {HOW_TO_UPGRADE}"
    # OffscreenView swaps the offscreen renderer's private _renderer, made in _create with _platform
    create = inspect.getsource(OffscreenRenderer._create)
    assert "self._renderer = Renderer(" in create and "self._platform" in create, (
        f"pyrender's OffscreenRenderer no longer keeps its Renderer in _renderer: {HOW_TO_UPGRADE}")


@pytest.mark.parametrize("name", sorted(FINGERPRINTS))
def test_the_pyrender_sources_glview_depends_on_are_unchanged(name):
    obj, expected = FINGERPRINTS[name]
    found = hashlib.sha256(inspect.getsource(obj).encode()).hexdigest()[:16]
    assert found == expected, f"the source of {name} changed (fingerprint {found}, expected {expected}): {HOW_TO_UPGRADE}"
