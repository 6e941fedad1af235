"""The check stages: validators, physics lints, cross-format equivalence, the consuming
programs and a simulation smoke test, each folded into one list of findings.

One function per kind of input: a robotkit build folder, a URDF, a xacro file, an SDF or MJCF
file written anywhere (meshes resolved relative to it or via package paths).  Which PATH is
which, and building a recipe first, is ``robotkit.commands.check``'s job.
"""

from __future__ import annotations

import contextlib
import json
import re
import shutil
import subprocess
import tempfile
import time
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

from robotkit import urdfxml
from robotkit.check import programs
from robotkit.check.cache import StageCache, from_json, kept, stage_cache, to_json
from robotkit.check.consumers import CONSUMERS, Build, consumer_findings
from robotkit.check.equivalence import equivalence
from robotkit.check.selfcollision import interference, mjcf_interference
from robotkit.check.findings import Finding
from robotkit.check.kinematics import read_mjcf, read_sdf
from robotkit.check.lints import LinkFacts, lint, lint_link, read_urdf_facts
from robotkit.check.locate import locate
from robotkit.check.motion.stage import MotionRun, compiled
from robotkit.check.simulation import smoke_test
from robotkit.check.validators import validate_mjcf, validate_sdf, validate_urdf
from robotkit.emit.layout import robot_layout
from robotkit.errors import Problem, RobotkitError


URDF_CONSUMERS = ["Gazebo (URDF)", "Drake (URDF)", "Pinocchio (URDF)", "PyBullet (URDF)"]


def _stage(name: str, subject: str, run) -> list[Finding]:
    """One stage of the check; a stage that cannot run is a finding with its reason, never
    a silent skip."""
    try:
        return run()
    except Exception as exc:  # a stage's own failure is reported: the other stages still run
        return [Finding("error", name, subject, f"the {name} stage could not run: {type(exc).__name__}: {exc}")]


def check_urdf_file(path: Path, package_paths: dict[str, str]) -> list[Finding]:
    """Findings on a URDF, each located at its link's or joint's line.  A broken tree (a
    cycle, a second parent, a missing link) is found here first: the validators and
    consumers are not given it (check_urdf prints a cycle forever, simulators crash)."""
    from robotkit.importer.package_xml import with_own_package  # the importer (pydantic): not for a build folder

    package_paths = with_own_package(path.absolute(), package_paths)
    try:
        links, joints, notes = read_urdf_facts(path, package_paths)
    except (ValueError, TypeError) as exc:  # numbers that are not numbers
        raise RobotkitError(Problem(f"not a valid URDF: {exc}", file=str(path))) from None
    lines, tree = urdf_tree(path)
    findings = notes + lint(links, joints) + tree
    if not tree:
        findings = validate_urdf(path) + findings
        build = Build(path.stem, path.parent, path, None, None, package_paths=package_paths, foreign=True)
        findings += _stage("consumers", f"robot '{path.stem}'", lambda: consumer_findings(build, URDF_CONSUMERS)[0])
    return locate([f if f.file or f.subject not in lines else replace(f, file=str(path), line=lines[f.subject])
                   for f in findings], path)


def xacro_robot(path: Path) -> str:
    """The robot a xacro file is checked as: its name without ``.xacro`` and ``.urdf``."""
    return path.name.removesuffix(".xacro").removesuffix(".urdf")


def check_xacro_file(path: Path, package_paths: dict[str, str], args: dict[str, str]) -> list[Finding]:
    """A xacro file expanded in the import's sandbox (``$(find)`` through ``package_paths``,
    ``args`` as xacro arguments), then checked as the URDF it expands to; findings name the
    xacro file."""
    from robotkit.importer.package_xml import with_own_package
    from robotkit.importer.xacro_expand import check_package_paths, expand

    packages = with_own_package(path.absolute(), check_package_paths(package_paths))
    text = expand(path, packages, args).text

    def absolute(m: re.Match) -> str:  # relative mesh paths stay relative to the xacro file
        uri = m.group(2)
        if "://" in uri or Path(uri).is_absolute():
            return m.group(0)
        return f'{m.group(1)}{(path.parent / uri).absolute().as_posix()}{m.group(3)}'

    text = re.sub(r'(<mesh\b[^>]*?\bfilename=")([^"]*)(")', absolute, text)
    stem = xacro_robot(path)
    with tempfile.TemporaryDirectory(prefix="robotkit-check-") as tmp:
        urdf = Path(tmp) / f"{stem}.urdf"
        urdf.write_text(text, encoding="utf-8")
        findings = check_urdf_file(urdf, packages)
    # the expanded file vanishes: findings in it are placed in the xacro file (on the element
    # when the name is written there literally)
    moved = [replace(f, subject=str(path) if f.subject == str(urdf) else f.subject,
                     file=None if f.file == str(urdf) else f.file, line=None if f.file == str(urdf) else f.line)
             for f in findings]
    return locate(moved, path)


