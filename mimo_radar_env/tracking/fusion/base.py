"""The fusion interface: how the measurements of the selected channels update the IMM prior."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from ...core.compiled import HAVE_NUMBA


@dataclass
class Prior:
    """The predicted IMM state of one step, with the sigma points of its models.

    Shapes: ``means`` (B, K, R, 4), ``covs`` (B, K, R, 4, 4), ``log_c`` (B, K, R) the log
    predicted model probabilities, ``sigmas`` (B, K, R, S, 4), ``wm``/``wc`` (S,) the
    unscented weights.
    """

    means: NDArray[np.float64]
    covs: NDArray[np.float64]
    log_c: NDArray[np.float64]
    sigmas: NDArray[np.float64]
    wm: NDArray[np.float64]
    wc: NDArray[np.float64]


@dataclass
class Posterior:
    """What a fusion returns: per-model means (B, K, R, 4), covariances (B, K, R, 4, 4) and log
    probabilities (B, K, R), and the fused estimate (B, K, 4) and covariance (B, K, 4, 4)."""

    means: NDArray[np.float64]
    covs: NDArray[np.float64]
    log_probs: NDArray[np.float64]
    estimate: NDArray[np.float64]
    covariance: NDArray[np.float64]

    def finite(self) -> NDArray[np.bool_]:
        """(B, K): True where the update produced finite numbers."""
        return (
            np.isfinite(self.means).all(axis=(-1, -2))
            & np.isfinite(self.covs).all(axis=(-1, -2, -3))
            & np.isfinite(self.log_probs).all(axis=-1)
        )


class Fusion(ABC):
    """Base class of fusions; each is registered by its ``name`` in ``FUSIONS``.

    Parameters
    ----------
    use_numba : bool
        Run the fusion's compiled path, where it has one and numba is installed (default).
    """

    name: ClassVar[str]

    def __init__(self, use_numba: bool = True) -> None:
        self.use_numba = use_numba and HAVE_NUMBA

    @abstractmethod
    def update(
        self,
        prior: Prior,
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
    ) -> Posterior:
        """Update the prior with the selected channels' measurements.

        ``tx_positions`` (B, Ms, 2) and ``rx_positions`` (B, Ns, 2) are the selected stations;
        every pair is a channel, TX-major (channel ``i * Ns + j``). ``measurement`` and
        ``noise_variance`` (B, K, Ms * Ns, 2) hold each channel's range sum and azimuth and the
        diagonal of its measurement covariance.
        """

    @staticmethod
    def run_path(
        path: Callable[..., tuple[NDArray[np.float64], ...]],
        prior: Prior,
        tx_positions: NDArray[np.float64],
        rx_positions: NDArray[np.float64],
        measurement: NDArray[np.float64],
        noise_variance: NDArray[np.float64],
    ) -> Posterior:
        """The posterior of a numpy or compiled path taking the prior's arrays one by one (the
        layout both a fusion's paths share)."""
        return Posterior(
            *path(
                prior.sigmas,
                prior.means,
                prior.covs,
                prior.log_c,
                prior.wm,
                prior.wc,
                tx_positions,
                rx_positions,
                measurement,
                noise_variance,
            )
        )
