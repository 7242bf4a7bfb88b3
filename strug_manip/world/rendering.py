"""Offscreen renderers of many models on one OpenGL context.

A :class:`mujoco.Renderer` creates an OpenGL context of its own, and setting up MuJoCo's
rendering (:class:`mujoco.MjrContext`) in a fresh context is several times slower
than in one that has served before (Mesa's software rasteriser; README, "Manipulation
tasks"): most of a renderer's construction. An episode renders the head camera in
the world of every belief particle, each its own model, so it built a context per
particle; a :class:`RenderContext` builds one and hands out renderers that share it.
Each renderer still gets its own MuJoCo rendering context (:class:`mujoco.MjrContext`:
the model's meshes and textures, its offscreen framebuffer), and renders exactly what
a :class:`mujoco.Renderer` of the same model renders (``tests/test_world.py``).
"""

from __future__ import annotations

import mujoco
from mujoco.rendering.classic import gl_context

from planners.errors import ConfigError


class RenderContext:
    """One OpenGL context (the backend of ``MUJOCO_GL``, made at the first
    :meth:`renderer`) for the renderers of :meth:`renderer`; :meth:`close` frees it
    after them, and a later :meth:`renderer` makes a new one."""

    def __init__(self) -> None:
        self._gl = None
        self._renderers: list[SharedRenderer] = []

    def renderer(self, model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
        """A renderer of ``model``'s images (``height`` x ``width`` px) on this context."""
        if self._gl is None:
            if gl_context.GLContext is None:
                raise ConfigError("no OpenGL backend: set MUJOCO_GL to egl or osmesa")
            # (The size is the first context's framebuffer, which no renderer uses.)
            self._gl = gl_context.GLContext(width, height)
        r = SharedRenderer(model, height, width, self._gl)
        self._renderers.append(r)
        return r

    def close(self) -> None:
        """Free every renderer of this context, then the context."""
        for r in self._renderers:
            r.close()
        self._renderers.clear()
        if self._gl is not None:
            self._gl.free()
            self._gl = None


class SharedRenderer(mujoco.Renderer):
    """A :class:`mujoco.Renderer` on a given OpenGL context instead of one of its own
    (:meth:`RenderContext.renderer` makes them). Its set-up repeats the base class's on
    that context; it renders with the base class's :meth:`render` after binding its
    own framebuffer; :meth:`close` frees its MuJoCo context, not the shared OpenGL
    one."""

    def __init__(self, model: mujoco.MjModel, height: int, width: int, gl) -> None:
        self._gl_context = None
        self._mjr_context = None
        g = model.vis.global_
        if not (0 < width <= g.offwidth and 0 < height <= g.offheight):
            raise ConfigError(
                f"image size {width}x{height} must be within the offscreen buffer "
                f"{g.offwidth}x{g.offheight} px"
            )
        self._width, self._height, self._model = width, height, model
        self._scene = mujoco.MjvScene(model=model, maxgeom=10000)
        self._scene_option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)
        gl.make_current()
        # The offscreen framebuffer is this renderer's image, not the model's largest
        # (sized for pictures): most of a context's set-up is allocating that buffer
        # with its multisamples, and only the image's corner of it is ever drawn.
        size = g.offwidth, g.offheight
        g.offwidth, g.offheight = width, height
        try:
            self._mjr_context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        finally:
            g.offwidth, g.offheight = size
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr_context)
        self._mjr_context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._depth_rendering = False
        self._segmentation_rendering = False
        # The base class's render() makes this context current and flips the image.
        self._gl_context = gl

    def render(self, *, out=None):
        """The base class's render, after binding this renderer's framebuffer (the
        OpenGL context's binding is the last renderer's)."""
        if self._mjr_context is not None and self._gl_context is not None:
            self._gl_context.make_current()
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr_context)
        return super().render(out=out)

    def __del__(self) -> None:
        # Not the base class's close: at interpreter exit the OpenGL display may be
        # gone before this object; its RenderContext frees it, else the exit does.
        pass

    def close(self) -> None:
        if self._mjr_context is not None and self._gl_context is not None:
            self._gl_context.make_current()
            self._mjr_context.free()
        self._mjr_context = None
        self._gl_context = None
