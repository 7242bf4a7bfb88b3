"""strug-manip: robots acting under model uncertainty.

Domains (toy POMDPs, and the Fetch manipulation tasks), the experiment runner, and the
``strug`` command line. The solvers live in the numpy-only ``planners`` package.
"""

import os

# Offscreen rendering: MuJoCo picks its OpenGL platform when first imported, and this
# stack has no window to draw in. EGL works on Mesa's software renderer; set MUJOCO_GL
# yourself (e.g. osmesa, or glfw with a display) to override.
os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
