"""What a run produces: its status and Dataset schema, the statistics of a time series, the physics checks, atomic files."""

from .io import atomic_write, read_attrs, read_dataset, write_dataset, write_text_atomic
from .schema import RUN_ATTRIBUTES, RUN_VARIABLES, SUMMARY_KEYS, Recording, Status, assemble_run, summary
from .velocity import VelocityStatus, steady_velocity

__all__ = ["RUN_ATTRIBUTES", "RUN_VARIABLES", "SUMMARY_KEYS", "Recording", "Status", "VelocityStatus", "assemble_run",
           "atomic_write", "read_attrs", "read_dataset", "steady_velocity", "summary", "write_dataset", "write_text_atomic"]
