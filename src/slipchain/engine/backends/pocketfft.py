"""scipy.fft's real 2-D transforms without its Python layer: the per-step FFTs of the slab's drivers.

The slab's and half-space's drivers (:func:`.compose.fft_advance`, :func:`.compose.krylov_implicit_advance`
and the top's :class:`.compose._TopDriver`) take one ``rfft2``/``irfft2`` pair, or more, per explicit
step. On the grids the tester and the suite run (4 x 4 to 16 x 16) scipy.fft's Python layer (the
uarray backend's dispatch, the argument checks and shape fixes of ``scipy.fft._pocketfft``) costs
several times the transform itself: measured on an 8 x 8 tester run (cProfile, this project's 2-core
AMD EPYC), 11.1 s of the 14.8 s its 100 000 ``SpectralOperator.apply_both`` calls took went to
scipy.fft, of which 1.6 s to the transforms.

:class:`DirectFFT` calls the C++ functions that scipy.fft's pocketfft backend ends in (``pypocketfft.r2c``
and ``c2r``, as scipy 1.17 calls them) with the arguments scipy.fft passes them for the calls the drivers make
(float64 input, the default norm, the half spectrum that rfft2 makes back to its grid, one thread),
so its results are scipy.fft's to the bit; any other call is scipy.fft's own. At first use it checks
itself against scipy.fft on a few shapes and falls back to scipy.fft wholesale where the private
module is missing or differs, as it may in another scipy (:func:`fft_module`). Bypassed with it: a scipy.fft backend a user has
installed (``scipy.fft.set_backend``) and ``scipy.fft.set_workers`` (the drivers' grids are too small
for threads to pay).
"""

from __future__ import annotations

import functools
import operator

import numba as nb
import numpy as np

_F64, _C128 = np.dtype(np.float64), np.dtype(np.complex128)


_AXES: dict = {}  # (axes, ndim) -> _axes' answer: the drivers ask for the same few (tuples of ints)


def _axes(axes, ndim: int) -> list[int] | None:
    """The two axes as scipy.fft normalises them (non-negative, distinct), or None for another request."""
    try:
        return _AXES[axes, ndim]
    except (KeyError, TypeError):  # not seen yet, or not hashable (a list)
        pass
    ax = _normalise(axes, ndim)
    if ax is not None and type(axes) is tuple:
        _AXES[axes, ndim] = ax
    return ax


def _normalise(axes, ndim: int) -> list[int] | None:
    try:
        ax = [operator.index(a) for a in axes]
    except TypeError:
        return None
    ax = [a + ndim if a < 0 else a for a in ax]
    if len(ax) != 2 or ax[0] == ax[1] or not all(0 <= a < ndim for a in ax):
        return None
    return ax


def _plain(x, dtype) -> bool:
    """An aligned ndarray of ``dtype`` in native byte order (a swapped dtype is not equal to it)."""
    return type(x) is np.ndarray and x.dtype == dtype and x.flags.aligned


class DirectFFT:
    """``rfft2`` and ``irfft2`` with scipy.fft's signature (the arguments the drivers use), by
    pypocketfft directly (module docstring); ``pfft`` the module ``scipy.fft._pocketfft.pypocketfft``.
    (scipy.fft is imported when this is made, not with the package: 0.25 s that a chain's run needs not.)"""

    def __init__(self, pfft):
        import scipy.fft

        self._r2c, self._c2r = pfft.r2c, pfft.c2r
        self._scipy = scipy.fft

    def rfft2(self, x, s=None, axes=(-2, -1), norm=None, overwrite_x=False, workers=None):
        ax = _axes(axes, getattr(x, "ndim", 0)) if s is None and norm is None and workers is None else None
        if ax is None or not _plain(x, _F64):
            return self._scipy.rfft2(x, s=s, axes=axes, norm=norm, overwrite_x=overwrite_x, workers=workers)
        return self._r2c(x, ax, True, 0, None, 1)  # scipy: r2c(tmp, axes, forward, inorm 0 = 'backward', out, workers)

    def irfft2(self, x, s=None, axes=(-2, -1), norm=None, overwrite_x=False, workers=None):
        plain = type(s) is tuple and len(s) == 2 and norm is None and workers is None
        ax = _axes(axes, getattr(x, "ndim", 0)) if plain else None
        if ax is None or not _plain(x, _C128) or x.shape[ax[0]] != s[0] or x.shape[ax[1]] != s[1] // 2 + 1:
            return self._scipy.irfft2(x, s=s, axes=axes, norm=norm, overwrite_x=overwrite_x, workers=workers)
        return self._c2r(x, ax, int(s[1]), False, 2, None, 1)  # scipy: inorm 2 - 0 for the inverse


