"""The one place where OpenCV camera conventions meet OpenGL, and the offscreen GL view.

Conventions (SPEC.md, :mod:`visland.camera`): camera frame C is OpenCV's (x right, y down, z
along the optical axis); pixels ``(u, v)`` have ``(0, 0)`` at the *centre* of the top-left pixel.
OpenGL differs twice:

- its camera frame G looks along -z with y up: ``p_G = diag(1, -1, -1) p_C``;
- its window coordinates put pixel centres at half-integers: the centre of column ``u`` is at
  ``x_window = u + 0.5``.

:func:`gl_projection_matrix` folds both into one matrix. We also render the image upside
down relative to OpenGL's habit (window row 0 is image row 0), so ``glReadPixels`` returns
rows in image order with no flip and no copy: ``y_window = v + 0.5``. Derivation, with
``w_clip = -Z_G = Z_C``::

    x_ndc = 2 (u + 0.5) / W - 1,   u = fx X_C / Z_C + cx
          = (2 fx / W) X_C / Z_C + (2 cx + 1) / W - 1
    x_ndc = P00 X_G / w + P02 Z_G / w = P00 X_C / Z_C - P02
    =>  P00 = 2 fx / W,   P02 = 1 - (2 cx + 1) / W
    y_ndc = 2 (v + 0.5) / H - 1,   v = fy Y_C / Z_C + cy,   Y_G = -Y_C
    =>  P11 = -2 fy / H,  P12 = 1 - (2 cy + 1) / H

(pyrender's own ``IntrinsicsCamera`` omits the half pixel and flips rows in numpy instead).
Flipping y reverses the winding of every triangle on screen, so the view culls clockwise
faces as back faces.

:class:`OffscreenView` owns one EGL context (pyrender's ``OffscreenRenderer``) with a renderer
that reads back colour only (no depth readback, no numpy flip), with a chosen number of MSAA
samples and anisotropic texture filtering, and that draws with visland's shaders.
"""
from __future__ import annotations

import os

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # must precede the first OpenGL import

import numpy as np

from visland.camera import CameraModel

__all__ = [
    "RenderingUnavailable",
    "gl_projection_matrix",
    "gl_camera_pose",
    "gl_view_matrix",
    "make_texture",
    "mipmap_chain",
    "check_opengl",
    "OffscreenView",
    "EGL_INSTALL_HINT",
]

EGL_INSTALL_HINT = ("install Mesa's EGL and software OpenGL driver, on Debian: "
                    "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0")

#: p_G = _G_FROM_C @ p_C (OpenGL camera axes from OpenCV camera axes).
_G_FROM_C = np.diag([1.0, -1.0, -1.0])
#: GL_TEXTURE_MAX_ANISOTROPY (core in OpenGL 4.6; PyOpenGL 3.1.0 does not name it).
_GL_TEXTURE_MAX_ANISOTROPY = 0x84FE


class RenderingUnavailable(ValueError):
    """No usable EGL/OpenGL on this machine (one sentence naming the library and the fix)."""


def gl_projection_matrix(camera: CameraModel, znear_m: float, zfar_m: float) -> np.ndarray:
    """OpenGL projection matrix (4, 4) reproducing ``camera``'s pixels exactly.

    See the module docstring for the derivation. The image is produced with row 0 at the
    top, so a point projecting to pixel ``(u, v)`` with :meth:`CameraModel.project` lands on
    the pixel whose centre is ``(u, v)`` in the array returned by :class:`OffscreenView`.

    Parameters
    ----------
    camera : CameraModel
        Intrinsics and image size.
    znear_m, zfar_m : float
        Near and far clipping distances along the optical axis, ``0 < znear_m < zfar_m``.
    """
    if not (np.isfinite(znear_m) and np.isfinite(zfar_m) and 0.0 < znear_m < zfar_m):
        raise ValueError(f"znear_m and zfar_m must satisfy 0 < znear_m < zfar_m, got {znear_m!r}, {zfar_m!r}")
    W, H = camera.width, camera.height
    P = np.zeros((4, 4))
    P[0, 0] = 2.0 * camera.fx / W
    P[0, 2] = 1.0 - (2.0 * camera.cx + 1.0) / W
    P[1, 1] = -2.0 * camera.fy / H
    P[1, 2] = 1.0 - (2.0 * camera.cy + 1.0) / H
    P[2, 2] = -(zfar_m + znear_m) / (zfar_m - znear_m)
    P[2, 3] = -2.0 * zfar_m * znear_m / (zfar_m - znear_m)
    P[3, 2] = -1.0
    return P


