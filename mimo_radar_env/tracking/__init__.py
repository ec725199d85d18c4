"""Target tracking: the batched IMM-UKF of Section III-C."""

from .imm_ukf import FUSIONS, IMMUKFTracker, combine, markov_matrix
from .unscented import SigmaPointParameters, robust_cholesky, sigma_points, unscented_update

__all__ = [
    "FUSIONS",
    "IMMUKFTracker",
    "SigmaPointParameters",
    "combine",
    "markov_matrix",
    "robust_cholesky",
    "sigma_points",
    "unscented_update",
]
