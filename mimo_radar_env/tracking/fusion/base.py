"""The fusion interface: everything the project knows of one way of fusing the selected
channels' measurements.

A fusion is one module defining one :class:`Fusion` subclass (Stone Soup's updaters are built
the same way). It holds:

* :meth:`Fusion.update`, the tracker's update of the IMM prior, with its compiled twin;
* its predicted posterior of a super arm, for the tracking search and the planner:
  :meth:`Fusion.channel_terms`, :meth:`Fusion.posterior_from_sum` and
  :meth:`Fusion.planning_gain`;
* :meth:`Fusion.update_operations`, its cost per trial-step for the harness's time estimates.

:func:`register_fusion` adds it to :data:`FUSIONS` (the env option ``fusion`` takes its choices
from there); no other module names a fusion.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from ...core.arrays import namespace
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
        xp = namespace(self.means)
        return (
            xp.isfinite(self.means).all(axis=(-1, -2))
            & xp.isfinite(self.covs).all(axis=(-1, -2, -3))
            & xp.isfinite(self.log_probs).all(axis=-1)
        )


#: Models of the IMM (constant velocity and the two coordinated turns), sigma points of a
#: 4-state unscented transform, and the operations of one channel's measurement model, 2 x 2
#: innovation and gain (the cost model's units: :meth:`Fusion.update_operations`).
MODELS, SIGMA_POINTS = 3, 9
CHANNEL_OPERATIONS = SIGMA_POINTS * 2 * 40 + 400


class Fusion(ABC):
    """Base class of fusions; each is registered by its ``name`` in ``FUSIONS``.

    Parameters
    ----------
    use_numba : bool
        Run the fusion's compiled path, where it has one and numba is installed (default).
    """

    name: ClassVar[str]
    #: How the compiled tracking search (``_selection_kernels.posterior_values``) turns a super
    #: arm's sum of :meth:`channel_terms` into its posterior: ``"information"``, the inverse of
    #: the prior's information plus the sum; ``"mean"``, the sum over the channel count; ``None``,
    #: neither (the search takes the numpy path with :meth:`posterior_from_sum`).
    compiled_posterior: ClassVar[str | None] = None

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

    # ------------------------------------------ the predicted posterior of a super arm
    @staticmethod
    @abstractmethod
    def channel_terms(
        prior_info: NDArray[np.float64], information: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Each channel's term (B, K, M, N, 2, 2) of the super-arm sum that
        :meth:`posterior_from_sum` maps to a posterior, from the prior's position information
        ``prior_info`` (B, K, 2, 2) and each channel's ``information`` (B, K, M, N, 2, 2)."""

    @staticmethod
    @abstractmethod
    def posterior_from_sum(
        prior_info: NDArray[np.float64], total: NDArray[np.float64], count: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The predicted posterior position covariance (..., 2, 2) of a super arm whose channels'
        terms sum to ``total`` over ``count`` channels (the arguments broadcast)."""

    @staticmethod
    @abstractmethod
    def planning_gain(
        information: NDArray[np.float64], position_cov: NDArray[np.float64], selected: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The gain ``G`` (S, K, 2, 2) of the posterior ``P - P E G E' P`` (Woodbury's identity,
        ``E`` picks the position) after the channels ``selected`` (S, M, N; 0 or 1) with position
        ``information`` (S, K, M, N, 2, 2), from priors of position block ``position_cov``
        (S, K, 2, 2): what the planner carries from step to step."""

    # ------------------------------------------------------------------ its cost
    @staticmethod
    @abstractmethod
    def update_operations(channels: int) -> float:
        """Arithmetic operations of one update of one target and model with ``channels`` selected
        channels, roughly (an upper estimate, in the units of :data:`CHANNEL_OPERATIONS`)."""

    @classmethod
    def compiled_kernels(cls, threaded: bool = False) -> list[Any]:
        """The numba kernels its update runs (their twins over threads with ``threaded``; none
        without numba or a compiled path)."""
        return []

    @classmethod
    def compiled_update(cls, channels: int) -> bool:
        """Whether its update of ``channels`` selected channels runs a compiled kernel (the cost
        model counts that kernel's work as shared by a task's threads)."""
        return bool(cls.compiled_kernels())

    @staticmethod
    def run_path(
        path: Callable[..., tuple[NDArray[np.float64], ...]], prior: Prior, *channels: NDArray[np.float64]
    ) -> Posterior:
        """The posterior of a numpy or compiled path that takes the prior's arrays one by one, then
        the channels' (``tx_positions``, ``rx_positions``, ``measurement``, ``noise_variance``
        of :meth:`update`): the layout both a fusion's paths share."""
        return Posterior(
            *path(prior.sigmas, prior.means, prior.covs, prior.log_c, prior.wm, prior.wc, *channels)
        )
