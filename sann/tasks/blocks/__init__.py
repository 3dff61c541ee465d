"""The multi-block world of the paper's first experiment (moved to a package: see world.py)."""

from .world import *  # noqa: F403
from .world import _check_workers, _dataset_scene, _pair_free  # noqa: F401
