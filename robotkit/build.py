"""The build: recipes -> resolved robots -> doit tasks -> files under the output folder.

    load + validate each recipe   (robotkit.recipe.load)   all problems together, exit 2
    resolve to a Robot            (robotkit.model.resolve) tree checks, SI units
    task dicts                    (robotkit.tasks)         file_dep, targets, config_changed
    run them with doit            (here)                   incremental, -j N worker processes

doit's own record (which tasks ran, which were up to date) is returned in a
:class:`BuildResult`; the CLI prints it, and the tests assert on it.
"""

from __future__ import annotations

import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from robotkit.errors import Problem, RobotkitError


@dataclass
class BuildResult:
    ran: list[str] = field(default_factory=list)
    uptodate: list[str] = field(default_factory=list)
    failed: list[tuple[str, str]] = field(default_factory=list)  # (task, message) user errors
    errors: list[tuple[str, str]] = field(default_factory=list)  # (task, traceback) bugs
    warnings: list[str] = field(default_factory=list)
    robots: list[str] = field(default_factory=list)
    exit_status: int = 0  # of the failed tasks: 2 bad input, 1 a robot a consumer refuses


SLOW = 1.0  # seconds: tasks at least this long are reported with their time


class _Recorder:
    """A doit reporter that records instead of printing."""

    def __init__(self, result: BuildResult, echo=None, progress=None):
        self.result = result
        self.echo = echo
        self.progress = progress  # a stream for progress of long tasks (None: quiet)
        self.started: dict[str, float] = {}
        self.failures = []
        self.runtime_errors: list[str] = []
        self.not_written: set[str] = set()  # refused by a consumer (exit 1), or not run for a failed dependency

    def initialize(self, tasks, selected_tasks):
        pass

    def get_status(self, task):
        pass

    def execute_task(self, task):
        import time

        if task.actions:
            self.result.ran.append(task.name)
            self.started[task.name] = time.perf_counter()
            if self.echo:
                self.echo(f"  {task.name}")
            elif self.progress is not None and self.progress.isatty():
                self.progress.write(f"\r\033[K  running {task.name}")
                self.progress.flush()

    def add_failure(self, task, fail):
        from doit.exceptions import TaskFailed, UnmetDependency

        if isinstance(fail, UnmetDependency):
            self.not_written.add(task.name)
            return
        if isinstance(fail, TaskFailed):
            self.result.failed.append((task.name, fail.message))
            self.result.exit_status = max(self.result.exit_status, getattr(fail, "exit_status", 2))
            if getattr(fail, "exit_status", 2) == 1:
                self.not_written.add(task.name)
        else:
            self.result.errors.append((task.name, fail.get_msg()))

    def add_success(self, task):
        import time

        start = self.started.pop(task.name, None)
        if start is None or self.progress is None or not self.progress.isatty():
            return  # quiet when not a terminal: logs and CI output stay deterministic
        elapsed = time.perf_counter() - start
        if elapsed >= SLOW:  # long tasks (CoACD, decimation) are named with their time
            self.progress.write(f"\r\033[K  {task.name}: {elapsed:.1f} s\n")
            self.progress.flush()

    def skip_uptodate(self, task):
        self.result.uptodate.append(task.name)

    def skip_ignore(self, task):
        pass

    def cleanup_error(self, exception):
        self.result.errors.append(("cleanup", exception.get_msg()))

    def runtime_error(self, msg):
        self.runtime_errors.append(msg)

    def teardown_task(self, task):
        pass

    def complete_run(self):
        if self.progress is not None and self.progress.isatty():
            self.progress.write("\r\033[K")
            self.progress.flush()


def state_db(out_dir: Path) -> str:
    from robotkit.tasks import STATE

    return str(out_dir / STATE / "doit.sqlite3")


def doit_config(out_dir: Path, reporter=None) -> dict:
    """The doit settings shared by ``robotkit build`` and dodo.py."""
    cfg = {
        "dep_file": state_db(out_dir),
        "backend": "sqlite3",
        "check_file_uptodate": "md5",
        "verbosity": 0,
        "continue": True,
    }
    if reporter is not None:
        cfg["reporter"] = reporter
        cfg["outfile"] = io.StringIO()
    return cfg


def to_doit(task: dict) -> dict:
    """Our task dict -> doit's (names are flat strings; robot:kind:item)."""
    return {"basename": task["name"], **{k: v for k, v in task.items() if k != "name"}}


