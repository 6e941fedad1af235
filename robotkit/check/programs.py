"""The outside programs a check runs (``ign sdf -k`` and ``ign sdf -p``: libsdformat's check and
reading of a file), each run once per check of a build folder and started early, beside the
other stages.

``ign`` is a Ruby program that loads libsdformat for each call: about 0.45 s of CPU each, and a
check makes three (the SDF checked, the URDF and the SDF read; the equivalence stage and
Gazebo's view both read the URDF).  :func:`started` runs them from the start in one helper
process that loads libsdformat once and calls the functions ``ign`` calls (``cmdCheck``,
``cmdPrint``: the same output and exit status, about 0.6 s of CPU for the three), or, where that
library is not the one whose functions are known (sdformat 12), each ``ign`` in a thread.
:func:`run` gives a started command's result (waiting for it), or runs the command there and
then when it was not started."""

from __future__ import annotations

import contextlib
import ctypes.util
import os
import subprocess
import sys
import tempfile
import threading
from concurrent.futures import Future, ThreadPoolExecutor

_started: dict[tuple[str, ...], Future] = {}
_lock = threading.Lock()

FUNCTIONS = {"-k": "cmdCheck", "-p": "cmdPrint"}
"""``ign sdf`` option -> the libsdformat function it calls with the file's absolute path."""
LIBRARY = "sdformat12"
"""The libsdformat whose ``cmdCheck(const char *)`` and ``cmdPrint(const char *)`` are known
(Ubuntu 22.04's, which ``ign sdf`` loads); another is run through ``ign``."""

_BATCH = r"""
import ctypes, os, sys
lib, libc = ctypes.CDLL(sys.argv[1]), ctypes.CDLL(None)
with open(sys.argv[2], "w") as results:
    for i in range(3, len(sys.argv), 4):
        name, path, out, err = sys.argv[i:i + 4]
        function = getattr(lib, name)
        function.argtypes, function.restype = [ctypes.c_char_p], ctypes.c_int
        with open(out, "wb") as o, open(err, "wb") as e:
            os.dup2(o.fileno(), 1)
            os.dup2(e.fileno(), 2)
            rc = function(os.fsencode(path))
            libc.fflush(None)
        results.write(f"{rc & 255}\n")
        results.flush()
"""


SPAWN = threading.Lock()
"""Held while a program is started (its fork and exec: :func:`popen`) and while the check forks a
worker process.  A process forked while another thread starts a program keeps the pipe through
which ``subprocess`` learns that the program's exec succeeded, and the start then waits until
that worker process exits: a check that never ends (seen when libsdformat's helper was started
beside the forks)."""


def _fresh_spawn_lock() -> None:  # a worker forked under the lock starts with it free
    global SPAWN
    SPAWN = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_fresh_spawn_lock)


def popen(cmd: list[str], **options) -> subprocess.Popen:
    """``subprocess.Popen(cmd, **options)``, started under :data:`SPAWN`."""
    with SPAWN:
        return subprocess.Popen(cmd, **options)


def capture(cmd: tuple[str, ...]) -> subprocess.CompletedProcess:
    """The command's exit status, stdout and stderr (text)."""
    proc = popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = proc.communicate()
    return subprocess.CompletedProcess(list(cmd), proc.returncode, out, err)


def run(cmd: list[str]) -> subprocess.CompletedProcess:
    """``cmd``'s result: the started run's when :func:`started` began it, else a run now."""
    with _lock:
        future = _started.get(tuple(cmd))
    return future.result() if future is not None else capture(tuple(cmd))


def is_started(cmd: list[str]) -> bool:
    with _lock:
        return tuple(cmd) in _started


def libsdformat(path) -> subprocess.CompletedProcess:
    """``ign sdf -p PATH``: libsdformat's reading of a URDF or SDF, printed as SDF."""
    return run(["ign", "sdf", "-p", str(path)])


def _in_one_process(keys: list[tuple[str, ...]], library: str) -> dict[tuple[str, ...], subprocess.CompletedProcess]:
    """The ``ign sdf`` commands ``keys`` run as ``ign`` runs them, in one process that loads
    ``library`` once; a command without a result (the process died) is left out."""
    with tempfile.TemporaryDirectory(prefix="robotkit-sdformat-") as tmp:
        argv = [sys.executable, "-S", "-c", _BATCH, library, os.path.join(tmp, "rc")]
        for k, key in enumerate(keys):
            argv += [FUNCTIONS[key[2]], os.path.abspath(key[3]), os.path.join(tmp, f"{k}.out"),
                     os.path.join(tmp, f"{k}.err")]
        popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).wait()
        try:
            with open(os.path.join(tmp, "rc"), encoding="utf-8") as f:
                codes = [int(line) for line in f.read().split()]
        except OSError:
            codes = []
        out = {}
        for k, (key, rc) in enumerate(zip(keys, codes)):
            text = [open(os.path.join(tmp, f"{k}.{s}"), encoding="utf-8", errors="replace").read()
                    for s in ("out", "err")]
            out[key] = subprocess.CompletedProcess(list(key), rc, text[0], text[1])
        return out


def _batch(keys: list[tuple[str, ...]], futures: dict[tuple[str, ...], Future], library: str) -> None:
    try:
        done = _in_one_process(keys, library)
    except Exception:  # noqa: BLE001  (each command then runs through ign)
        done = {}
    for key in keys:
        try:
            futures[key].set_result(done[key] if key in done else capture(key))
        except Exception as exc:  # noqa: BLE001
            futures[key].set_exception(exc)


@contextlib.contextmanager
def started(cmds: list[list[str]], known: dict[tuple[str, ...], subprocess.CompletedProcess] | None = None):
    """Within the block, each of ``cmds`` (``ign sdf -k|-p FILE``) runs once, started now; the
    ones in ``known`` are not run: their results are those (an earlier run's, cached)."""
    keys = [k for k in dict.fromkeys(tuple(c) for c in cmds)]
    known = {k: v for k, v in (known or {}).items() if k in keys}
    with _lock:
        given = [k for k in known if k not in _started]
        for k in given:
            _started[k] = Future()
            _started[k].set_result(known[k])
    keys = [k for k in keys if k not in known]
    library = ctypes.util.find_library(LIBRARY) if keys else None
    batch = library is not None and all(len(k) == 4 and k[:2] == ("ign", "sdf") and k[2] in FUNCTIONS for k in keys)
    pool = ThreadPoolExecutor(max_workers=1 if batch else max(1, len(keys)), thread_name_prefix="robotkit-program")
    with _lock:
        mine = [k for k in keys if k not in _started]
        if batch and mine:
            futures = {k: Future() for k in mine}
            _started.update(futures)
            pool.submit(_batch, mine, futures, library)
        else:
            _started.update({k: pool.submit(capture, k) for k in mine})
    try:
        yield
    finally:
        with _lock:
            for key in mine + given:
                _started.pop(key, None)
        pool.shutdown(wait=True)
