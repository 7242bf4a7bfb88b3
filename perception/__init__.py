"""Perception: RGB-D from the robot's head camera to an initial belief over kinematic models.

Planned contents (see ../shared/DESIGN.md, "Perception"): part segmentation, joint type
and joint parameter prediction (torch), the pull-affordance heat map that biases
controller parameters, and the point-cloud observation model. This package may import
numpy, torch and opencv only. Today it holds the per-pixel articulation network
(:mod:`perception.articulation_net`). Its training and test data, labelled
RGB-D views rendered in MuJoCo, come from :mod:`strug_manip.world.perception_data`
(``tools/render_perception_data.py``), stored as ``.npz`` shards this package can read
without MuJoCo.
"""
