"""Test set-up shared by every test: numba's cache, hypothesis, and the ``backend`` fixture.

The ``backend`` fixture runs a physics test on every backend, as hoomd's and PySDM's test suites
do: the CPU backend, and the CUDA backend, on numba's CUDA simulator (set here, before numba is
imported) unless ``SLIPCHAIN_TEST_CUDA=hardware`` asks for a real GPU. The simulator runs the
kernel as Python threads (about 50 ms per step for N = 11), so tests size their runs with
``backend.small``.
"""

import os
from dataclasses import dataclass

os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".numba_cache"))
if os.environ.get("SLIPCHAIN_TEST_CUDA") != "hardware":
    os.environ["NUMBA_ENABLE_CUDASIM"] = "1"  # must precede the first import of numba

import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

# Numba compiles on first call; timings of single examples mean nothing here.
settings.register_profile("slipchain", deadline=None, derandomize=True)
settings.load_profile("slipchain")


@dataclass(frozen=True)
class BackendCase:
    """A backend under test: its name for ``run(..., backend=name)``, and whether runs must be tiny."""

    name: str
    small: bool

    def steps(self, cpu: int, cuda: int) -> int:
        """Step count (or any size) for this backend: ``cuda`` on the simulator, else ``cpu``."""
        return cuda if self.small else cpu


@pytest.fixture(params=["cpu", pytest.param("gpu", marks=pytest.mark.cuda)])
def backend(request) -> BackendCase:
    if request.param == "gpu":
        from slipchain.engine.backends.cuda import cuda_available

        if not cuda_available():  # pragma: no cover - numba without its CUDA target
            pytest.skip("numba.cuda is not usable here (neither a GPU nor the simulator)")
        return BackendCase("gpu", small=os.environ.get("NUMBA_ENABLE_CUDASIM") == "1")
    return BackendCase("cpu", small=False)


# `slipchain` (the command line) that stops itself with SIGSTOP right after writing its first
# checkpoint, so that a test can send it a signal at that point whatever the machine's speed
# (issue 30: polling for the checkpoint file raced the end of the run).
_STOP_AFTER_FIRST_CHECKPOINT = (
    "import os, signal\n"
    "from slipchain.engine import checkpoint as c\n"
    "save = c.Checkpointer.save\n"
    "def stop_after(self):\n"
    "    save(self)\n"
    "    if self.writes == 1:\n"
    "        os.kill(os.getpid(), signal.SIGSTOP)\n"
    "c.Checkpointer.save = stop_after\n"
    "from slipchain.cli import app\n"
    "app(prog_name='slipchain')\n")


@pytest.fixture
def cli_stopping_at_first_checkpoint() -> list[str]:
    """The command prefix of a ``slipchain`` that stops itself after its first checkpoint (wait for it
    with ``os.waitpid(pid, os.WUNTRACED)``)."""
    import sys

    return [sys.executable, "-c", _STOP_AFTER_FIRST_CHECKPOINT]


# `slipchain` (the command line) that stops itself with SIGSTOP right after storing its k-th member
# (of a sweep, or of a mu-max bisection's rounds): a signal sent then lands there on any machine.
_STOP_AFTER_MEMBERS = (
    "import os, signal, sys\n"
    "from slipchain.sweeps.store import Store\n"
    "k, write, done = int(sys.argv.pop(1)), Store.write_member, []\n"
    "def stop_after(self, member, ds):\n"
    "    path = write(self, member, ds)\n"
    "    done.append(member.id)\n"
    "    if len(done) == k:\n"
    "        os.kill(os.getpid(), signal.SIGSTOP)\n"
    "    return path\n"
    "Store.write_member = stop_after\n"
    "from slipchain.cli import app\n"
    "app(prog_name='slipchain')\n")