def urdf_tree(path: Path) -> tuple[dict[str, int], list[Finding]]:
    """(subject -> line of each ``<link>`` and ``<joint>``, findings on the kinematic tree)."""
    try:
        root = urdfxml.parse_file(path).getroot()
    except (urdfxml.MalformedXML, OSError) as exc:
        raise RobotkitError(Problem(f"not well-formed XML: {exc}", file=str(path))) from None
    lines = {f"{e.tag} '{e.get('name')}'": e.sourceline for e in root if e.tag in ("link", "joint")}
    links = {e.get("name") for e in root.iter("link") if e.getparent() is root}
    found: list[Finding] = []

    def bad(joint, message):
        found.append(Finding("error", "tree", f"joint '{joint.get('name')}'", message, file=str(path),
                             line=joint.sourceline))

    parent_of: dict[str, str] = {}
    for j in (e for e in root if e.tag == "joint"):
        ends = {}
        for end in ("parent", "child"):
            el = j.find(end)
            ends[end] = el.get("link") if el is not None else None
            if ends[end] not in links:
                bad(j, f"its {end} link {ends[end]!r} is not a link of the robot")
        child = ends["child"]
        if child in parent_of:
            bad(j, f"link '{child}' already has a parent ('{parent_of[child]}'); a link has at most one")
        elif child in links and ends["parent"] in links:
            parent_of[child] = ends["parent"]
    cycles = set()
    for start in sorted(parent_of):
        seen, node = [], start
        while node in parent_of and node not in seen:
            seen.append(node)
            node = parent_of[node]
        if node == start and frozenset(seen) not in cycles:
            cycles.add(frozenset(seen))
            found.append(Finding("error", "tree", f"link '{start}'", "its joints form a cycle: "
                                 + " <- ".join(seen + [start]), file=str(path), line=lines.get(f"link '{start}'")))
    return lines, found


class Clock:
    """Each stage's wall time in seconds, added into ``timings`` (stage -> seconds; None: not kept)."""

    def __init__(self, timings: dict[str, float] | None):
        self.timings = timings

    def add(self, stage: str, seconds: float) -> None:
        if self.timings is not None:
            self.timings[stage] = self.timings.get(stage, 0.0) + seconds

    def timed(self, stage: str, run):
        """``run()``, its time added to ``stage``."""
        t = time.perf_counter()
        try:
            return run()
        finally:
            self.add(stage, time.perf_counter() - t)


def _timed(run, *args) -> tuple[object, float]:
    """(``run(*args)``, its wall time): a stage run in a thread or a worker process."""
    t = time.perf_counter()
    return run(*args), time.perf_counter() - t


def _stage_outcome(name: str, subject: str, future: Future) -> tuple[list[Finding], float]:
    try:
        return future.result()
    except Exception as exc:  # as _stage reports it (a worker process that died, a program that crashed)
        return [Finding("error", name, subject, f"the {name} stage could not run: {type(exc).__name__}: {exc}")], 0.0


def _own_consumers(build: Build) -> tuple[list[Finding], float]:
    """The consumers that read the robot in Python (Drake, Pinocchio, PyBullet, MuJoCo), in a
    worker process: their imports and readings beside the main process's stages.  MuJoCo's
    reads the MJCF: not without one."""
    consumers = IN_WORKER if build.mjcf is not None else [c for c in IN_WORKER if c != "MuJoCo (MJCF)"]
    return _timed(lambda: _stage("consumers", f"robot '{build.name}'",
                                 lambda: consumer_findings(build, consumers)[0]))


IN_WORKER = [c for c in CONSUMERS if not c.startswith("Gazebo")]
"""The consumers read in a worker process; Gazebo's (``ign sdf -p``, run once for the equivalence
stage too: robotkit.check.programs) in the main one."""


def _fork_pool():
    """A one-worker process pool, forked where the system can (the worker inherits the imports)."""
    import multiprocessing

    context = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else None)
    return ProcessPoolExecutor(max_workers=1, mp_context=context)


