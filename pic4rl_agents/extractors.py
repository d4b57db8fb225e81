"""The import path that models saved before the sub-packages name their feature extractor by:
SB3 pickles ``policy_kwargs`` by reference, so ``checkpoints/td3_depth/model.zip`` and every
depth run saved then load ``pic4rl_agents.extractors.DepthGoalExtractor``. The class lives in
``pic4rl_agents.models.extractors``; this is the same class under its old name.
"""

from pic4rl_agents.models.extractors import DepthGoalExtractor

__all__ = ["DepthGoalExtractor"]