def gl_camera_pose(p_runway_m, R_camera_from_runway) -> np.ndarray:
    """``T_runway_from_G`` (4, 4): the pose pyrender wants for a camera node in the runway frame.

    Parameters
    ----------
    p_runway_m : (3,) camera centre in the runway frame R.
    R_camera_from_runway : (3, 3) rotation from R to the OpenCV camera frame C.
    """
    p = np.asarray(p_runway_m, dtype=float).reshape(-1)
    R_cr = np.asarray(R_camera_from_runway, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"p_runway_m must be 3 finite numbers, got {p_runway_m!r}")
    if R_cr.shape != (3, 3) or not np.all(np.isfinite(R_cr)):
        raise ValueError(f"R_camera_from_runway must be a finite 3x3 matrix, got shape {R_cr.shape}")
    if not np.allclose(R_cr @ R_cr.T, np.eye(3), atol=1e-6) or np.linalg.det(R_cr) < 0:
        raise ValueError("R_camera_from_runway must be a rotation matrix (orthonormal, determinant +1)")
    T = np.eye(4)
    T[:3, :3] = R_cr.T @ _G_FROM_C.T          # R_runway_from_G = R_runway_from_camera R_C_from_G
    T[:3, 3] = p
    return T


def gl_view_matrix(p_runway_m, R_camera_from_runway) -> np.ndarray:
    """``T_G_from_runway`` (4, 4): the OpenGL view matrix, computed element by element.

    ``R_G_from_runway = diag(1, -1, -1) R_camera_from_runway`` and ``t = -R_G_from_runway p``
    (OpenGL's camera looks along -z with y up; OpenCV's along +z with y down).
    Written without BLAS or LAPACK so that every process gets the same bits (their SIMD paths
    depend on memory alignment), which keeps resumed datasets byte-identical.

    Parameters
    ----------
    p_runway_m : array_like, shape (3,)
        Camera centre in the runway frame R, metres.
    R_camera_from_runway : array_like, shape (3, 3)
        Rotation from R to the OpenCV camera frame.

    Returns
    -------
    ndarray, shape (4, 4)
    """
    p = [float(v) for v in np.asarray(p_runway_m, dtype=float).reshape(3)]
    R = np.asarray(R_camera_from_runway, dtype=float)
    V = np.zeros((4, 4))
    for i, sign in enumerate((1.0, -1.0, -1.0)):
        row = [sign * float(R[i, j]) for j in range(3)]
        V[i, :3] = row
        V[i, 3] = -((row[0] * p[0] + row[1] * p[1]) + row[2] * p[2])
    V[3, 3] = 1.0
    return V


def check_opengl(libraries=("libEGL.so.1", ("libOpenGL.so.0", "libGL.so.1"))) -> None:
    """Raise :class:`RenderingUnavailable` if the EGL and OpenGL system libraries cannot be loaded.

    Checked with ctypes, before PyOpenGL touches them (importing ``OpenGL.EGL`` ahead of
    pyrender's EGL platform breaks PyOpenGL 3.1).

    Parameters
    ----------
    libraries : sequence
        Each entry a library file name, or a tuple of alternatives of which one must load.
    """
    import ctypes
    if os.environ.get("PYOPENGL_PLATFORM", "egl") != "egl":
        return
    for entry in libraries:
        names = entry if isinstance(entry, tuple) else (entry,)
        errors = []
        for name in names:
            try:
                ctypes.CDLL(name)
                break
            except OSError as error:
                errors.append(str(error))
        else:
            raise RenderingUnavailable(
                f"no usable EGL: the system library {' or '.join(names)} could not be loaded "
                f"({errors[0]}); {EGL_INSTALL_HINT}")


