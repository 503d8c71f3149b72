"""The geometries, each described once (issue 26): what the rest of the package asks of a geometry
instead of testing its name.

* ``body``: how the slider's body acts on the interface blocks. 'lattice': springs between
  neighbouring blocks and an upper layer of blocks driven through springs (the paper's two chains,
  Fig. 4; on a square lattice for chain2d). 'spectral': a quasi-static elastic body whose force is
  diagonal in Fourier space, a**2 k(q) (the slab of thickness H = N_L a, the half-space; docs/model.md),
  computed by FFT. The engine composes its loops per body (:mod:`slipchain.engine.backends.compose`).
* ``two_d``: the interface is an (Lx, Ly) grid (``Ly`` may exceed 1).
* ``top``: the slider has a top that can carry a dead weight (the chains' upper layer, the slab's
  clamped top); a half-space has none.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Geometry:
    name: str
    body: str  # 'lattice' or 'spectral'
    two_d: bool
    top: bool

    @property
    def spectral(self) -> bool:
        """The body's force is computed by FFT (slab, half-space)."""
        return self.body == "spectral"


GEOMETRIES: dict[str, Geometry] = {g.name: g for g in (
    Geometry("chain", "lattice", two_d=False, top=True),
    Geometry("chain2d", "lattice", two_d=True, top=True),
    Geometry("slab", "spectral", two_d=True, top=True),
    Geometry("halfspace", "spectral", two_d=True, top=False),
)}


def geometry_of(cfg) -> Geometry:
    """The :class:`Geometry` of a config (or of a geometry's name)."""
    return GEOMETRIES[cfg if isinstance(cfg, str) else cfg.geometry]


__all__ = ["GEOMETRIES", "Geometry", "geometry_of"]
