"""The CPU backend object: ``advance`` on one core, by the loop composed for the batch's geometry and
integrator (:mod:`.compose`): the chains' whole-chunk kernel, or the slab's and half-space's FFT
driver (:func:`.compose.fft_advance` with the body of :mod:`.spectral`, issue 13)."""

from __future__ import annotations

import numpy as np

from ..scheme import N_ACC, N_CACC, N_OUT
from . import compose
from .base import Batch, ChunkOutput


class CPUBackend:
    """The composed loops on one CPU core: ``advance(batch, n_samples, sample_steps)``."""

    name = "cpu"

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        if compose.BODIES[batch.geometry] == "spectral":  # slab, half-space: the elastic force by FFT
            return compose.fft_advance(batch, n_samples, sample_steps)
        b = batch.x.shape[0]
        cmax = batch.sites.shape[1]
        out = np.zeros((b, n_samples, N_OUT))
        acc = np.zeros((b, N_ACC))
        cacc = np.zeros((b, N_CACC, cmax))
        adaptive = batch.folds is not None  # integrator = 'adaptive'
        folds = batch.folds if adaptive else np.zeros((b, 1, 2, cmax))
        control = batch.step_control if adaptive else np.zeros((b, 4))
        compose.loop(batch.geometry, adaptive)(
            batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar, batch.n_contacts,
            batch.ysolve, folds, control, n_samples, sample_steps, out, acc, cacc, batch.status)
        return ChunkOutput(out, acc, cacc)


__all__ = ["CPUBackend"]
