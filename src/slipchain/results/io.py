"""Writing and reading result files atomically: Datasets (NetCDF via h5netcdf), text, figures.

A file is written to a temporary name beside its destination, flushed to the disk
(``os.fsync``) and moved into place with ``os.replace`` (:func:`atomic_write`), so an
interrupted write never leaves a half-written result under the final name, and never replaces a
finished one with a broken one; the rename itself is flushed too (the directory is synced), so a
power cut after a member was reported stored does not take it back.
"""

from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import xarray as xr

ENGINE = "h5netcdf"


@contextmanager
def atomic_write(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; if the block succeeds it is moved onto ``path``,
    otherwise removed. The parent directory is created."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        yield tmp
        _fsync(tmp)
        os.replace(tmp, path)
        _fsync(path.parent)
    finally:
        tmp.unlink(missing_ok=True)


def _fsync(path: Path) -> None:
    """Flush a file's (or a directory's entries') data to the disk; a no-op where the OS cannot."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:  # e.g. a file system without fsync for directories
        pass
    finally:
        os.close(fd)


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    with atomic_write(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_csv(table: Any, path: str | os.PathLike, **to_csv: Any) -> Path:
    """Write a table (a pandas DataFrame) as CSV atomically, without its index unless ``index=True``
    is given among the ``to_csv`` options; returns the path."""
    with atomic_write(path) as tmp:
        table.to_csv(tmp, **{"index": False, **to_csv})
    return Path(path)


def write_dataset(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` (NetCDF4) atomically; returns the path.

    The file is made in memory and written with plain file I/O (:func:`write_bytes`), so that a
    full disk is one OSError (ENOSPC, naming the file) and the temporary file is removed: HDF5
    writing onto a full disk printed dozens of tracebacks and then crashed the process (issue 30).
    Where xarray cannot make NetCDF4 in memory (before 2025) it writes the temporary file itself.

    The in-memory write runs under dask's synchronous scheduler: inside a Dask worker xarray would
    otherwise guard the write with a distributed lock named after the in-memory buffer, which the
    scheduler does not know (RuntimeError "Semaphore or Lock ... not known"); the buffer is this
    call's own, so no lock across processes is needed."""
    import dask

    try:
        with dask.config.set(scheduler="synchronous"):
            data = ds.to_netcdf(engine=ENGINE)
    except (ValueError, TypeError, NotImplementedError):  # an xarray that writes NetCDF4 to files only
        with atomic_write(path) as tmp:
            ds.to_netcdf(tmp, engine=ENGINE)
        return Path(path)
    return write_bytes(path, data)


def write_bytes(path: str | os.PathLike, data: bytes | memoryview) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path. A failed write (a full disk) raises
    OSError with the destination as its filename and leaves no temporary file."""
    try:
        with atomic_write(path) as tmp, open(tmp, "wb") as fh:
            fh.write(data)
    except OSError as e:
        raise OSError(e.errno, e.strerror or str(e), str(path)) from None
    return Path(path)


def read_attrs(path: str | os.PathLike) -> dict[str, Any]:
    """The global attributes of a file written by :func:`write_dataset`, as plain Python values,
    opening only its header (no variable is read). Raises what h5py raises for a damaged file."""
    import h5netcdf

    with h5netcdf.File(path, "r") as f:
        return {k: _plain(v) for k, v in f.attrs.items()}


def _plain(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray) and v.size == 1:
        v = v.reshape(()).item()
    if isinstance(v, np.generic):
        return v.item()
    return v


def read_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Load a result written by :func:`write_dataset` fully into memory."""
    with xr.open_dataset(path, engine=ENGINE) as ds:
        return ds.load()
