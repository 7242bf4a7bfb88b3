"""Perception: RGB-D from the robot's head camera to part hypotheses for the belief.

Imports numpy, torch, opencv and scipy only: it sees images, depth and camera poses,
never MuJoCo, a planner or the rest of the stack (so its errors live in
:mod:`perception.errors`).

- :mod:`perception.inputs`: checking one view (shapes, dtypes, units, dropouts).
- :mod:`perception.articulation_net`: the per-pixel network (classes, instance centre
  votes, hinge sides, pull affordance) and its training targets.
- :mod:`perception.parts`: one view to part instances in the world frame.
- :mod:`perception.fusion`: the cabinet's front plane and the views' instances fused
  into part hypotheses (existence, class and hinge-side probabilities, joint
  parameters, their spread).
- :mod:`perception.affordance`: grasp poses biased by the pull affordance.
- :mod:`perception.likelihood`: the point-cloud observation model (quantile
  Hausdorff distance, vectorised over particles).

Training data (labelled views rendered in MuJoCo) come from
:mod:`strug_manip.world.perception_data`; particles of complete cabinets are drawn by
:mod:`strug_manip.domains.manipulation.belief`.
"""
