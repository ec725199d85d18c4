"""Uniformly random selection: a random valid super arm every step."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .base import Agent, Observation
from .costs import Needs


class RandomAgent(Agent):
    """A uniformly random valid super arm every step, independently per trial."""

    name = "random"
    needs = Needs(device=True)

    def _act(self, obs: Observation) -> NDArray[np.int8]:
        return self.random_super_arms(self.batch_size)