@pytest.fixture
def cli_stopping_after_members():
    """``k -> command prefix`` of a ``slipchain`` that stops itself (SIGSTOP) once it has stored k
    members; append the command's arguments, and wait with ``os.waitpid(pid, os.WUNTRACED)``."""
    import sys

    return lambda k: [sys.executable, "-c", _STOP_AFTER_MEMBERS, str(k)]


@dataclass(frozen=True)
class CliResult:
    """What a ``slipchain`` command gave, under subprocess.CompletedProcess's names."""

    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def slipchain_cli():
    """``(*args, cwd=None, env=None) -> CliResult``: ``slipchain ARGS`` run in this process by typer's
    runner: the same app, parsing, exit code and streams as the command, without a new Python (whose
    imports cost about 3 s a call here, over a third of some tests' time). For commands that compute in
    this process (figures, tables, analyses, single runs, rejected input); commands that start worker
    processes (sweep, reproduce, mu-max's bisections) or whose test is about the process (signals, a
    fresh process's bits) keep ``subprocess``. What a command installs in its process (the SIGTERM
    handler, the warning display) is put back after it, and an exception other than an exit comes back
    with its traceback in ``stderr``, as the command would print it."""
    import signal
    import traceback
    import warnings

    from typer.testing import CliRunner

    from slipchain.cli import app

    def invoke(*args, cwd=None, env=None) -> CliResult:
        term, show, here = signal.getsignal(signal.SIGTERM), warnings.showwarning, os.getcwd()
        try:
            if cwd is not None:
                os.chdir(cwd)
            r = CliRunner().invoke(app, [str(a) for a in args], env=env, prog_name="slipchain")
        finally:
            os.chdir(here)
            signal.signal(signal.SIGTERM, term)
            warnings.showwarning = show
        stderr = r.stderr
        if r.exc_info is not None and not isinstance(r.exception, SystemExit):
            stderr += "".join(traceback.format_exception(*r.exc_info))
        return CliResult(r.exit_code, r.stdout, stderr)

    return invoke


@pytest.fixture
def store_of_runs():
    """``(path, sweep) -> Store``: a sweep's store whose members are run in this process, one after the
    other, and written as the sweep's tasks write them (``slipchain.run`` is bit for bit a member run on
    a worker: tests/workflows/test_runner.py). For tests of what reads a store; the sweeps on Dask are
    test_runner's. ``sweep``: a SweepDefinition, or the path of its TOML."""
    from slipchain import run
    from slipchain.sweeps.definition import load_sweep_definition
    from slipchain.sweeps.store import Store

    def make(path, sweep):
        if isinstance(sweep, (str, os.PathLike)):
            sweep = load_sweep_definition(sweep)
        st = Store.open(path, sweep)
        for m in sweep.members:
            st.write_member(m, run(m.config))
        return st

    return make


@pytest.fixture
def checkpointed_releases(tmp_path):
    """A store of two released 4 x 4 slabs (weights 0.3 and 0.9; tests/physics/test_dead_weight.py's RELEASE) run
    without the stop rules and checkpointed, not stored, as a sweep leaves a run in flight: (store path, sweep,
    Store). Over 0.03 s the rules would call 0.9 a runaway and 0.3 held."""
    from slipchain import run
    from slipchain.sweeps.definition import make_sweep
    from slipchain.sweeps.store import Store

    release = dict(geometry="slab", N=4, Ly=4, N_L=50, theta=1.0, delta=0.0, epsilon=1.0, start="rest",
                   top_mass=1e-6, eta_c=1e5, t_ramp=1e-5, t_decide=0.02, t_max=0.03, output_interval=2e-5)
    sweep = make_sweep({"name": "slab", "base": {**release, "dead_weight": 0.3}, "grid": {"dead_weight": [0.3, 0.9]}})
    st = Store.open(tmp_path / "s", sweep)
    for m in sweep.members:
        run(m.config, checkpoint=st.checkpoint_path([m]))
    return tmp_path / "s", sweep, st
