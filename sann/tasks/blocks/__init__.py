"""The multi-block world of the paper's first experiment: scenes, features, labels, datasets.

:mod:`.world` states the geometry (table, blocks, the modes C1-C3), builds scenes and labels
them from the true geometry; :mod:`.features` is the sensor (noisy centres, the Table-1
features); :mod:`.dataset` builds and caches the datasets D1 and D2. Their public names are
re-exported here; the package attribute ``features`` is the function, not the module
(``from sann.tasks.blocks.features import observe`` still reaches the module).
"""

from .dataset import DATASET_VERSION, KINDS, BlockDataset, feature_names_for, make_dataset
from .features import ObservedScene, features, neighbours, observe, observe_scene
from .world import (
    BLOCK_SIZES,
    COLOR_NAMES,
    DISTANCE_CLIP,
    FEATURE_NAMES,
    MAX_BLOCKS,
    MODES,
    N_COLORS,
    NAMES,
    ROBOT_BASE,
    SIDES,
    TABLE_SIZE,
    BlockWorldParams,
    Scene,
    as_rng,
    check_mode,
    generate_scene,
    graspable,
    rests_on_matrix,
    scene_from_blocks,
)

__all__ = [
    "BLOCK_SIZES", "COLOR_NAMES", "DATASET_VERSION", "DISTANCE_CLIP", "FEATURE_NAMES", "KINDS",
    "MAX_BLOCKS", "MODES", "NAMES", "N_COLORS", "ROBOT_BASE", "SIDES", "TABLE_SIZE",
    "BlockDataset", "BlockWorldParams", "ObservedScene", "Scene", "as_rng", "check_mode",
    "feature_names_for", "features", "generate_scene", "graspable", "make_dataset",
    "neighbours", "observe", "observe_scene", "rests_on_matrix", "scene_from_blocks",
]
