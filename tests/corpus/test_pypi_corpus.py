"""Public robots (tests/corpus/robots.tsv: the PyPI packages rtb-data and example-robot-data)
through `robotkit import`, `build` and `check`, as a user runs them, one process per stage.

A fixed sample per run (SAMPLE: one robot of each shape issue 32 found trouble with); all of
them with ROBOTKIT_CORPUS_ALL=1, or in benchmarks/bench_corpus.py, which prints the figures of
docs/performance.md.  The sample's robots run in parallel (as many as the cores this process may
use), each once per session (under pytest-xdist, once per worker that has tests of it).

- No error of robotkit's own making: no traceback, no disagreement between the URDF, SDF and
  MJCF it wrote, no consumer, MuJoCo or libsdformat refusal of them, no simulation error.
- Every robot imports, builds and is checked, or the refusal names the file.
- Every error check finds in the build is a defect of the original that the import reported
  (it names the same link).

What fails on main today is listed in KNOWN (strict: a fix makes the test fail until its line
goes), with the issue's words.
"""

from __future__ import annotations

import os
import re
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.corpus.corpus import own_finding, reported, robots, run, table_names
from tests.validators import IN_CI

pytestmark = [pytest.mark.slow, pytest.mark.consumers]

SAMPLE = {  # robot: the shape it stands for
    "interbotix_px100": "link names with a leading slash (tf-prefix style), xacro",
    "talos_reduced": "humanoid; <mimic> on fixed joints",
    "iris": "drone: floating base, rotor limits of +-1e16 meaning unlimited",
    "ridgeback": "mobile base (xacro): planar virtual joints with limits meaning unlimited",
    "pr2": "mobile manipulator: long chains of fixed joints and massless frames, <gazebo> blocks",
    "lynxmotion_al5d": "small arm whose poses hold 1e-19 values (tolerance against zero); velocity limits 0",
    "abb_irb140": "industrial arm (xacro macros): effort limits 0 on driven joints",
    "ur5_robot": "arm on a world link: placeholder inertias, transmissions",
    "qut_panda_arm_hand": "xacro arm and hand: mimic finger, fixed flange and hand",
    "allegro_right_hand": "hand: many small links, inertias that do not fit",
    "solo12": "quadruped, floating base",
    "kuka_kr210l150": "industrial arm (xacro 1): unprefixed <property> and <macro> tags, read as ROS 1 xacro did",
}

# what main does today that the issue asks otherwise, one line per (test, robot); each goes when
# its fix lands (strict: the test fails until it does).  Empty since issue 32's fixes landed.
KNOWN: dict[tuple[str, str], str] = {}

ALL = os.environ.get("ROBOTKIT_CORPUS_ALL", "") not in ("", "0")
NAMES = table_names() if ALL else sorted(SAMPLE)


def _known(test: str, name: str):
    why = KNOWN.get((test, name))
    return pytest.param(name, marks=pytest.mark.xfail(reason=why, strict=True)) if why else name


def params(test: str) -> list:
    return [_known(test, n) for n in NAMES]


class Runs(dict):
    """Each robot's Run, made on first use (under pytest-xdist: once per worker that has its tests)."""

    def __init__(self, available: dict, root):
        super().__init__()
        self.available, self.root = available, root

    def __missing__(self, name: str):
        self[name] = run(self.available[name], self.root / name)
        return self[name]


@pytest.fixture(scope="session")
def corpus(request, tmp_path_factory) -> Runs:
    """The robots this session's tests use, each imported, built and checked once; without
    pytest-xdist all of them at once, in parallel, before the first test."""
    available = robots()
    wanted = sorted({item.callspec.params["name"] for item in request.session.items
                     if item.path.parent.name == "corpus" and hasattr(item, "callspec")
                     and "name" in item.callspec.params})
    missing = [n for n in wanted if n not in available or not available[n].entry.is_file()]
    if missing:
        msg = (f"the robot corpus is not installed ({len(missing)} robots missing, e.g. {missing[0]}): "
               "scripts/setup.sh --test installs rtb-data and example-robot-data, or set ROBOTKIT_CORPUS to "
               "a folder the wheels are unzipped into")
        pytest.fail(msg) if IN_CI else pytest.skip(msg)
    runs = Runs(available, tmp_path_factory.mktemp("corpus"))
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        with ThreadPoolExecutor(len(os.sched_getaffinity(0))) as pool:
            list(pool.map(runs.__getitem__, wanted))
    return runs


@pytest.mark.parametrize("name", params("own"))
def test_no_error_of_robotkit_own_making(corpus, name):
    assert corpus[name].own_errors() == []


@pytest.mark.parametrize("name", params("reached"))
def test_imports_builds_and_is_checked(corpus, name):
    result = corpus[name]
    assert result.reached == "checked", result.stages[-1].lines()


@pytest.mark.parametrize("name", params("refusal"))
def test_a_refusal_names_the_file(corpus, name):
    result = corpus[name]
    if result.reached == "checked":
        return
    for line in result.stages[-1].lines():
        assert re.match(r"\S+\.(urdf|xacro|yaml|stl|dae|obj|STL|DAE)(:\d+)?: ", line), line


@pytest.mark.parametrize("name", params("reported"))
def test_every_check_error_is_a_defect_the_import_reported(corpus, name):
    result = corpus[name]
    if result.reached != "checked":
        pytest.skip(f"{name} is {result.reached}")
    said = result.stages[0].stderr
    unreported = [f"{f['check']}: {f['subject']}: {f['message']}" for f in result.errors()
                  if not own_finding(f) and not reported(f, said)]
    assert unreported == []
