"""The build: recipes -> resolved robots -> doit tasks -> files under the output folder.

    load + validate each recipe   (robotkit.recipe.load)   all problems together, exit 2
    resolve to a Robot            (robotkit.model.resolve) tree checks, SI units
    task dicts                    (robotkit.pipeline.tasks)         file_dep, targets, config_changed
    run them with doit            (here)                   incremental, -j N worker processes

doit's own record (which tasks ran, which were up to date) is returned in a
:class:`BuildResult`; the CLI prints it, and the tests assert on it.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path

from doit.control import TaskControl
from doit.dependency import Dependency, JSONCodec, MD5Checker, SqliteDB
from doit.exceptions import InvalidDodoFile, InvalidTask, TaskFailed, UnmetDependency
from doit.globals import Globals
from doit.runner import MRunner, Runner
from doit.task import Stream, dict_to_task

from robotkit.emit.env import template_dirs
from robotkit.emit.formats import Outputs, outputs_of, unknown_outputs
from robotkit.emit.layout import output_path
from robotkit.emit.registry import FORMATS
from robotkit.errors import Problem, RobotkitError
from robotkit.model.load import load_robots, mesh_locations
from robotkit.pipeline import actions, stamp
from robotkit.pipeline.buildwarn import build_warnings, no_pictures, warning_line
from robotkit.pipeline.progress import Progress
from robotkit.pipeline.publish import STATE, loss_warning, publish, stage_dir, staged_files
from robotkit.pipeline.tasks import robot_tasks


@dataclass
class BuildResult:
    ran: list[str] = field(default_factory=list)
    uptodate: list[str] = field(default_factory=list)
    failed: list[tuple[str, str]] = field(default_factory=list)  # (task, message) user errors
    errors: list[tuple[str, str]] = field(default_factory=list)  # (task, traceback) bugs
    warnings: list[str] = field(default_factory=list)
    warning_lines: list[str] = field(default_factory=list)  # the same, located: file:line: key: warning: ...
    robots: list[str] = field(default_factory=list)
    left_out: dict[str, list[str]] = field(default_factory=dict)  # robot -> files not published (exit 1)
    exit_status: int = 0  # of the failed tasks: 2 bad input, 1 a robot a consumer refuses


SLOW = 1.0  # seconds: tasks at least this long are reported with their time


class _Recorder:
    """A doit reporter that records instead of printing."""

    def __init__(self, result: BuildResult, echo=None, progress=None):
        self.result = result
        self.echo = echo
        # the progress line on a terminal (robotkit.pipeline.progress); quiet with echo or no stream
        if isinstance(progress, Progress):  # a caller's own (robotkit catalogue: time left, CI log lines)
            self.progress = progress
        else:
            self.progress = Progress(None if echo else progress, slow=SLOW)
        self.failures = []
        self.runtime_errors: list[str] = []
        self.not_written: set[str] = set()  # refused by a consumer (exit 1), or not run for a failed dependency

    def initialize(self, tasks, selected_tasks):
        self.progress.total = len(tasks)

    def get_status(self, task):
        pass

    def execute_task(self, task):
        if task.actions:
            self.result.ran.append(task.name)
            if self.echo:
                self.echo(f"  {task.name}")
            self.progress.started(task.name)

    def add_failure(self, task, fail):
        self.progress.finished(task.name, ran=False)
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
        # long tasks (CoACD, decimation) are named with their time, on a terminal only
        self.progress.finished(task.name, ran=bool(task.actions))

    def skip_uptodate(self, task):
        self.result.uptodate.append(task.name)
        self.progress.finished(task.name, ran=False)

    def skip_ignore(self, task):
        pass

    def cleanup_error(self, exception):
        self.result.errors.append(("cleanup", exception.get_msg()))

    def runtime_error(self, msg):
        self.runtime_errors.append(msg)

    def teardown_task(self, task):
        pass

    def complete_run(self):
        self.progress.clear()  # before the caller prints warnings or errors


def state_db(out_dir: Path) -> str:
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
          report: bool = False, args: dict[str, str] | None = None, keep_going: bool = False,
          moveit: bool = False, variant: str | None = None, matrix: bool = True) -> BuildResult:
    """Build every recipe into ``out_dir``.  Raises RobotkitError with every user problem.
    ``ros`` (ros1 | ros2) overrides the recipes' ``ros`` key, ``moveit`` turns their ``moveit``
    key on; ``args`` sets recipe arguments (``--arg``); ``variant`` builds only that variant of
    each recipe (``--variant``; a recipe without it is bad input).  ``matrix=False`` leaves out
    the self-collision matrix (the outputs render as for a robot without one): an import's
    verification, which compares no contacts, builds so.
    ``report`` also writes each robot's picture report (``<robot>/report/report.html``); the
    command line does unless ``--no-report``.

    ``keep_going`` returns the result with its ``failed`` tasks instead of raising, so that a
    batch (``robotkit catalogue``) builds every robot it can.  ``progress`` is a stream for the
    progress line (:mod:`robotkit.pipeline.progress`, terminals only) or a ``Progress`` of the caller's.

    The stamp of the no-op fast path (:mod:`robotkit.pipeline.stamp`) is removed first and written
    again when the build succeeds; ``stamp_options`` are the options it is kept under
    (default :func:`robotkit.pipeline.stamp.build_options` of these settings).
    """
    if stamp_options is None:  # a build without the report is another build than one with it
        stamp_options = stamp.build_options(recipes, out_dir, ros, report, moveit, args, variant)
        stamp_options.update({} if matrix else {"no_matrix": True})
    stamp.remove(out_dir, stamp_options)
    out = Path(out_dir).absolute()
    robots = load_robots(recipes, ros, args, moveit=moveit, variant=variant)  # raises before anything is written
    result = BuildResult(robots=[r.name for _, r in robots])
    chosen = chosen_outputs(robots)  # an unknown format under outputs: is bad input, before anything is written
    tasks = [t for loaded, robot in robots for t in robot_tasks(robot, out, mesh_locations(loaded, robot),
                                                                 report=report, outputs=chosen[robot.name],
                                                                 matrix=matrix)]
    (out / STATE).mkdir(parents=True, exist_ok=True)
    recorder = _Recorder(result, echo, progress)
    inputs = _input_stats(robots, tasks)  # before running: an edit during the build is a change
    rc = run_doit(tasks, out, recorder, jobs)
    if recorder.runtime_errors:
        result.errors.append(("doit", "\n".join(recorder.runtime_errors)))
    published = _publish(out, robots, tasks, result, recorder)
    if result.failed and not keep_going:
        raise _failure(result, {robot.name: str(loaded.file) for loaded, robot in robots})
    if rc not in (0,) and not result.errors and not result.failed:
        result.errors.append(("doit", f"doit exited with status {rc}"))
    warnings = losses(robots, chosen, report) + build_warnings(robots, out)  # (text, file:line: key: warning: text)
    result.warnings, result.warning_lines = [t for t, _ in warnings], [line for _, line in warnings]
    # a report drawn without pictures is retried by the next build (MuJoCo may draw by then): no stamp
    retry = any(no_pictures(name, out) for name in result.robots)
    if rc == 0 and not result.errors and not result.failed and not retry:
        outputs = sorted({str(Path(t).absolute()) for task in tasks for t in task.get("targets", [])} | set(published))
        try:
            stamp.write(out, stamp_options, inputs, outputs,
                        {"robots": result.robots, "tasks": len(tasks), "warnings": result.warning_lines})
        except OSError:
            pass  # no stamp: the next build runs doit's checks
    return result


def chosen_outputs(robots) -> dict[str, Outputs]:
    """Each robot's formats (robotkit.emit.formats.outputs_of its recipe's ``outputs:``)."""
    problems = [loaded.marks.problem(("outputs",), f"'{name}' is not an output format (one of: {', '.join(FORMATS)})")
                for loaded, _ in robots for name in unknown_outputs(loaded.recipe.outputs or [], FORMATS)]
    if problems:
        raise RobotkitError(problems)
    return {robot.name: outputs_of(robot, FORMATS, loaded.recipe.outputs) for loaded, robot in robots}


def losses(robots, chosen: dict[str, Outputs], report: bool) -> list[tuple[str, str]]:
    """The warning of each robot that lost a format to the format's own limit, placed on its recipe's
    ``robot:`` line: the formats, why, and every file left out with them."""
    out = []
    for loaded, robot in robots:
        mine = chosen[robot.name]
        if not mine.lost:
            continue
        files = [f"{robot.name}/{output_path(FORMATS[n].path, robot.name, robot.ros)}"
                 for n in (*mine.lost, *mine.with_lost)]
        files += [f"{robot.name}/report/report.html"] if report and "mjcf" not in mine else []
        text = loss_warning(robot.name, dict(mine.lost), files)
        file, line = loaded.marks.locate(("robot",))
        out.append((text, warning_line(text, {"file": file or str(loaded.file), "line": line})))
    return out


def run_doit(tasks: list[dict], out: Path, recorder: "_Recorder", jobs: int = 1) -> int:
    """Run the task dicts with doit's runner (its database in ``out``, the settings of
    :func:`doit_config`): in this process, or in ``jobs`` worker processes unless every task would
    be a cache hit (:func:`warm`: then a process pool costs more than the tasks).  doit's
    command line is not used (it looks its plugins up in every installed package's metadata).
    doit's exit status: 0, 1 a task failed, 2 a task raised, 3 the tasks are invalid."""
    cfg = doit_config(out)
    try:
        control = TaskControl([dict_to_task(dict(t)) for t in tasks])
        control.process(None)  # every task
    except (InvalidTask, InvalidDodoFile) as exc:
        recorder.runtime_error(str(exc))
        recorder.progress.clear()
        return 3
    dep_manager = Dependency(SqliteDB, cfg["dep_file"], checker_cls=MD5Checker, codec_cls=JSONCodec)
    Globals.dep_manager = dep_manager
    options = (dep_manager, recorder, cfg["continue"], False, Stream(cfg["verbosity"]))
    parallel = jobs > 1 and MRunner.available() and not warm(tasks)
    runner = MRunner(*options, jobs) if parallel else Runner(*options)
    try:
        return runner.run_all(control.task_dispatcher())
    finally:
        recorder.progress.clear()  # no progress line left behind, whatever happened


def warm(tasks: list[dict]) -> bool:
    """Whether every cached task that reads no other task's output finds its result in the cache
    (:func:`robotkit.pipeline.actions.in_cache`): a build from the cache (a fresh output folder,
    or another branch's), whose tasks then take milliseconds each.  The others are not asked
    (their inputs are not written yet): they come from the same cache when these do, and a task
    after an edit runs where it would have (in this process rather than in a worker).  Stops at
    the first miss, so a cold build pays one lookup."""
    targets = {str(Path(t).absolute()) for task in tasks for t in task.get("targets", [])}
    for task in tasks:
        for fn, args in task.get("actions", []):
            if fn is actions.copy_file:  # a file copied: as cheap in this process
                continue
            if fn is not actions.cached_task:  # a world, never cached: the pool
                return False
            if any(str(Path(d).absolute()) in targets for d in task.get("file_dep", [])):
                continue
            if not actions.in_cache(*args):
                return False
    return True


def _failure(result: BuildResult, recipes: dict[str, str]) -> RobotkitError:
    """The failed tasks' user errors as one error (each line once), with their exit status; the
    files left out of a robot's folder named after its recipe (``recipes``: robot -> file)."""
    lines = []
    for _, msg in result.failed:
        for line in msg.splitlines():
            if line not in lines:
                lines.append(line)
    problems = [Problem(line) for line in lines]
    for robot, files in result.left_out.items():
        problems.append(Problem(f"{robot}: left out (refused by a consumer, or naming a file that is): "
                                + ", ".join(files), file=recipes.get(robot)))
    error = RobotkitError(problems)
    error.exit_status = result.exit_status or 2
    return error


def _publish(out: Path, robots, tasks: list[dict], result: BuildResult, recorder) -> list[str]:
    """Publish each robot whose tasks all succeeded (robotkit.pipeline.publish): a failed robot keeps its
    previous complete output.  A file a consumer would refuse (exit 1: the MJCF of a chain too
    deep for MuJoCo) is left out of an otherwise complete output with every file that names it
    (robotkit.emit.formats.Format.needs), and listed (``result.left_out``).  Returns the published files."""
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
            left = _stage_paths([t for t in mine if t["name"] in recorder.not_written], stage_dir(out))
            if left:
                result.left_out[robot.name] = left
        except OSError as exc:
            result.errors.append((f"{robot.name}:publish", f"cannot publish {robot.name}: {exc}"))
    return published


def _stage_paths(tasks: list[dict], stage: Path) -> list[str]:
    """The targets of ``tasks`` below the ``stage`` folder, relative to it (as below the output
    folder once published: ``<robot>/urdf/<robot>.urdf``), in task order."""
    out = []
    for task in tasks:
        for target in task.get("targets", []):
            p = Path(target)
            if stage in p.parents and p.relative_to(stage).as_posix() not in out:
                out.append(p.relative_to(stage).as_posix())
    return out


def _input_stats(robots, tasks) -> dict:
    """Every file the build reads that no task writes, with its (size, mtime) now."""
    targets = {str(Path(t).absolute()) for task in tasks for t in task.get("targets", [])}
    files = {str(Path(f).absolute()) for loaded, _ in robots for f in loaded.files}
    files |= {str(Path(f).absolute()) for task in tasks for f in task.get("file_dep", [])}
    for d in template_dirs():
        for root, _dirs, names in os.walk(d):
            files |= {os.path.join(root, n) for n in names}
    return stamp.stats(sorted(files - targets))
