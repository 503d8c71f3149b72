import os

os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".numba_cache"))

from hypothesis import settings

# Numba compiles on first call; timings of single examples mean nothing here.
settings.register_profile("slipchain", deadline=None, derandomize=True)
settings.load_profile("slipchain")
