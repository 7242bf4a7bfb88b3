"""The oracle: a manipulation task whose belief is the true model (evaluation only).

The oracle is a choice of *belief*, not of planner: ``strug run --solver oracle`` (and
the ``oracle`` row of ``strug bench``, the tables and ``tools/eval_manipulation.py``)
runs STRUG's planner with its configuration, its skills and its budgets
(:mod:`strug_manip.experiments.task`) on a task built with ``belief="true"``
(:class:`.tasks.ManipulationTask`). Only the belief differs:

* **initially**, the real cabinet as the episode's real environment knows it (the
  generator's :class:`~strug_manip.objects.generator.CabinetSpec`, or a real object's
  description, standing where the real one stands, its parts where the real ones are)
  is the belief's only particle (:func:`true_particle`), handed to the twins' POMDP
  instead of perception's particles (:attr:`.model.EpisodeView.truth`). Its twin is
  the same planning twin every particle has, and the catalogue, the actions, the
  search and the real robot's planning go through the same code as any belief's;
* **after every real step**, once the belief is updated and conditioned as every
  belief is (:mod:`.conditioning`), the particle takes over the real world's state
  (:func:`take_over`): where the real cabinet stands, every part's joint position, the
  object, the robot's base; not what its twin predicted. A held object keeps the
  grasp :mod:`.conditioning` gives it (the twin's floating hand is not the Fetch's).

What it bounds: the skills and the planner knowing the cabinet exactly; the gap to
STRUG with perception's belief is what the belief costs (perception and its updates).
It reads the true cabinet, so it is a baseline for evaluation, never a robot's belief.
The toy domains have no perception to replace: the runner refuses the oracle there
(:func:`strug_manip.experiments.task.check_solver`).
"""

from __future__ import annotations

from planners.particles import ParticleBelief
from strug_manip.control import PlanningTwin
from strug_manip.domains.manipulation.belief import Particle
from strug_manip.domains.manipulation.conditioning import edit_states
from strug_manip.domains.manipulation.state import ManipState
from strug_manip.domains.manipulation.worlds import ParticleWorlds
from strug_manip.world.sim import ManipulationWorld

#: The belief choices of a manipulation task: perception's particles, or the oracle's.
BELIEFS: tuple[str, ...] = ("perception", "true")


def true_particle(real: ManipulationWorld) -> Particle:
    """The real cabinet of ``real`` as a belief particle: its description, its parts'
    joint positions now (by joint name, [m or rad]); no front-frame model
    (``model=None``: it is not made from perception's parts) and no fused hypotheses
    (``source`` all -1, ``run`` -1)."""
    spec = real.scene.cabinet_spec
    pre = real.scene.cabinet_prefix
    q = {name.removeprefix(pre): v for name, v in real.part_positions().items()}
    return Particle(None, spec, q, tuple(-1 for _ in spec.parts), -1)


def take_over(belief: ParticleBelief, real: ManipulationWorld, w: ParticleWorlds) -> ParticleBelief:
    """``belief`` (already conditioned) with every particle's cabinet as the real one
    is now: its base where the real base is, each part joint at the real position (at
    rest). The oracle's particle describes the real cabinet, so its joints are the
    real joints by name."""
    T_cabinet, parts = real.cabinet_pose(), real.part_positions()

    def edit(tw: PlanningTwin, _: ManipState) -> None:
        tw.world.set_cabinet_pose(T_cabinet)
        tw.world.set_parts(parts)

    return edit_states(belief, w, edit)