def _make_renderer_class():
    """Subclass pyrender's Renderer (imported lazily: OpenGL must not load at import time)."""
    from OpenGL import GL
    from pyrender.renderer import Renderer

    class _ColourRenderer(Renderer):
        """pyrender's forward renderer with visland's shaders, colour-only readback and chosen MSAA."""

        def __init__(self, width, height, shader_dir, samples, anisotropy):
            super().__init__(width, height)
            from pyrender.shader_program import ShaderProgramCache
            self._program_cache = ShaderProgramCache(shader_dir=shader_dir)
            self.samples = int(samples)
            self.anisotropy = float(anisotropy)
            self._anisotropic_ids = set()
            self._rgba = np.empty((height, width, 4), dtype=np.uint8)

        # framebuffer: single-sample colour + depth, plus a multisample one when samples > 0
        def _configure_main_framebuffer(self):
            if self._main_fb is not None:
                return
            w, h = self.viewport_width, self.viewport_height
            self._main_cb, self._main_db = GL.glGenRenderbuffers(2)
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._main_cb)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_RGBA8, w, h)
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._main_db)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT24, w, h)
            self._main_fb = GL.glGenFramebuffers(1)
            GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._main_fb)
            GL.glFramebufferRenderbuffer(GL.GL_DRAW_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER,
                                         self._main_cb)
            GL.glFramebufferRenderbuffer(GL.GL_DRAW_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER,
                                         self._main_db)
            if self.samples > 0:
                self._main_cb_ms, self._main_db_ms = GL.glGenRenderbuffers(2)
                GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._main_cb_ms)
                GL.glRenderbufferStorageMultisample(GL.GL_RENDERBUFFER, self.samples, GL.GL_RGBA8, w, h)
                GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._main_db_ms)
                GL.glRenderbufferStorageMultisample(GL.GL_RENDERBUFFER, self.samples, GL.GL_DEPTH_COMPONENT24,
                                                    w, h)
                self._main_fb_ms = GL.glGenFramebuffers(1)
                GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._main_fb_ms)
                GL.glFramebufferRenderbuffer(GL.GL_DRAW_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0,
                                             GL.GL_RENDERBUFFER, self._main_cb_ms)
                GL.glFramebufferRenderbuffer(GL.GL_DRAW_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT,
                                             GL.GL_RENDERBUFFER, self._main_db_ms)
            else:
                self._main_fb_ms = self._main_fb
            status = GL.glCheckFramebufferStatus(GL.GL_DRAW_FRAMEBUFFER)
            if status != GL.GL_FRAMEBUFFER_COMPLETE:
                raise RenderingUnavailable(f"the OpenGL framebuffer of {w}x{h} px with {self.samples} MSAA samples "
                                           f"is incomplete (status {status}); try fewer samples")
            self._main_fb_dims = (w, h)

        def _delete_main_framebuffer(self):
            fbs = {fb for fb in (self._main_fb, self._main_fb_ms) if fb is not None}
            if fbs:
                GL.glDeleteFramebuffers(len(fbs), list(fbs))
            rbs = [rb for rb in (self._main_cb, self._main_db, self._main_cb_ms, self._main_db_ms) if rb is not None]
            if rbs:
                GL.glDeleteRenderbuffers(len(rbs), rbs)
            self._main_fb = self._main_cb = self._main_db = None
            self._main_fb_ms = self._main_cb_ms = self._main_db_ms = None
            self._main_fb_dims = (None, None)

        def _configure_forward_pass_viewport(self, flags):
            super()._configure_forward_pass_viewport(flags)
            # rows are rendered top-first (see module docstring): screen winding is mirrored
            GL.glFrontFace(GL.GL_CW)

        def _update_context(self, scene, flags):
            super()._update_context(scene, flags)
            if self.anisotropy > 1.0:  # hardware anisotropic filtering (slow on llvmpipe), off by default
                for texture in self._mesh_textures:
                    if texture._texid is not None and texture._texid not in self._anisotropic_ids:
                        GL.glBindTexture(GL.GL_TEXTURE_2D, texture._texid)
                        GL.glTexParameterf(GL.GL_TEXTURE_2D, _GL_TEXTURE_MAX_ANISOTROPY, self.anisotropy)
                        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
                        self._anisotropic_ids.add(texture._texid)

        def _get_primitive_program(self, primitive, flags, program_flags):
            # pyrender's choice of defines, plus one naming the surface kind (material.name,
            # e.g. "KIND_SKY"): each kind compiles to its own straight-line shader instead of
            # llvmpipe evaluating every branch for every pixel
            from pyrender.constants import BufFlags, TexFlags
            defines = {}
            location = 1
            for flag, name in ((BufFlags.NORMAL, "NORMAL_LOC"), (BufFlags.TANGENT, "TANGENT_LOC"),
                               (BufFlags.TEXCOORD_0, "TEXCOORD_0_LOC"), (BufFlags.TEXCOORD_1, "TEXCOORD_1_LOC"),
                               (BufFlags.COLOR_0, "COLOR_0_LOC"), (BufFlags.JOINTS_0, "JOINTS_0_LOC"),
                               (BufFlags.WEIGHTS_0, "WEIGHTS_0_LOC")):
                if primitive.buf_flags & flag:
                    defines[name] = location
                    location += 1
            defines["INST_M_LOC"] = location
            material = primitive.material
            for flag, name in ((TexFlags.BASE_COLOR, "HAS_BASE_COLOR_TEX"), (TexFlags.EMISSIVE, "HAS_EMISSIVE_TEX")):
                if material.tex_flags & flag:
                    defines[name] = 1
            kind = material.name if material.name and material.name.startswith("KIND_") else "KIND_GROUND"
            defines[kind] = 1
            program = self._program_cache.get_program(vertex_shader="flat.vert", fragment_shader="flat.frag",
                                                      defines=defines)
            if not program._in_context():
                program._add_to_context()
                if hasattr(program, "_visland_uniforms"):
                    program._visland_uniforms.clear()      # a new GL program: nothing held yet
            if not hasattr(program, "_visland_uniforms"):
                _cache_uniforms(program)
            return program

        def _get_camera_matrices(self, scene):
            # pyrender inverts the camera pose with LAPACK, whose last bits vary with memory
            # alignment from process to process; the exact inverse is set by OffscreenView
            P = scene.main_camera_node.camera.get_projection_matrix(self.viewport_width, self.viewport_height)
            return self.view_matrix, P

        def _sorted_mesh_nodes(self, scene):
            # pyrender iterates a set (order varies between processes); where clipped neighbour
            # triangles meet, the draw order decides an edge pixel: draw in name order so that
            # every process renders the same bytes
            return sorted(scene.mesh_nodes, key=lambda node: node.name or "")

        def _read_main_framebuffer(self, scene, flags):
            w, h = self._main_fb_dims
            if self.samples > 0:
                GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._main_fb_ms)
                GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self._main_fb)
                GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT, GL.GL_NEAREST)
            GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self._main_fb)
            GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
            # RGBA is the framebuffer's own layout (a straight copy in llvmpipe); RGB would be
            # converted pixel by pixel, three times slower
            GL.glReadPixels(0, 0, w, h, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, self._rgba)
            import cv2
            return cv2.cvtColor(self._rgba, cv2.COLOR_RGBA2RGB)

    return _ColourRenderer


