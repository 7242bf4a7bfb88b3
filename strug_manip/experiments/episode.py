"""The product's episode runner is the library's: :mod:`planners.episode`.

Re-exported here so that the experiment code and the command line import their runner
from the experiments package, while one implementation serves every domain.
"""

from planners.episode import (
    DEFAULT_PARTICLES,
    EpisodeResult,
    StepRecord,
    episode_generators,
    run_episode,
)

__all__ = ["DEFAULT_PARTICLES", "EpisodeResult", "StepRecord", "episode_generators", "run_episode"]
