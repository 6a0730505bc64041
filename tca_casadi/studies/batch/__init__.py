"""Batch studies (``tca-casadi study``): one scenario solved at many samples (:class:`Study`:
grids, Monte Carlo, Sobol', Latin hypercube, explicit rows), serially, on local processes or a
Dask cluster (``executors``), what a worker does (``worker``), and the result type
:class:`StudyResult`."""
from .design import Axis, Design, build_design, rows_design
from .result import StudyResult
from .study import AUTO_JIT_SAMPLES, Study, read_rows

__all__ = ["Study", "StudyResult", "Axis", "Design", "build_design", "rows_design", "read_rows", "AUTO_JIT_SAMPLES"]