def _destroy_context_only(platform) -> None:
    """Make pyrender's EGL ``platform`` destroy its context without terminating the shared
    display (:meth:`OffscreenView.close`); other platforms are left as they are."""
    if not hasattr(platform, "_egl_display"):
        return

    def delete_context():
        from OpenGL.EGL import EGL_NO_CONTEXT, EGL_NO_SURFACE, eglDestroyContext, eglMakeCurrent
        if platform._egl_display is not None and platform._egl_context is not None:
            eglMakeCurrent(platform._egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)
            eglDestroyContext(platform._egl_display, platform._egl_context)
        platform._egl_context = None
        platform._egl_display = None

    platform.delete_context = delete_context


def _cache_uniforms(program) -> None:
    """Make ``program.set_uniform`` skip a value the program already holds.

    pyrender sets the camera matrices, the model matrix and every material uniform for every
    primitive of every frame, and each ``set_uniform`` asks the driver for the uniform's location
    first: on visland's scene (66 primitives, about 10 uniforms each) that was 0.65 million
    calls and 33 ms per 512 px frame on this machine, 40 % of the rendering (cProfile of a
    ``fly --measure detection`` flight). A GL program keeps its uniform values until they are set
    again, so a value equal, byte for byte, to the one this program was last given is not sent;
    the frames are the same bytes.
    """
    held = {}
    set_uniform = program.set_uniform

    def set_uniform_if_changed(name, value, unsigned=False):
        if isinstance(value, np.ndarray):
            key = (value.dtype.str, value.shape, value.tobytes(), unsigned)
        else:
            key = (type(value), value, unsigned)
        if held.get(name) == key:
            return
        set_uniform(name, value, unsigned)
        held[name] = key

    program.set_uniform = set_uniform_if_changed
    program._visland_uniforms = held


