"""How it is simulated: the scheme (written once), CPU and CUDA backends, run control, the one time loop, a solve_ivp reference."""

from .backends import BackendName, get_backend
from .simulate import run, simulate, simulate_batch

__all__ = ["BackendName", "get_backend", "run", "simulate", "simulate_batch"]