def _agrees(direct: DirectFFT) -> bool:
    """Whether ``direct`` gives scipy.fft's bits on the shapes and axes the drivers use."""
    import scipy.fft

    def same(a, b):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()

    rng = np.random.default_rng(0)
    for shape, axes in (((8, 8), (-2, -1)), ((2, 5, 6), (1, 2)), ((2, 3, 4, 4), (2, 3)), ((3, 16, 16), (1, 2))):
        x = rng.standard_normal(shape)
        s = (shape[axes[0]], shape[axes[1]])
        spec = scipy.fft.rfft2(x, axes=axes)
        if not (same(direct.rfft2(x, axes=axes), spec)
                and same(direct.irfft2(spec * 0.5, s=s, axes=axes), scipy.fft.irfft2(spec * 0.5, s=s, axes=axes))):
            return False
    return True


@functools.cache
def fft_module():
    """The FFT the CPU drivers use by default: :class:`DirectFFT` where it agrees with scipy.fft bit
    for bit (checked once per process), else scipy.fft itself."""
    import scipy.fft

    try:
        from scipy.fft._pocketfft import pypocketfft
    except ImportError:  # a scipy whose private layout moved: the public module
        return scipy.fft
    direct = DirectFFT(pypocketfft)
    try:
        return direct if _agrees(direct) else scipy.fft
    except Exception:  # noqa: BLE001 - a private signature that changed: the public module
        return scipy.fft


@nb.njit(cache=True)
def _numba_pair(x, s):
    """rfft2 over the last two axes of ``x`` (the grids of a batch of rows), and irfft2 of half that spectrum,
    as :func:`.compose.fft_chunk_driver` calls them, compiled (:func:`numba_fft`; called from Python only, so
    it may keep numba's cache)."""
    spec = np.fft.rfft2(x, axes=(1, 2))
    half = spec * 0.5
    return spec, np.fft.irfft2(half, s=s, axes=(1, 2))


@nb.njit(cache=True)
def _numba_pair_2d(x, s):
    """The same on one grid (the implicit stepper's SpectralOperator.apply: rfft2 over the default axes)."""
    spec = np.fft.rfft2(x)
    return spec, np.fft.irfft2(spec * 0.5, s=s)


@functools.cache
def numba_fft() -> bool:
    """Whether numpy.fft compiles in numba here (rocket-fft, which teaches numba numpy.fft with the
    pocketfft/DUCC transforms scipy.fft runs) with :func:`fft_module`'s bits on batches of grids and on
    single grids (checked once per process). Where not, the slab's drivers keep their per-step Python
    (:func:`.compose.fft_advance`, :func:`.compose.krylov_implicit_advance`), whose results are the same:
    only slower."""
    try:
        import rocket_fft  # noqa: F401 - registers numpy.fft for numba (also by its numba entry point)
    except ImportError:
        return False
    fft = fft_module()
    rng = np.random.default_rng(1)
    try:
        for shape in ((1, 8, 8), (2, 5, 6), (3, 16, 16)):
            x = rng.standard_normal(shape)
            spec, back = _numba_pair(x, shape[1:])
            ref = fft.rfft2(x, axes=(1, 2))
            if not (spec.tobytes() == ref.tobytes()
                    and back.tobytes() == fft.irfft2(ref * 0.5, s=shape[1:], axes=(1, 2)).tobytes()):
                return False
        for shape in ((8, 8), (5, 6), (16, 16)):
            x = rng.standard_normal(shape)
            spec, back = _numba_pair_2d(x, shape)
            ref = fft.rfft2(x)
            if not (spec.tobytes() == ref.tobytes() and back.tobytes() == fft.irfft2(ref * 0.5, s=shape).tobytes()):
                return False
    except Exception:  # noqa: BLE001 - a rocket-fft that does not compile these calls: the Python driver
        return False
    return True


__all__ = ["DirectFFT", "fft_module", "numba_fft"]
