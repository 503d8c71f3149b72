"""Writing and reading result Datasets: NetCDF via h5netcdf, written atomically.

A file is written to a temporary name beside its destination and moved into place with
``os.replace``, so an interrupted write never leaves a half-written result under the final
name, and never replaces a finished one with a broken one.
"""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

ENGINE = "h5netcdf"


def write_dataset(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` (NetCDF4) atomically; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        ds.to_netcdf(tmp, engine=ENGINE)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def read_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Load a result written by :func:`write_dataset` fully into memory."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()
