"""The paper's friction-tester experiment (Figs. 1 to 3) as data: inputs, mu and p0 with uncertainties, maxima, the load test, synthetic data.

:mod:`.inputs` reads and checks ``runs.csv`` and ``traces.csv``; the steady velocity of a trace is
:func:`slipchain.results.velocity.steady_velocity` (the same algorithm measures the model's
dead-weight runs); :mod:`.analysis` gives mu, p0, the first maxima and the load test; :mod:`.synth`
simulates a dead-weight tester for examples and tests. The whole analysis with its files and
figures is :func:`slipchain.workflows.tester.analyze`.
"""

from .inputs import Run, TesterDataError, read_runs, read_traces

__all__ = ["Run", "TesterDataError", "read_runs", "read_traces"]
