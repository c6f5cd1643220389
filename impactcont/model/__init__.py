"""The oscillator and its modal decomposition (eq. 1-10)."""

from impactcont.model.modal import ModalBasis, forced_coefficients, free_transfer
from impactcont.model.oscillator import ImpactOscillator, chain_stiffness

__all__ = ["ImpactOscillator", "ModalBasis", "chain_stiffness", "forced_coefficients",
           "free_transfer"]