MJCF_STAGES = ("mujoco", "simulation", "self-collision", "motion")
"""The stages that read the MJCF (its validator on it and the scene, the scene's simulation, the
self-collision sampled in MuJoCo, the motion in MuJoCo): skipped when the build left it out."""


def mjcf_left_out(robot_dir: Path) -> str | None:
    """Why the build left the MJCF out of a build folder (a limit of the format: its report.json
    says), as the stages it skips say it; None when the folder should hold it."""
    why = robot_layout(robot_dir).left_out().get("mjcf")
    return None if why is None else f"the MJCF was left out: {why}"


def check_build_dir(robot_dir: Path, declared_mass: float | None = None, motion: dict | None = None,
                    timings: dict[str, float] | None = None) -> list[Finding]:
    """Every stage on a build folder: lints, validators, equivalence of the formats, what each
    consuming program sees, the MuJoCo scene's own simulation and, when the MJCF has actuators,
    the step responses of its drives (``motion``: gets the robot's motion results by name).
    Every stage always runs but the ones of :data:`MJCF_STAGES` (and MuJoCo's consumer) on a
    folder whose MJCF the build left out (:func:`mjcf_left_out`); the ones that do not depend on
    each other at once (the motion stage's simulators and the Python consumers in worker
    processes, the validator programs and ``ign sdf -p`` in threads).  ``timings``: gets each
    stage's wall time (seconds, by stage)."""
    layout = robot_layout(robot_dir)
    name, urdf, sdf, mjcf, scene = layout.name, layout.urdf, layout.sdf, layout.mjcf, layout.scene
    lost = mjcf_left_out(robot_dir) is not None
    for p in (urdf, sdf) if lost else (urdf, sdf, mjcf, scene):
        if not p.is_file():
            raise RobotkitError(Problem(f"not a robotkit build folder: {p.relative_to(robot_dir)} is missing",
                                        file=str(robot_dir)))
    clock, subject = Clock(timings), f"robot '{name}'"
    build = Build(name, robot_dir, urdf, sdf, None if lost else mjcf, _base(layout, lost))
    consumers_started = time.perf_counter()
    cached = stage_cache(robot_dir)
    with _libsdformat(build, cached):  # libsdformat's runs first, beside the workers' imports
        workers, collider = _fork_pool(), _fork_pool()
        try:  # each worker imports its own libraries, beside the others (measured: importing them here
            # first, for the workers to inherit, saved no CPU and lengthened the main process's path)
            own = _cached_or(cached, "consumers", workers, _own_consumers, build)
            started = None if lost else start_motion(mjcf, urdf, {name: robot_dir}, cached)  # beside the others
            collisions = None if lost else _cached_or(cached, "self-collision", collider, _interference,
                                                      robot_dir, subject)  # forked with MuJoCo imported
            return _rest(build, clock, declared_mass, own, started, collisions, motion, consumers_started, cached)
        finally:  # waited for: a pool left behind (wait=False) can raise at the interpreter's exit, after
            # the report is written (OSError: Bad file descriptor, seen on interbotix_px150's check)
            workers.shutdown(wait=True, cancel_futures=True)
            collider.shutdown(wait=True, cancel_futures=True)


@contextlib.contextmanager
def _libsdformat(build: Build, cached: StageCache | None):
    """libsdformat's runs (:func:`_sdformat_runs`) started for the block, or their results taken
    from the cache; stored there once they are done."""
    runs = _sdformat_runs(build)
    rows = cached.get("libsdformat") if cached and runs else None
    known = ({tuple(c): subprocess.CompletedProcess(c, *row) for c, row in zip(runs, rows)}
             if rows and len(rows) == len(runs) else {})
    with programs.started(runs, known):
        yield
        if cached and runs and not known:
            cached.put("libsdformat", [[r.returncode, r.stdout, r.stderr] for r in map(programs.run, runs)])


def _cached(cached: StageCache | None, stage: str, run) -> list[Finding]:
    """``run()``'s findings, or the stage's from the cache (:mod:`robotkit.check.cache`)."""
    found = cached.get(stage) if cached else None
    if found is not None:
        return from_json(found)
    found = run()
    if cached and kept(found):
        cached.put(stage, to_json(found))
    return found