def mipmap_chain(image: np.ndarray) -> list:
    """Mipmap levels of ``image`` down to 1x1, by area averaging.

    Computed here rather than by ``glGenerateMipmap``, whose llvmpipe results differ from one
    process to the next (and would break byte-identical datasets). Level ``k`` has the OpenGL
    size ``max(1, floor(size / 2^k))``.

    Parameters
    ----------
    image : ndarray, shape (rows, cols, channels), uint8
        Level 0.

    Returns
    -------
    list of ndarray
        Level 0 first.
    """
    import cv2
    levels = [np.ascontiguousarray(image)]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        rows, cols = levels[-1].shape[:2]
        smaller = cv2.resize(levels[-1], (max(1, cols // 2), max(1, rows // 2)), interpolation=cv2.INTER_AREA)
        levels.append(np.ascontiguousarray(smaller.reshape(max(1, rows // 2), max(1, cols // 2), -1)))
    return levels


def make_texture(image_t_rows: np.ndarray, wrap: int, trilinear: bool = True):
    """A pyrender texture with visland's own mipmaps and byte-packed upload.

    pyrender's own upload leaves ``GL_UNPACK_ALIGNMENT`` at 4 (rows of odd byte length come
    out sheared) and calls ``glGenerateMipmap``.

    Parameters
    ----------
    image_t_rows : ndarray, shape (rows, cols, 3), uint8
        The texture, its row index growing with the texture coordinate t (OpenGL order).
    wrap : int
        OpenGL wrap mode (``GL_REPEAT``, ``GL_CLAMP_TO_EDGE``...).
    trilinear : bool, default True
        False samples the nearest mipmap level (half the cost; for detail textures).

    Returns
    -------
    pyrender.Texture
    """
    import pyrender
    from OpenGL import GL

    class MipTexture(pyrender.Texture):
        def _add_to_context(self):
            if self._texid is not None:
                raise ValueError("texture already loaded into the OpenGL context")
            self._texid = GL.glGenTextures(1)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._texid)
            GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
            levels = mipmap_chain(self.visland_image)
            for k, level in enumerate(levels):
                GL.glTexImage2D(GL.GL_TEXTURE_2D, k, GL.GL_RGB8, level.shape[1], level.shape[0], 0, GL.GL_RGB,
                                GL.GL_UNSIGNED_BYTE, level)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, len(levels) - 1)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER,
                               GL.GL_LINEAR_MIPMAP_LINEAR if self.visland_trilinear else GL.GL_LINEAR_MIPMAP_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, self.sampler.wrapS)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, self.sampler.wrapT)
            GL.glBindTexture(GL.GL_TEXTURE_2D, 0)

    image = np.ascontiguousarray(image_t_rows, dtype=np.uint8)
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"image_t_rows must be (rows, cols, 3) uint8, got shape {image.shape}")
    # pyrender keeps a top-row-first source; the upload above uses visland_image directly
    texture = MipTexture(source=np.flipud(image), source_channels="RGB",
                         sampler=pyrender.Sampler(wrapS=wrap, wrapT=wrap))
    texture.visland_image = image
    texture.visland_trilinear = bool(trilinear)
    return texture


class _ExactCamera:
    """A pyrender camera whose projection matrix is :func:`gl_projection_matrix` (built lazily)."""

    def __new__(cls, camera: CameraModel, znear_m: float, zfar_m: float):
        import pyrender

        class ExactCamera(pyrender.camera.Camera):
            def __init__(self):
                super().__init__(znear=znear_m, zfar=zfar_m, name="visland-camera")
                self.model = camera

            def get_projection_matrix(self, width=None, height=None):
                return gl_projection_matrix(self.model, self.znear, self.zfar)

        return ExactCamera()


class OffscreenView:
    """One EGL context drawing a pyrender scene through an exact OpenCV camera.

    Parameters
    ----------
    camera : CameraModel
        Image size and intrinsics (the mounting is not used here: poses are given directly).
    shader_dir : str
        Folder holding ``flat.vert`` and ``flat.frag`` (see :mod:`visland.render.shaders`).
    samples : int
        MSAA samples (0 disables multisampling).
    anisotropy : float
        OpenGL (hardware) anisotropic filtering ratio for mipmapped textures; 1 disables it.
        llvmpipe does it in software at about a second per frame, so visland's scenes use 1 and
        filter the pavements in the shader instead (``SceneParams.anisotropy``).
    """

    def __init__(self, camera: CameraModel, shader_dir: str, samples: int = 4, anisotropy: float = 1.0):
        check_opengl()
        try:
            import pyrender
            from pyrender.constants import RenderFlags
            self._offscreen = pyrender.OffscreenRenderer(camera.width, camera.height)
        except RenderingUnavailable:
            raise
        except Exception as error:  # EGL reports missing drivers through many exception types
            raise RenderingUnavailable(
                f"no usable EGL/OpenGL context could be created ({type(error).__name__}: {error}); "
                f"{EGL_INSTALL_HINT}") from None
        self._flags = RenderFlags.FLAT
        self.camera = camera
        renderer_class = _make_renderer_class()
        self._offscreen._platform.make_current()
        self._offscreen._renderer.delete()
        self._offscreen._renderer = renderer_class(camera.width, camera.height, shader_dir, samples, anisotropy)
        self._offscreen._platform.make_uncurrent()
        self._camera_node = None

    def render(self, scene, p_runway_m, R_camera_from_runway, znear_m: float, zfar_m: float) -> np.ndarray:
        """Draw ``scene`` (a pyrender Scene in runway coordinates) from the given camera pose.

        Returns
        -------
        rgb : ndarray of uint8, shape (H, W, 3)
            Row 0 at the top; pixel ``(u, v)`` is ``rgb[v, u]`` with SPEC pixel centres.
        """
        import pyrender
        pose = gl_camera_pose(p_runway_m, R_camera_from_runway)
        self._offscreen._renderer.view_matrix = gl_view_matrix(p_runway_m, R_camera_from_runway)
        if self._camera_node is None or self._camera_node not in scene.nodes:
            self._camera_node = pyrender.Node(camera=_ExactCamera(self.camera, znear_m, zfar_m), matrix=pose)
            scene.add_node(self._camera_node)
            scene.main_camera_node = self._camera_node
        else:
            self._camera_node.camera.znear = znear_m
            self._camera_node.camera.zfar = zfar_m
            scene.set_pose(self._camera_node, pose)
        return self._offscreen.render(scene, self._flags)

    def close(self) -> None:
        """Release this view's GL context (idempotent), and only it.

        pyrender's EGL platform also terminates the EGL display when it deletes a context; the
        display is one per process, shared by every view, so that killed the contexts of the
        other views still open (their next render or close failed with EGL_BAD_DISPLAY or
        EGL_NOT_INITIALIZED: a renderer cached by ``visland.datasets.generate`` after another
        one was closed). The display stays initialised for the process's life.
        """
        if getattr(self, "_offscreen", None) is not None:
            try:
                _destroy_context_only(self._offscreen._platform)
                self._offscreen.delete()
            finally:
                self._offscreen = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
