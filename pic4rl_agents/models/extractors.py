"""Feature extractors: the paper's convolutional multi-input network for depth + goal, and
any Dict of images (each its own CNN: depth, goToPose's memory crop) and vectors.

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
    """Conv layers (``channels``, stride 2) over each image entry (3-D Box) of a Dict
    observation → ``cnn_features`` units each, concatenated with every vector entry (sorted by
    key). The first image (``depth`` when there is one) keeps the names ``cnn`` and ``head``,
    so models saved before memory load; others (``memory``) get their own CNN in ``more``. A
    bare image observation (the vineyard task's) goes through the same CNN alone."""

    def __init__(self, observation_space: gym.spaces.Dict | gym.spaces.Box,
                 channels: tuple[int, ...] | list[int] = (16, 32, 32),
                 cnn_features: int = 128) -> None:
        if isinstance(observation_space, gym.spaces.Dict):
            spaces = observation_space.spaces
            images = sorted((k for k, v in spaces.items() if len(v.shape) == 3),
                            key=lambda k: (k != IMAGE_KEY, k))
            vector_keys = sorted(k for k in spaces if k not in images)
            image = spaces[images[0]]
        else:
            images, image, vector_keys = [], observation_space, []
        vector_dim = sum(int(observation_space[k].shape[0]) for k in vector_keys)
        n_images = max(len(images), 1)
        super().__init__(observation_space, features_dim=n_images * cnn_features + vector_dim)
        self.cnn, self.head = _cnn(image, channels, cnn_features)
        self.more = nn.ModuleDict({k: nn.Sequential(*_cnn(observation_space[k], channels,
                                                          cnn_features))
                                   for k in images[1:]})
        self.image_keys, self.vector_keys = images, vector_keys

    def forward(self, observations: dict[str, torch.Tensor] | torch.Tensor) -> torch.Tensor:
        if not isinstance(observations, dict):
            return self.head(self.cnn(observations.float()))
        first, *others = self.image_keys
        features = [self.head(self.cnn(observations[first].float()))]
        features += [self.more[k](observations[k].float()) for k in others]
        features += [observations[k].float().flatten(1) for k in self.vector_keys]
        return torch.cat(features, dim=1)


def _cnn(image: gym.spaces.Box, channels: tuple[int, ...] | list[int],
         cnn_features: int) -> tuple[nn.Sequential, nn.Sequential]:
    """Conv layers over ``image`` (kernel 5 then 3, stride 2, ReLU), flattened, and the
    linear head to ``cnn_features`` units."""
    layers: list[nn.Module] = []
    in_channels = int(image.shape[0])
    for i, out_channels in enumerate(channels):
        kernel = 5 if i == 0 else 3
        layers += [nn.Conv2d(in_channels, out_channels, kernel, stride=2), nn.ReLU()]
        in_channels = out_channels
    layers.append(nn.Flatten())
    cnn = nn.Sequential(*layers)
    with torch.no_grad():
        n_flat = cnn(torch.zeros(1, *image.shape)).shape[1]
    return cnn, nn.Sequential(nn.Linear(n_flat, cnn_features), nn.ReLU())