def _cached_or(cached: StageCache | None, stage: str, pool, run, *args) -> Future:
    """The stage's (findings, seconds): from the cache (:mod:`robotkit.check.cache`), or ``run(*args)``
    in ``pool``'s worker, its findings stored once it is done."""
    found = cached.get(stage) if cached else None
    if found is not None:
        done: Future = Future()
        done.set_result((from_json(found), 0.0))
        return done
    with programs.SPAWN:  # the worker forked while no program is being started (programs.SPAWN)
        future = pool.submit(run, *args)
    if cached:
        def store(f: Future) -> None:
            if not f.cancelled() and f.exception() is None and kept(f.result()[0]):
                cached.put(stage, to_json(f.result()[0]))

        future.add_done_callback(store)
    return future


def _rest(build: Build, clock: Clock, declared_mass: float | None, own: Future, started, collisions,
          motion: dict | None, consumers_started: float, cached: StageCache | None) -> list[Finding]:
    """The main process's stages, then the workers' findings gathered in the stages' order."""
    subject, lost = f"robot '{build.name}'", build.mjcf is None
    findings, gazebo = _main_stages(build, clock, declared_mass, cached)
    findings += _merged_consumers(gazebo, own, subject)
    clock.add("consumers", time.perf_counter() - consumers_started)
    if lost:
        return findings
    scene = robot_layout(build.dir).scene
    findings += clock.timed("simulation", lambda: _stage("simulation", subject, lambda: _simulate(scene, subject)))
    found, seconds = _stage_outcome("self-collision", subject, collisions)
    clock.add("self-collision", seconds)
    findings += found
    return findings + unreported_missing(findings, finish_motion(started, subject, build.name, motion, clock))


def _interference(robot_dir: Path, subject: str) -> tuple[list[Finding], float]:
    """The self-collision stage, in a worker process beside the main process's stages."""
    return _timed(lambda: _stage("self-collision", subject, lambda: interference(robot_dir)))


def _base(layout, lost: bool) -> str:
    """How the robot's root sits (free | fixed): the MJCF's free joint, or report.json's word on
    it when the MJCF was left out."""
    if not lost:
        return "free" if "<freejoint" in layout.mjcf.read_text(encoding="utf-8") else "fixed"
    consumers = json.loads(layout.report_json.read_text(encoding="utf-8")).get("consumers", {})
    return "free" if consumers.get("MuJoCo (MJCF)", {}).get("base") == "free joint" else "fixed"


def _main_stages(build: Build, clock: Clock, declared_mass: float | None,
                 cached: StageCache | None = None) -> tuple[list[Finding], list[Finding]]:
    """The lints, the validators, the equivalence and Gazebo's view, with libsdformat's runs
    and check_urdf started first beside them: (their findings, Gazebo's findings)."""
    subject, sdf, mjcf = f"robot '{build.name}'", build.sdf, build.mjcf
    scene = robot_layout(build.dir).scene
    with ThreadPoolExecutor(max_workers=2) as threads:  # libsdformat's runs started by the caller
        validators = {"check_urdf": threads.submit(_timed, validate_urdf, build.urdf),
                      "ign sdf -k": threads.submit(_timed, validate_sdf, sdf)}
        findings = clock.timed("lints", lambda: _lints(build.urdf, {build.name: str(build.dir)}, declared_mass))
        for stage, future in validators.items():  # in the order the stages are listed
            found, seconds = _stage_outcome(stage, subject, future)
            findings += found
            clock.add(stage, seconds)
        if mjcf is not None:
            findings += clock.timed("mujoco", lambda: validate_mjcf(mjcf) + validate_mjcf(scene))

        def equivalent() -> list[Finding]:
            return [Finding("error", "equivalence", subject, f"{what}: {d}")
                    for what, diffs in equivalence(build.dir).items() for d in diffs]

        findings += clock.timed("equivalence", lambda: _cached(cached, "equivalence", lambda: _stage(
            "equivalence", subject, equivalent)))
        gazebo = _cached(cached, "consumers gazebo", lambda: _stage("consumers", subject,
                                                                    lambda: consumer_findings(build, GAZEBO)[0]))
    return findings, gazebo


GAZEBO = [c for c in CONSUMERS if c.startswith("Gazebo")]


def _sdformat_runs(build: Build) -> list[list[str]]:
    """libsdformat's runs a build folder's check makes: ``ign sdf -k`` of model.sdf (its validator),
    ``ign sdf -p`` of the URDF and of model.sdf (the equivalence stage and Gazebo's view)."""
    if not shutil.which("ign"):
        return []
    return [["ign", "sdf", "-k", str(build.sdf)]] + [["ign", "sdf", "-p", str(p)] for p in (build.urdf, build.sdf)]


