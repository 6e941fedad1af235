"""The progress line of long builds (robotkit.pipeline.progress): on a terminal only, erased before anything else."""

from __future__ import annotations

import pytest

import io
import os
import subprocess
import sys
import threading

from conftest import write_recipe
from robotkit.pipeline.progress import Progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_progress_line_names_running_tasks_with_their_time():
    out, clock = Terminal(), Clock()
    p = Progress(out, total=5, interval=0, clock=clock, width=200)
    p.started("r:mesh:a")
    clock.now += 2.4
    p.started("r:collision:b")
    clock.now += 63.0
    assert p.line() == "  [0/5] 1:05  r:mesh:a 65 s, r:collision:b 63 s"
    p.finished("r:mesh:a")  # slow: a line of its own above the progress line
    assert out.getvalue().endswith("\r\033[K  r:mesh:a: 65.4 s\n\r\033[K  [1/5] 1:05  r:collision:b 63 s")
    p.finished("r:up-to-date", ran=False)
    assert p.line() == "  [2/5] 1:05  r:collision:b 63 s"
    p.width = 30  # cut to the terminal's width, never wrapped
    assert p.line() == "  [2/5] 1:05  r:collision:..." and len(p.line()) == 29
    p.clear()
    assert out.getvalue().endswith("\r\033[K")
    before = out.getvalue()
    p.finished("r:collision:b")
    assert out.getvalue() == before + "\r\033[K  r:collision:b: 63.0 s\n"  # no progress line after clear


def test_quick_tasks_get_no_line_of_their_own():
    out, clock = Terminal(), Clock()
    p = Progress(out, total=1, interval=0, clock=clock, width=80)
    p.started("r:urdf")
    clock.now += 0.5
    p.finished("r:urdf")
    p.clear()
    assert out.getvalue() == "\r\033[K  [0/1] 0:00  r:urdf 0 s\r\033[K  [1/1] 0:00\r\033[K"


def test_quiet_when_not_a_terminal():
    out = io.StringIO()
    p = Progress(out, total=2, interval=0.001)
    p.started("a")
    p.finished("a")
    p.clear()
    assert out.getvalue() == ""


def test_clock_moves_while_a_task_runs_and_stops_at_clear():
    out, clock = Terminal(), Clock()
    drawn = threading.Event()

    class Watch(Terminal):
        def write(self, text):
            if "1:40" in text:
                drawn.set()
            return super().write(text)

    out = Watch()
    p = Progress(out, total=1, interval=0.005, clock=clock, width=80)
    p.started("r:collision:x")
    clock.now += 100
    assert drawn.wait(5)  # redrawn by the clock thread, with no task event
    p.clear()
    assert out.getvalue().endswith("\r\033[K")
    size = len(out.getvalue())
    threading.Event().wait(0.05)
    assert len(out.getvalue()) == size  # the thread has stopped


@pytest.mark.slow
def test_build_progress_on_a_terminal_only(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: p
        links:
          a: {visual: {box: {size: [0.1, 0.1, 0.1]}}}
        """)
    cmd = [sys.executable, "-m", "robotkit", "build", str(recipe), "--no-report", "-j", "1"]
    piped = subprocess.run(cmd + ["--out", str(tmp_path / "piped")], capture_output=True, text=True)
    assert piped.returncode == 0, piped.stderr
    assert "\r" not in piped.stderr and "\033" not in piped.stderr and "[" not in piped.stderr

    import pty

    leader, follower = pty.openpty()
    proc = subprocess.Popen(cmd + ["--out", str(tmp_path / "tty")], stdout=subprocess.PIPE, stderr=follower)
    os.close(follower)
    chunks = []
    while True:
        try:
            data = os.read(leader, 4096)
        except OSError:  # the child closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    proc.wait()
    os.close(leader)
    assert proc.returncode == 0
    shown = b"".join(chunks).decode()
    assert "\r\033[K  [" in shown and " p:urdf " in shown  # a task was shown running
    head, tail = shown.rsplit("\r\033[K", 1)  # the line erased at the end, before the warnings
    assert "maintainer" in tail and "\033" not in tail and "\r" not in tail.replace("\r\n", "")
    assert "maintainer" not in head


def test_time_left_and_plain_lines_for_logs():
    """A batch's progress (robotkit catalogue): the time left from the pace so far, and off a
    terminal a plain line every ``log_every`` seconds."""
    now = [0.0]
    out = io.StringIO()  # not a terminal
    p = Progress(out, total=4, interval=0, clock=lambda: now[0], eta=True, log_every=10.0, label="catalogue ")
    p.started("a")
    now[0] = 5.0
    p.finished("a")  # 5 s after the start: no line yet
    assert out.getvalue() == ""
    now[0] = 12.0
    p.finished("b")
    assert out.getvalue() == "catalogue [2/4] 0:12, about 0:12 left\n"
    now[0] = 15.0
    p.finished("c")  # within 10 s of the last line
    assert out.getvalue().count("\n") == 1
