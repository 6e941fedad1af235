"""The public robot corpus: where it is, and one robot through `robotkit import`, `build` and `check`.

Two corpora share one runner:

- the PyPI packages ``rtb-data`` (the Robotics Toolbox's descriptions) and ``example-robot-data``,
  installed by ``scripts/setup.sh --test`` (the test extras) or unzipped into a folder named by
  ``ROBOTKIT_CORPUS`` (a wheel is a zip: ``unzip rtb_data-*.whl -d DIR``); their robots are
  listed in ``tests/corpus/robots.tsv``, entries and package folders relative to that root;
- ``../shared/assets/robots`` (its own ``robots.tsv``), also read by tests/importer/test_corpus.py.

Each stage runs as a user runs it, in its own ``python -m robotkit`` process, so a traceback is
seen as a traceback and a crash stops one robot only.  What robotkit makes of a robot is a
``Run``: the stage it reached, each stage's exit status and message lines, and the check's
findings.  An error is *robotkit's own* when it is a disagreement between robotkit's outputs or
a refusal of one of them (``OWN_CHECKS``), a traceback, or an exit status no command documents;
the other errors are the original's defects, which import reports and check names.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
TABLE = Path(__file__).resolve().parent / "robots.tsv"
SHARED = REPO.parent / "shared" / "assets" / "robots"
CORPUS_ENV = "ROBOTKIT_CORPUS"
DISTRIBUTIONS = ("rtb-data", "example-robot-data")

# check rules whose errors are robotkit's own: its outputs disagree, or a program refuses one
OWN_CHECKS = frozenset({"equivalence", "consumer", "mujoco", "simulation", "ign sdf -k", "check_urdf", "build"})
TIMEOUT = 900  # seconds per stage: a robot that takes longer is reported as a timeout


def pypi_root() -> Path | None:
    """The folder the corpus table's paths are relative to: $ROBOTKIT_CORPUS, else the
    site-packages folder holding both distributions, else None."""
    if os.environ.get(CORPUS_ENV):
        return Path(os.environ[CORPUS_ENV])
    from importlib.metadata import PackageNotFoundError, distribution

    roots = set()
    for name in DISTRIBUTIONS:
        try:
            roots.add(Path(str(distribution(name).locate_file(""))))
        except PackageNotFoundError:
            return None
    return roots.pop() if len(roots) == 1 else None


@dataclass(frozen=True)
class Robot:
    name: str
    entry: Path
    packages: dict[str, str]
    args: dict[str, str]
    source: str  # "pypi" or "shared"


def _read_table(table: Path, root: Path, source: str) -> list[Robot]:
    robots = []
    with open(table, encoding="utf-8") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            packages = dict(p.split("=", 1) for p in (row["packages"] or "").split())
            args = dict(a.split(":=", 1) for a in (row["xacro_args"] or "").split())
            robots.append(Robot(row["name"], root / row["entry"], {k: str(root / v) for k, v in packages.items()},
                                args, source))
    return robots


def robots() -> dict[str, Robot]:
    """Every robot of both corpora that is on this machine, by name."""
    found = []
    root = pypi_root()
    if root is not None and (root / "rtbdata").is_dir():
        found += _read_table(TABLE, root, "pypi")
    if (SHARED / "robots.tsv").is_file():
        found += _read_table(SHARED / "robots.tsv", SHARED, "shared")
    return {r.name: r for r in found}


def table_names() -> list[str]:
    """The names the table lists (whether the corpus is installed or not)."""
    with open(TABLE, encoding="utf-8") as f:
        return [row["name"] for row in csv.DictReader(f, delimiter="\t")]


@dataclass
class Stage:
    name: str
    argv: list[str]
    returncode: int | None  # None: timed out
    seconds: float
    stderr: str
    stdout: str = ""

    @property
    def traceback(self) -> bool:
        return "Traceback (most recent call last)" in self.stderr

    def lines(self) -> list[str]:
        """The message lines: errors of a refusal, or the traceback's last line."""
        lines = [ln for ln in self.stderr.splitlines() if ln.strip()]
        if self.traceback:
            return lines[-1:]
        return [ln for ln in lines if not ln.startswith(("warning:", "note:", "copied ", "wrote ", "built ", "  "))
                and ": warning:" not in ln] or lines[-3:]


