"""The slab drivers' FFT without scipy.fft's Python layer (engine/backends/pocketfft.py) gives
scipy.fft's bits: the same C++ transforms with the same arguments, for every shape and axes pair the
drivers use, and scipy.fft's own answer (or error) for any other call."""

import numpy as np
import pytest
import scipy.fft
from hypothesis import given, settings
from hypothesis import strategies as hs

from slipchain.engine.backends.pocketfft import DirectFFT, fft_module


def _direct():
    from scipy.fft._pocketfft import pypocketfft

    return DirectFFT(pypocketfft)


def _same(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_the_drivers_get_the_direct_transforms_with_the_locked_scipy():
    """With the scipy this project pins, the private module is there and agrees: the drivers get
    DirectFFT, not scipy.fft (were it lost, the slab's steps would cost about three times as much)."""
    assert isinstance(fft_module(), DirectFFT)


@settings(max_examples=60, deadline=None)
@given(batch=hs.lists(hs.integers(1, 3), max_size=2), lx=hs.integers(1, 20), ly=hs.integers(1, 20),
       seed=hs.integers(0, 2**31), scale=hs.floats(1e-12, 1e12))
def test_rfft2_and_irfft2_are_scipy_fft_to_the_bit(batch, lx, ly, seed, scale):
    x = np.random.default_rng(seed).standard_normal((*batch, lx, ly)) * scale
    d = _direct()
    axes = (len(batch), len(batch) + 1)
    for ax in (axes, (-2, -1)):
        spec = d.rfft2(x, axes=ax)
        assert _same(spec, scipy.fft.rfft2(x, axes=ax))
        assert _same(d.irfft2(spec * 1.5, s=(lx, ly), axes=ax), scipy.fft.irfft2(spec * 1.5, s=(lx, ly), axes=ax))
    assert _same(d.rfft2(x[..., ::2, :], axes=ax), scipy.fft.rfft2(x[..., ::2, :], axes=ax))  # a strided view
    swapped = x.astype(x.dtype.newbyteorder())  # the same values in the other byte order: scipy.fft's way
    assert _same(d.rfft2(swapped, axes=ax), scipy.fft.rfft2(swapped, axes=ax))


def test_other_calls_are_scipy_fft_s_own():
    """Requests the drivers do not make (another dtype, a padded shape, a norm, the first axes, a
    half spectrum of another grid, a list) are answered by scipy.fft, errors included."""
    d = _direct()
    rng = np.random.default_rng(1)
    x = rng.standard_normal((3, 6, 5))
    spec = scipy.fft.rfft2(x)
    for args, kw in (((x.astype(np.float32),), {}), ((x,), dict(s=(8, 8))), ((x,), dict(norm="ortho")),
                     ((x,), dict(axes=(0, 1))), ((x.tolist(),), {})):
        assert _same(d.rfft2(*args, **kw), scipy.fft.rfft2(*args, **kw)), kw
    for kw in (dict(s=(6, 5)), dict(s=(6, 4)), dict(s=(5, 5)), dict(s=[6, 5]), dict(s=(6, 5), norm="forward"), {}):
        assert _same(d.irfft2(spec, **kw), scipy.fft.irfft2(spec, **kw)), kw
    with pytest.raises(TypeError):  # complex input to the real transform: scipy.fft's error
        d.rfft2(spec)
    with pytest.raises(ValueError):  # one size for two axes: scipy.fft's error
        d.irfft2(spec, s=6)
    with pytest.raises(ValueError):
        scipy.fft.irfft2(spec, s=6)
