"""The outside programs a check runs (``ign sdf -p``: libsdformat's reading of a file), each run
once per check of a build folder and started early, in a thread beside the other stages.

``ign`` is a Ruby program: about 0.4 s of CPU per call, and a check reads the URDF through it
twice (the equivalence stage and Gazebo's view).  :func:`started` runs each command given in a
thread from the start; :func:`run` gives a started command's result (waiting for it), or runs
the command there and then when it was not started."""

from __future__ import annotations

import contextlib
import subprocess
import threading
from concurrent.futures import Future, ThreadPoolExecutor

_started: dict[tuple[str, ...], Future] = {}
_lock = threading.Lock()


def capture(cmd: tuple[str, ...]) -> subprocess.CompletedProcess:
    """The command's exit status, stdout and stderr (text)."""
    return subprocess.run(list(cmd), capture_output=True, text=True)


def run(cmd: list[str]) -> subprocess.CompletedProcess:
    """``cmd``'s result: the started run's when :func:`started` began it, else a run now."""
    with _lock:
        future = _started.get(tuple(cmd))
    return future.result() if future is not None else capture(tuple(cmd))


def libsdformat(path) -> subprocess.CompletedProcess:
    """``ign sdf -p PATH``: libsdformat's reading of a URDF or SDF, printed as SDF."""
    return run(["ign", "sdf", "-p", str(path)])


@contextlib.contextmanager
def started(cmds: list[list[str]]):
    """Within the block, each of ``cmds`` runs (once) in a thread of its own from the start."""
    keys = [tuple(c) for c in dict.fromkeys(tuple(c) for c in cmds)]
    pool = ThreadPoolExecutor(max_workers=max(1, len(keys)), thread_name_prefix="robotkit-program")
    with _lock:
        mine = [k for k in keys if k not in _started]
        for key in mine:
            _started[key] = pool.submit(capture, key)
    try:
        yield
    finally:
        with _lock:
            for key in mine:
                _started.pop(key, None)
        pool.shutdown(wait=True)