@dataclass
class Run:
    robot: str
    stages: list[Stage] = field(default_factory=list)
    findings: list[dict] = field(default_factory=list)  # the check's, from --format json

    @property
    def reached(self) -> str:
        """'imported', 'built', 'checked' (the check ran) or 'refused by <stage>'."""
        names = {"import": "imported", "build": "built", "check": "checked"}
        last = self.stages[-1]
        if last.name == "check" and last.returncode in (0, 1) and not last.traceback:
            return "checked"
        if last.returncode == 0 and not last.traceback:
            return names[last.name]
        return f"refused by {last.name}"

    def errors(self) -> list[dict]:
        return [f for f in self.findings if f["severity"] == "error"]

    def own_errors(self) -> list[str]:
        """robotkit's own errors, one line each: tracebacks, timeouts, exit statuses no command
        documents, and check errors of OWN_CHECKS."""
        out = []
        for s in self.stages:
            if s.traceback:
                out.append(f"{s.name}: traceback: {s.lines()[0]}")
            elif s.returncode is None:
                out.append(f"{s.name}: timed out after {s.seconds:.0f} s")
            elif s.returncode not in ((0, 1) if s.name == "check" else (0, 1, 2)):
                out.append(f"{s.name}: exit {s.returncode}: {' | '.join(s.lines())}")
        if self.stages[-1].name == "build" and self.stages[-1].returncode == 1:
            out += [f"build: {ln}" for ln in self.stages[-1].lines() if _own_build_refusal(ln)]
        out += [f"check: {f['check']}: {f['subject']}: {f['message']}" for f in self.errors() if own_finding(f)]
        return out

    def refusal(self) -> list[str]:
        """The last stage's message lines, when it refused (or timed out)."""
        last = self.stages[-1]
        if self.reached == "checked" or (last.returncode == 0 and not last.traceback):
            return []
        if last.returncode is None:
            return [f"{last.name}: timed out after {last.seconds:.0f} s"]
        return last.lines() or [f"{last.name}: exit {last.returncode} without a message"]

    def clean(self) -> bool:
        return self.reached == "checked" and not self.errors()

    def summary(self) -> dict:
        return {"robot": self.robot, "reached": self.reached, "clean": self.clean(),
                "seconds": {s.name: round(s.seconds, 1) for s in self.stages},
                "refusal": self.refusal(),
                "errors": sorted({f["check"] for f in self.errors()}),
                "error_counts": _count(f["check"] for f in self.errors()),
                "own": self.own_errors()}


def own_finding(finding: dict) -> bool:
    """Whether a check finding is robotkit's own: a rule of OWN_CHECKS, or a stage that could
    not run on the build."""
    return finding["check"] in OWN_CHECKS or "stage could not run" in finding["message"]


TOPIC = {"inertia-box": "inerti", "inertia": "inerti", "implied-density": "densit|implies", "total-mass": "mass"}


def reported(finding: dict, said: str) -> bool:
    """Whether a line of the import's messages names the finding's subject and its topic (for
    joint-limits: which limit, "effort limit 0 ..." -> effort)."""
    name = finding["subject"].split(" ", 1)[-1]
    rule = finding["check"]
    topic = finding["message"].split()[0] if rule == "joint-limits" else TOPIC.get(rule, rule.split("-")[0])
    topics = topic.lower().split("|")  # implied-density: "implies" in the import's "mass ... implies D kg/m^3"
    return any(name in line and any(t in line.lower() for t in topics) for line in said.splitlines())


def _count(items) -> dict[str, int]:
    out: dict[str, int] = {}
    for i in items:
        out[i] = out.get(i, 0) + 1
    return dict(sorted(out.items()))


def _own_build_refusal(line: str) -> bool:
    """A build refusal that names a format robotkit could not write (MuJoCo, libsdformat),
    rather than a defect of the recipe's input (a broken mesh file)."""
    return any(w in line for w in ("MuJoCo", "MJCF", "libsdformat", "SDF", "equivalen"))


def _stage(name: str, argv: list[str], log: Path) -> Stage:
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    t = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-m", "robotkit", *argv], capture_output=True, text=True, env=env,
                           timeout=TIMEOUT, cwd=log.parent)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as e:
        rc, out, err = None, str(e.stdout or ""), str(e.stderr or "")
    log.write_text(f"$ robotkit {' '.join(argv)}\n# exit {rc}\n{out}\n{err}", encoding="utf-8")
    return Stage(name, argv, rc, time.perf_counter() - t, err, out)


def run(robot: Robot, out: Path, jobs: int = 1) -> Run:
    """Import ``robot`` into out/recipe/robot.yaml, build it into out/build and check the build
    (each stage's command and output in out/<stage>.log); stop at the first refusal."""
    out.mkdir(parents=True, exist_ok=True)
    recipe = out / "recipe" / "robot.yaml"
    argv = ["import", str(robot.entry), "-o", str(recipe)]
    argv += [a for k, v in sorted(robot.packages.items()) for a in ("--package-path", f"{k}={v}")]
    argv += [a for k, v in sorted(robot.args.items()) for a in ("--arg", f"{k}:={v}")]
    result = Run(robot.name, [_stage("import", argv, out / "import.log")])
    if result.stages[-1].returncode != 0:
        return result
    build_dir = out / "build"
    result.stages.append(_stage("build", ["build", str(recipe), "-o", str(build_dir), "-j", str(jobs), "--no-report"],
                                out / "build.log"))
    if result.stages[-1].returncode != 0:
        return result
    folders = [p for p in sorted(build_dir.iterdir()) if p.is_dir() and not p.name.startswith(".")]
    report = out / "check.json"
    check = _stage("check", ["check", *map(str, folders), "--format", "json", "--no-report", "-j", str(jobs)],
                   out / "check.log")
    result.stages.append(check)
    if check.returncode in (0, 1) and check.stdout.lstrip().startswith("{"):
        report.write_text(check.stdout, encoding="utf-8")
        result.findings = json.loads(check.stdout).get("findings", [])
    return result


def reproduce(robot: Robot) -> str:
    """The shell command that reruns ``robot``'s import (the build and check follow from it)."""
    argv = ["robotkit", "import", str(robot.entry), "-o", f"/tmp/{robot.name}/robot.yaml"]
    argv += [a for k, v in sorted(robot.packages.items()) for a in ("--package-path", f"{k}={v}")]
    argv += [a for k, v in sorted(robot.args.items()) for a in ("--arg", f"'{k}:={v}'")]
    return " ".join(argv)
