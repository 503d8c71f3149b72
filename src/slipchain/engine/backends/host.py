"""The CPU backend object: ``advance`` on one core, by the loop composed for the batch's geometry and
integrator (:func:`.compose.advance`): the chains' whole-chunk kernel, or the slab's and
half-space's FFT driver with the body of :mod:`.spectral` (issue 13)."""

from __future__ import annotations

from . import compose
from .base import Batch, ChunkOutput


class CPUBackend:
    """The composed loops on one CPU core: ``advance(batch, n_samples, sample_steps)``."""

    name = "cpu"

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        return compose.advance(batch, n_samples, sample_steps)


__all__ = ["CPUBackend"]