def build(recipes: list[str | os.PathLike], out_dir: str | os.PathLike = "build", jobs: int = 1,
          echo=None, progress=None, ros: str | None = None, stamp_options: dict | None = None,
          report: bool = False, args: dict[str, str] | None = None) -> BuildResult:
    """Build every recipe into ``out_dir``.  Raises RobotkitError with every user problem.
    ``ros`` (ros1 | ros2) overrides the recipes' ``ros`` key; ``args`` sets recipe arguments (``--arg``).
    ``report`` also writes each robot's picture report (``<robot>/report/report.html``); the
    command line does unless ``--no-report``.

    The stamp of the no-op fast path (:mod:`robotkit.stamp`) is removed first and written
    again when the build succeeds; ``stamp_options`` are the options it is kept under
    (default :func:`robotkit.stamp.options` of the recipes and the output folder).
    """
    from doit.cmd_base import TaskLoader2
    from doit.doit_cmd import DoitMain
    from doit.task import dict_to_task

    from robotkit import stamp

    if stamp_options is None:  # a build without the report is another build than one with it
        stamp_options = stamp.options(recipes, out_dir, None if report else {"no_report": True})
    stamp.remove(out_dir, stamp_options)

    from robotkit.tasks import load_robots, mesh_locations, robot_tasks

    out = Path(out_dir).absolute()
    robots = load_robots(recipes, ros, args)  # raises before anything is written
    result = BuildResult(robots=[r.name for _, r in robots])
    tasks = []
    for loaded, robot in robots:
        tasks.extend(robot_tasks(robot, out, mesh_locations(loaded, robot), report=report))
    (out / ".robotkit").mkdir(parents=True, exist_ok=True)
    recorder = _Recorder(result, echo, progress)
    inputs = _input_stats(robots, tasks)  # before running: an edit during the build is a change

    class Loader(TaskLoader2):
        def setup(self, opt_values):
            pass

        def load_doit_config(self):
            return doit_config(out, recorder)

        def load_tasks(self, cmd, pos_args):
            return [dict_to_task(dict(t)) for t in tasks]

    args = ["run"]
    if jobs > 1:
        args += ["-n", str(jobs), "-P", "process"]
    rc = DoitMain(Loader(), config_filenames=()).run(args)
    if recorder.runtime_errors:
        result.errors.append(("doit", "\n".join(recorder.runtime_errors)))
    published = _publish(out, robots, tasks, result, recorder)
    if result.failed:
        lines = []
        for _, msg in result.failed:
            for line in msg.splitlines():
                if line not in lines:
                    lines.append(line)
        error = RobotkitError([Problem(line) for line in lines])
        error.exit_status = result.exit_status or 2
        raise error
    if rc not in (0,) and not result.errors:
        result.errors.append(("doit", f"doit exited with status {rc}"))
    result.warnings = collect_warnings(tasks) + collect_losses(out, result.robots)
    if rc == 0 and not result.errors:
        outputs = sorted({str(Path(t).absolute()) for task in tasks for t in task.get("targets", [])} | set(published))
        try:
            stamp.write(out, stamp_options, inputs, outputs,
                        {"robots": result.robots, "tasks": len(tasks), "warnings": result.warnings})
        except OSError:
            pass  # no stamp: the next build runs doit's checks
    return result


def _publish(out: Path, robots, tasks: list[dict], result: BuildResult, recorder) -> list[str]:
    """Publish each robot whose tasks all succeeded (robotkit.publish): a failed robot keeps its
    previous complete output.  A file a consumer would refuse (exit 1: the MJCF of a chain too
    deep for MuJoCo) is left out of an otherwise complete output, as the build says.
    Returns the published files."""
    from robotkit.publish import publish, staged_files

    if recorder.runtime_errors:
        return []
    owner = {f"world:{w.name}": robot.name for _, robot in robots for w in robot.worlds}
    bad = {owner.get(name, name.split(":")[0]) for name, _ in result.failed + result.errors
           if name not in recorder.not_written}
    published = []
    for _, robot in robots:
        if robot.name in bad:
            continue
        mine = [t for t in tasks if owner.get(t["name"], t["name"].split(":")[0]) == robot.name]
        try:
            written = [t for t in mine if t["name"] not in recorder.not_written]
            published += publish(out, robot.name, staged_files(written, out))
        except OSError as exc:
            result.errors.append((f"{robot.name}:publish", f"cannot publish {robot.name}: {exc}"))
    return published


def _input_stats(robots, tasks) -> dict:
    """Every file the build reads that no task writes, with its (size, mtime) now."""
    from robotkit import stamp
    from robotkit.emit.env import template_dirs

    targets = {str(Path(t).absolute()) for task in tasks for t in task.get("targets", [])}
    files = {str(Path(f).absolute()) for loaded, _ in robots for f in loaded.files}
    files |= {str(Path(f).absolute()) for task in tasks for f in task.get("file_dep", [])}
    for d in template_dirs():
        for root, _dirs, names in os.walk(d):
            files |= {os.path.join(root, n) for n in names}
    return stamp.stats(sorted(files - targets))


def collect_losses(out: Path, robots: list[str]) -> list[str]:
    """What each output format could not express (from each robot's report.json)."""
    lines = []
    names = {"urdf": "URDF", "sdf": "SDF", "mjcf": "MJCF", "package": "ROS package"}
    for name in robots:
        try:
            data = json.loads((out / name / "report.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        for fmt, items in sorted(data.get("losses", {}).items()):
            lines.extend(f"{name}: {names.get(fmt, fmt)}: {item}" for item in items)
    return lines


def collect_warnings(tasks: list[dict]) -> list[str]:
    """Warnings recorded by this build's mesh tasks (shown on every build, not only the one
    that ran them, so a no-op rebuild does not hide them)."""
    seen: list[str] = []
    for task in tasks:
        if ":mesh:" not in task["name"]:
            continue
        for path in task["targets"]:
            path = Path(path)
            try:
                data = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue
            for w in data.get("warnings", []):
                if w not in seen:
                    seen.append(w)
    return seen