def _lints(urdf: Path, package_paths: dict[str, str], declared_mass: float | None) -> list[Finding]:
    links, joints, notes = read_urdf_facts(urdf, package_paths)
    return notes + lint(links, joints, declared_mass)


def _merged_consumers(gazebo: list[Finding], own: Future, subject: str) -> list[Finding]:
    """Gazebo's findings, then the worker's, each once (both say when the description cannot be read)."""
    found, _ = _stage_outcome("consumers", subject, own)
    return list(dict.fromkeys(gazebo + found))


def _simulate(scene: Path, subject: str) -> list[Finding]:
    notes: list[str] = []
    problems = smoke_test(scene, notes=notes)
    return ([Finding("error", "simulation", subject, p, "MuJoCo scene mjcf/scene.xml") for p in problems]
            + [Finding("warning", "simulation", subject, n, "MuJoCo scene mjcf/scene.xml") for n in notes])


def unreported_missing(findings: list[Finding], more: list[Finding]) -> list[Finding]:
    """``more`` without the programs it says are not installed that ``findings`` already name
    (one warning per missing program: the consumers stage's)."""
    said = " ".join(f.message for f in findings if "not installed" in f.message).lower()
    return [f for f in more if not ("not checked" in f.message and f.message.split(":")[0].lower() in said)]


def start_motion(mjcf: Path, urdf: Path | None, package_dirs: dict[str, Path],
                 cached: StageCache | None = None) -> MotionRun | Exception | None:
    """The motion stage started (None when the MJCF has no actuator; the exception if it cannot
    start); each simulator's runs taken from ``cached`` when they are there."""
    try:
        model = compiled(mjcf)  # compiled once: whether it has actuators, then the plan
        return MotionRun(mjcf, urdf, package_dirs, cached=cached, model=model) if model.nu > 0 else None
    except Exception as exc:  # reported by finish_motion, as _stage reports a stage's failure
        return exc


def finish_motion(started: MotionRun | Exception | None, subject: str, name: str,
                  motion: dict | None, clock: Clock | None = None) -> list[Finding]:
    if started is None:
        return []

    def finish() -> list[Finding]:
        if isinstance(started, Exception):
            raise started
        found, results = started.finish()
        if clock is not None:  # from the stage's start: its simulators ran beside the other stages
            clock.add("motion", float(results.get("wall", 0.0)))
        if motion is not None:
            motion[name] = results
        return found

    return _stage("motion", subject, finish)


def check_model_file(path: Path, kind: str, motion: dict | None = None) -> list[Finding]:
    """An SDF (``kind`` sdf) or MJCF (mjcf) file: its validator, then, for an MJCF the validator
    accepts and for every SDF, the mass and inertia lints (their geometry is not measured yet);
    for an accepted MJCF with actuators, the motion stage in MuJoCo (``motion``: gets its results)."""
    if kind == "sdf":
        return locate(validate_sdf(path) + _inertial_lints(path, kind), path)
    invalid = validate_mjcf(path)
    if invalid:
        return locate(invalid, path)
    started = start_motion(path, None, {})
    findings = _inertial_lints(path, kind)
    findings += _stage("self-collision", f"robot '{path.stem}'", lambda: mjcf_interference(path))
    findings += finish_motion(started, f"robot '{path.stem}'", path.stem, motion)
    return locate(findings, path)


def _inertial_lints(path: Path, kind: str) -> list[Finding]:
    try:
        model = read_sdf(path) if kind == "sdf" else read_mjcf(path)
    except Exception as exc:  # an invalid file is reported by its validator
        return [Finding("warning", "inertia", str(path), f"could not read inertials: {exc}")]
    out = []
    if kind == "sdf":  # what Gazebo and Drake will see: SDF's default for a link without <inertial>
        for el in ET.parse(path).getroot().iter("link"):
            if el.find("inertial") is None:
                out.append(Finding("error", "consumer", f"link '{el.get('name')}'",
                                   "has no <inertial>: Gazebo and Drake give it a mass of 1 kg and a unit inertia",
                                   "give it an <inertial>, or make a massless thing a <frame>", file=str(path)))
    for link in model.links.values():
        if link.mass == 0 and not link.inertia.any():
            continue
        out += lint_link(LinkFacts(link.name, link.mass, link.com, link.inertia))
    return out
