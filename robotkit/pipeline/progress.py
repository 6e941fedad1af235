"""The progress line of a build on a terminal: tasks done, time so far, and what is running.

    [12/40] 0:23  ur5:collision:shoulder 9 s, ur5:collision:wrist2 4 s

One line on ``stream``, rewritten in place (carriage return, erase to the end of the line)
when a task starts or ends and every ``interval`` seconds by a background thread, so that a
minute of CoACD shows its clock moving.  It is cut to the terminal's width (a wrapped line
could not be erased).  Tasks that took at least ``slow`` seconds get a line of their own
(``  ur5:collision:shoulder: 9.1 s``) above it.

Quiet unless ``stream.isatty()``: logs, pipes and CI output carry no progress at all,
unless ``log_every`` asks for a plain line (no control characters) every so many seconds
(a long batch, ``robotkit catalogue``, in a CI log).  ``eta`` adds an estimate of the time
left from the pace so far.
Every write holds one lock, and :meth:`Progress.clear` (called when the run ends, before
the caller prints any warning or error) erases the line and stops the thread, so a
progress line never ends up inside another line.
"""

from __future__ import annotations

import shutil
import threading
import time


def _clock(seconds: float) -> str:
    m, s = divmod(int(seconds), 60)
    return f"{m}:{s:02d}"


class Progress:
    """Progress of ``total`` tasks on ``stream`` (quiet when it is not a terminal)."""

    def __init__(self, stream, total: int = 0, *, interval: float = 1.0, slow: float = 1.0, clock=time.monotonic,
                 width=None, eta: bool = False, log_every: float | None = None, label: str = ""):
        self.stream = stream
        self.active = stream is not None and bool(getattr(stream, "isatty", lambda: False)())
        self.eta = eta
        self.label = label
        self.log_every = log_every if stream is not None and not self.active else None
        self._logged = clock()
        self.total = total
        self.done = 0
        self.interval = interval
        self.slow = slow
        self.clock = clock
        self.width = width  # None: the terminal's width at each write
        self.running: dict[str, float] = {}  # task name -> start time, in start order
        self.start = clock()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = None
        self._shown = False

    # the task events ---------------------------------------------------------------------
    def started(self, name: str) -> None:
        with self._lock:
            self.running[name] = self.clock()
            self._draw()
        if self.active and self._thread is None and self.interval > 0:
            self._thread = threading.Thread(target=self._tick, name="robotkit-progress", daemon=True)
            self._thread.start()

    def finished(self, name: str, *, ran: bool = True) -> float | None:
        """A task ended (``ran``: it ran, else it was up to date); returns its time if it ran."""
        with self._lock:
            start = self.running.pop(name, None)
            self.done += 1
            elapsed = None if start is None else self.clock() - start
            if self.active and ran and elapsed is not None and elapsed >= self.slow:
                self._write(f"\r\033[K  {name}: {elapsed:.1f} s\n")
                self._shown = False
            self._draw()
            if self.log_every is not None and self.clock() - self._logged >= self.log_every:
                self._logged = self.clock()
                self._write(self.head().strip() + "\n")
        return elapsed

    def clear(self) -> None:
        """Erase the line and stop the clock: call before printing anything else."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join()
        with self._lock:
            if self._shown:
                self._write("\r\033[K")
                self._shown = False

    # the line ------------------------------------------------------------------------------
    def line(self) -> str:
        """The progress line (without control characters), cut to the width."""
        now = self.clock()
        head = self.head()
        tasks = ", ".join(f"{name} {int(now - t)} s" for name, t in self.running.items())
        text = f"{head}  {tasks}" if tasks else head
        width = self.width if self.width is not None else shutil.get_terminal_size((80, 24)).columns
        limit = max(width - 1, 10)  # the last column would wrap on some terminals
        return text if len(text) <= limit else text[:limit - 3] + "..."

    def head(self) -> str:
        """Tasks done, the clock and (with ``eta``) the time left."""
        elapsed = self.clock() - self.start
        head = f"  {self.label}[{self.done}/{self.total}] {_clock(elapsed)}" if self.total else \
            f"  {self.label}{_clock(elapsed)}"
        if self.eta and self.total and 0 < self.done < self.total:
            head += f", about {_clock(elapsed / self.done * (self.total - self.done))} left"
        return head

    def _draw(self) -> None:
        if self.active and not self._stop.is_set():
            self._write(f"\r\033[K{self.line()}")
            self._shown = True

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # a closed terminal: no progress, the build goes on
            self.active = False

    def _tick(self) -> None:
        while not self._stop.wait(self.interval):
            with self._lock:
                if self.running:
                    self._draw()
