"""Read tmrotor recordings (MCAP files of protobuf messages) into pandas DataFrames.

>>> import tmrotor
>>> rec = tmrotor.read("sweep.mcap")
>>> rec.info["points"], rec.info["complete"]
>>> rec.branch[["omega_rad_s", "stable", "amp_rms_node8_m"]]
>>> rec.orbit(rec.points[-1], samples=256)

:func:`read` returns a :class:`Recording`; see its docstring and ``python/README.md`` for
the tables and their columns. ``tmrotor.rerun`` (extra ``[rerun]``) exports a recording to
a Rerun ``.rrd`` file.
"""

from ._scan import LogEntry, RecordingError
from .recording import (
    TABLES,
    Recording,
    bearing_keys,
    node_key,
    read,
    thermal_node_key,
)

__version__ = "0.1.0"

__all__ = [
    "TABLES",
    "LogEntry",
    "Recording",
    "RecordingError",
    "__version__",
    "bearing_keys",
    "node_key",
    "read",
    "thermal_node_key",
]
