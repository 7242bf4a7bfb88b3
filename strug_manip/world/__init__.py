"""The manipulation world: Fetch, a table with an object, and a cabinet, in MuJoCo.

:func:`strug_manip.world.scene.build_scene` composes the MJCF;
:class:`strug_manip.world.sim.ManipulationWorld` resets, steps, reads and renders it.
"""

from strug_manip.world.scene import SceneConfig, SceneModel, build_scene
from strug_manip.world.sim import CameraFrame, ManipulationWorld, depth_to_points

__all__ = [
    "CameraFrame",
    "ManipulationWorld",
    "SceneConfig",
    "SceneModel",
    "build_scene",
    "depth_to_points",
]
