"""slipchain: the multi-contact friction model of Braun, Steenwyk, Warhadpande and Persson,
"On the dependency of friction on load: Theory and experiment", EPL 113, 56002 (2016).

Data flow: config -> system -> simulation (compiled kernel in chunks) -> observables ->
result Dataset -> store -> plots.
"""

from ._version import __version__
from .config import Config, ConfigError, load_config, make_config
from .contact_law import ContactLaw
from .io import read_dataset, write_dataset
from .simulation import run, simulate, summary
from .system import State, System, build_system, initial_state

__all__ = [
    "Config",
    "ConfigError",
    "ContactLaw",
    "State",
    "System",
    "__version__",
    "build_system",
    "initial_state",
    "load_config",
    "make_config",
    "read_dataset",
    "run",
    "simulate",
    "summary",
    "write_dataset",
]
