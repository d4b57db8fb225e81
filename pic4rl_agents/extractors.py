"""Feature extractors: the paper's convolutional multi-input network for depth + goal.

SB3's NatureCNN is sized for 84×84 Atari frames; a small depth image (80×60 here) wants fewer,
smaller layers, and the goal vector must reach the policy head beside the image features, not
through a CNN. SB3 scales uint8 images to [0, 1] before this module sees them.
"""

from __future__ import annotations

import gymnasium as gym
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from torch import nn

IMAGE_KEY = "depth"


class DepthGoalExtractor(BaseFeaturesExtractor):
    """Conv layers (``channels``, stride 2) over the ``depth`` image → ``cnn_features`` units,
    concatenated with every other (vector) entry of a Dict observation. A bare image
    observation (the vineyard task's) goes through the same CNN alone."""

    def __init__(self, observation_space: gym.spaces.Dict | gym.spaces.Box,
                 channels: tuple[int, ...] | list[int] = (16, 32, 32),
                 cnn_features: int = 128) -> None:
        if isinstance(observation_space, gym.spaces.Dict):
            image = observation_space[IMAGE_KEY]
            vector_keys = sorted(k for k in observation_space.spaces if k != IMAGE_KEY)
        else:
            image, vector_keys = observation_space, []
        vector_dim = sum(int(observation_space[k].shape[0]) for k in vector_keys)
        super().__init__(observation_space, features_dim=cnn_features + vector_dim)
        layers: list[nn.Module] = []
        in_channels = int(image.shape[0])
        for i, out_channels in enumerate(channels):
            kernel = 5 if i == 0 else 3
            layers += [nn.Conv2d(in_channels, out_channels, kernel, stride=2), nn.ReLU()]
            in_channels = out_channels
        layers.append(nn.Flatten())
        self.cnn = nn.Sequential(*layers)
        with torch.no_grad():
            n_flat = self.cnn(torch.zeros(1, *image.shape)).shape[1]
        self.head = nn.Sequential(nn.Linear(n_flat, cnn_features), nn.ReLU())
        self.vector_keys = vector_keys

    def forward(self, observations: dict[str, torch.Tensor] | torch.Tensor) -> torch.Tensor:
        if not isinstance(observations, dict):
            return self.head(self.cnn(observations.float()))
        image = self.head(self.cnn(observations[IMAGE_KEY].float()))
        vectors = [observations[k].float().flatten(1) for k in self.vector_keys]
        return torch.cat([image, *vectors], dim=1)
