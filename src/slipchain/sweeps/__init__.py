"""Many runs: sweep definitions (TOML grids), their execution on Dask, and the resumable store of one file per member."""

from .definition import Member, Preset, SweepDefinition, SweepError, SweepWarning, load_preset, load_sweep_definition, make_sweep, member_id
from .executor import SweepReport, run_sweep
from .store import Store, open_sweep

__all__ = ["Member", "Preset", "Store", "SweepDefinition", "SweepError", "SweepReport", "SweepWarning", "load_preset",
           "load_sweep_definition", "make_sweep", "member_id", "open_sweep", "run_sweep"]
