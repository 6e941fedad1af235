"""Expensive mesh work on a Dask cluster (``robotkit build --scheduler ADDRESS``).

The doit graph stays the one source of dependencies: doit decides what is out of date and
runs the tasks as it always does.  Only the computation inside the cache's
``get_or_compute`` (CoACD, hulls, decimation: the work whose result the mesh cache keeps)
is sent to the cluster; the result comes back to the task, which stores it in the cache
(:mod:`robotkit.mesh.cache`, local and shared) and writes its files locally.  So the
workers need robotkit installed and nothing else: no access to the recipe, the output
folder or the cache.  A worker that dies is replaced by Dask rescheduling its task
(``pure=False``: every submission runs; the cache key decides what is reused).

The scheduler comes from ``--scheduler ADDRESS`` (exported to the doit worker processes
as ``ROBOTKIT_SCHEDULER``), else Dask's own ``DASK_SCHEDULER_ADDRESS``.  ``local`` starts a
scheduler and one single-threaded worker per core as separate processes
(:class:`LocalCluster`) for the length of the command.

Without a scheduler nothing here is imported.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from robotkit.errors import Problem, RobotkitError

ENV = "ROBOTKIT_SCHEDULER"
DASK_ENV = "DASK_SCHEDULER_ADDRESS"

_client = None
_client_pid = None


def scheduler_address() -> str | None:
    """The scheduler this process sends mesh work to, or None."""
    return os.environ.get(ENV) or os.environ.get(DASK_ENV) or None


def run(compute):
    """``compute()``, on the cluster when one is configured, else here."""
    address = scheduler_address()
    if not address:
        return compute()
    client = _get_client(address)
    return client.submit(compute, pure=False).result()


def _get_client(address: str):
    """One client per process (doit's worker processes each make their own after the fork)."""
    global _client, _client_pid
    if _client is None or _client_pid != os.getpid():
        try:
            from distributed import Client
        except ImportError:
            raise RobotkitError(Problem("--scheduler needs Dask: pip install 'robotkit[distributed]'")) from None
        _client = Client(address, timeout="30s", set_as_default=False)
        _client_pid = os.getpid()
    return _client


def cluster_threads(address: str) -> int:
    """How many tasks the cluster runs at once (asked from a separate process, so that the
    CLI process holds no Dask threads when doit forks its workers)."""
    code = ("import sys; from distributed import Client; c = Client(sys.argv[1], timeout='30s'); "
            "print(sum(c.nthreads().values())); c.close()")
    try:
        out = subprocess.run([sys.executable, "-c", code, address], capture_output=True, text=True,
                             timeout=120, check=True).stdout
        return max(1, int(out.strip().splitlines()[-1]))
    except (subprocess.SubprocessError, ValueError, IndexError, OSError) as exc:
        raise RobotkitError(Problem(f"--scheduler {address}: cannot reach the Dask scheduler ({exc})")) from None


class LocalCluster:
    """A Dask scheduler and ``workers`` single-threaded worker processes on this machine, as
    separate processes (``dask scheduler`` / ``dask worker``), stopped on exit."""

    def __init__(self, workers: int | None = None):
        self.workers = workers or os.cpu_count() or 1
        self.procs: list[subprocess.Popen] = []
        self.address = ""
        self._dir = None

    def __enter__(self) -> "LocalCluster":
        self._dir = tempfile.TemporaryDirectory(prefix="robotkit-dask-")
        sched_file = Path(self._dir.name) / "scheduler.json"
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
        env.pop(ENV, None)
        env.pop(DASK_ENV, None)
        self.procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
             "--no-dashboard", "--scheduler-file", str(sched_file)], env=env, **quiet))
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                self.address = json.loads(sched_file.read_text())["address"]
                break
            except (OSError, ValueError, KeyError):
                if self.procs[0].poll() is not None:
                    break
                time.sleep(0.1)
        if not self.address:
            self.__exit__(None, None, None)
            raise RobotkitError(Problem("--scheduler local: the Dask scheduler did not start"))
        self.procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", self.address, "--nworkers", str(self.workers),
             "--nthreads", "1", "--no-dashboard", "--local-directory", self._dir.name], env=env, **quiet))
        return self

    def __exit__(self, *exc) -> None:
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in reversed(self.procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        if self._dir is not None:
            self._dir.cleanup()
