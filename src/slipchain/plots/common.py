"""What every figure shares: matplotlib without a display, the paper's symbols, atomic PNG + PDF output."""

from __future__ import annotations

import os
from pathlib import Path

from ..results.io import atomic_write

ETA_STYLE = {1.0: ("tab:blue", "o"), 0.3: ("tab:red", "D"), 0.1: ("black", "s")}  # Fig. 6 symbols per eta_c/omega0


def pyplot():
    """matplotlib.pyplot with the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, out: str | os.PathLike, stem: str) -> list[Path]:
    """Write ``fig`` as OUT/STEM.png and OUT/STEM.pdf (atomically) and close it; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        p = out / f"{stem}.{ext}"
        with atomic_write(p) as tmp:
            fig.savefig(tmp, dpi=150, bbox_inches="tight", format=ext)
        paths.append(p)
    pyplot().close(fig)
    return paths


__all__ = ["ETA_STYLE", "pyplot", "save_figure"]
