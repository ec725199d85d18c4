"""Target tracking: the batched IMM-UKF of Section III-C and its fusions."""

from .fusion import FUSIONS, Fusion, make_fusion
from .imm import combine, markov_matrix
from .imm_ukf import IMMUKFTracker
from .unscented import SigmaPointParameters, robust_cholesky, sigma_points, unscented_update

__all__ = [
    "FUSIONS",
    "Fusion",
    "IMMUKFTracker",
    "SigmaPointParameters",
    "combine",
    "make_fusion",
    "markov_matrix",
    "robust_cholesky",
    "sigma_points",
    "unscented_update",
]
