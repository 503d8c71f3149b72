"""slipchain: the multi-contact friction model of Braun, Steenwyk, Warhadpande and Persson,
"On the dependency of friction on load: Theory and experiment", EPL 113, 56002 (2016).

Data flow, one way: config -> system (``model``) -> simulation (``engine``: compiled kernel in
chunks) -> observables and the run Dataset (``results``) -> store (``sweeps``) -> analysis ->
plots; ``workflows`` chain them into jobs and ``cli`` exposes them. See docs/architecture.md.
"""

from ._version import __version__
from .engine import BackendName, run, simulate, simulate_batch
from .model import Config, ConfigError, ContactLaw, State, System, build_system, initial_state, load_config, make_config
from .results import Status, read_dataset, summary, write_dataset
from .sweeps import open_sweep, run_sweep

__all__ = [
    "BackendName",
    "Config",
    "ConfigError",
    "ContactLaw",
    "State",
    "Status",
    "System",
    "__version__",
    "build_system",
    "initial_state",
    "load_config",
    "make_config",
    "open_sweep",
    "read_dataset",
    "run",
    "run_sweep",
    "simulate",
    "simulate_batch",
    "summary",
    "write_dataset",
]
