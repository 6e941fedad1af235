"""robotkit check in CI: JUnit that validates against the schema CI reporters read (Jenkins
xUnit's junit-10.xsd), with failures counted at every --fail-on; GitHub workflow commands in
GitHub's documented syntax, with file and line for recipes and URDF/SDF/MJCF findings; bad
input (exit 2) reported in every format."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from conftest import run_cli
from tests.check.test_check import arm_urdf, box_inertia, link_xml

SCHEMA = Path(__file__).parents[1] / "data" / "schemas" / "junit-10.xsd"


@pytest.fixture(scope="module")
def junit_schema():
    import xmlschema

    return xmlschema.XMLSchema(SCHEMA)


def junit(schema, text: str) -> ET.Element:
    schema.validate(text)  # raises with the element and the rule it breaks
    return ET.fromstring(text)


# GitHub's workflow commands (docs.github.com, "Workflow commands for GitHub Actions"):
# ::error file={name},line={line},endLine={endLine},title={title}::{message}; property values
# escape % CR LF : , as %25 %0D %0A %3A %2C, the message % CR LF.
PROPERTIES = {"title", "file", "line", "endLine", "col", "endColumn"}


def workflow_command(line: str) -> tuple[str, dict[str, str], str]:
    m = re.fullmatch(r"::(error|warning|notice)(?: ([^:]*))?::(.*)", line)
    assert m, f"not a workflow command: {line!r}"
    command, props, message = m.groups()
    assert not re.search(r"%(?!25|0D|0A)", message) and "\r" not in message, message
    values = {}
    for prop in (props or "").split(","):
        key, sep, value = prop.partition("=")
        assert sep and key in PROPERTIES and key not in values, prop
        assert not re.search(r"%(?!25|0D|0A|3A|2C)", value), value
        values[key] = value
    for key in ("line", "endLine", "col", "endColumn"):
        assert key not in values or values[key].isdigit() and int(values[key]) >= 1, values
    return command, values, message


def unescape(text: str) -> str:
    for esc, char in (("%0D", "\r"), ("%0A", "\n"), ("%3A", ":"), ("%2C", ","), ("%25", "%")):
        text = text.replace(esc, char)
    return text


@pytest.fixture(scope="module")
def urdfs(tmp_path_factory):
    """One URDF with an error (triangle inequality) and one with only a warning (inertia box 3x)."""
    folder = tmp_path_factory.mktemp("urdfs")
    bad, warn = folder / "bad.urdf", folder / "warn.urdf"
    bad.write_text(arm_urdf(arm=link_xml("arm", inertia=(0.01, 0.01, 0.05))))
    warn.write_text(arm_urdf(arm=link_xml("arm", inertia=tuple(3 * v for v in box_inertia(16.2, 0.1, 0.2, 0.3)))))
    return folder


def link_line(path: Path, name: str) -> int:
    return next(i for i, line in enumerate(path.read_text().splitlines(), 1) if f'<link name="{name}">' in line)


@pytest.mark.consumers
@pytest.mark.slow
def test_junit_counts_failures_at_each_fail_on(urdfs, junit_schema):
    warn = urdfs / "warn.urdf"
    proc = run_cli("check", warn, "--format", "junit")
    assert proc.returncode == 0, proc.stderr
    doc = junit(junit_schema, proc.stdout)
    suite = doc.find("testsuite")
    assert (suite.get("tests"), suite.get("failures")) == ("5", "0")
    # one case per check and subject: what fired, then what ran and passed
    assert [(c.get("classname"), c.get("name"), [e.tag for e in c]) for c in suite] == [
        ("robotkit.inertia-box", "link 'arm'", ["system-out"]),
        ("robotkit.check_urdf", str(warn), []),
        ("robotkit.consumer", "robot 'warn'", []),
        ("robotkit.lints", "link 'base'", []),
        ("robotkit.lints", "joint 'shoulder'", [])]
    case = suite.find("testcase")
    assert case.find("system-out").text.startswith(f"{warn}:{link_line(warn, 'arm')}: warning: ")

    proc = run_cli("check", warn, "--format", "junit", "--fail-on", "warning")
    assert proc.returncode == 1
    doc = junit(junit_schema, proc.stdout)
    assert doc.get("failures") == doc.find("testsuite").get("failures") == "1"
    failure = doc.find("testsuite/testcase/failure")
    assert failure.get("type") == "warning"


@pytest.mark.consumers
@pytest.mark.slow
def test_junit_error_is_a_failing_case(urdfs, junit_schema):
    proc = run_cli("check", urdfs / "bad.urdf", "--format", "junit")
    assert proc.returncode == 1
    doc = junit(junit_schema, proc.stdout)
    assert doc.find("testsuite").get("failures") == "1"
    case = doc.find("testsuite/testcase[@classname='robotkit.triangle-inequality']")
    assert case.get("name") == "link 'arm'" and case.find("failure").get("type") == "error"


@pytest.mark.consumers
@pytest.mark.slow
def test_github_annotations_name_the_urdf_line(urdfs):
    bad, warn = urdfs / "bad.urdf", urdfs / "warn.urdf"
    proc = run_cli("check", bad, warn, "--format", "github", cwd=urdfs)
    assert proc.returncode == 1
    lines = [line for line in proc.stdout.splitlines() if "title=robotkit consumer" not in line]
    for line in proc.stdout.splitlines():
        workflow_command(line)
    assert [workflow_command(line)[:2] for line in lines] == [
        ("error", {"file": "bad.urdf", "line": str(link_line(bad, "arm")), "title": "robotkit triangle-inequality"}),
        ("warning", {"file": "warn.urdf", "line": str(link_line(warn, "arm")), "title": "robotkit inertia-box"})]
    assert unescape(workflow_command(lines[0])[2]).startswith("link 'arm': principal moments 0.01, 0.01, 0.05")
    # --fail-on warning: the warning fails the run, so it is an error annotation (titled a warning)
    proc = run_cli("check", warn, "--format", "github", "--fail-on", "warning", cwd=urdfs)
    assert proc.returncode == 1
    assert workflow_command(proc.stdout.strip())[:2] == (
        "error", {"file": "warn.urdf", "line": str(link_line(warn, "arm")), "title": "robotkit inertia-box (warning)"})


@pytest.mark.consumers
@pytest.mark.slow
def test_text_and_json_reflect_fail_on(urdfs):
    proc = run_cli("check", "warn.urdf", "--fail-on", "warning", cwd=urdfs)
    # each stage with its verdict (the lint's warning is the lints stage's), then the problem
    assert proc.stdout.splitlines()[:4] == ["  ok         check_urdf", "  1 warning  lints (3 links and joints)",
                                            "  ok         consumers", f"link 'arm' (warn.urdf:{link_line(urdfs / 'warn.urdf', 'arm')})"]
    assert re.fullmatch(r"warn\.urdf: 2 stages passed, 0 errors, 1 warning \(they fail the check: --fail-on "
                        r"warning\) \(\d+\.\d s\)", proc.stdout.splitlines()[-1])
    data = json.loads(run_cli("check", urdfs / "warn.urdf", "--format", "json", "--fail-on", "warning").stdout)
    assert (data["fail_on"], data["failed"], data["warnings"]) == ("warning", 1, 1)
    assert data["stages"] == [{"stage": "check_urdf", "verdict": "ok", "subjects": 1},
                              {"stage": "lints", "verdict": "1 warning", "subjects": 3},
                              {"stage": "consumers", "verdict": "ok", "subjects": 1}]


BAD_RECIPE = "robot: x\nlinks:\n  a:\n    visual: {box: {size: [0.1, 0.1]}}\n    inertial: {denisty: 3}\n"
BAD_LINES = ["bad.yaml:4: links.a.visual.box.size: must have 3 values (got 2)",
             "bad.yaml:5: links.a.inertial.denisty: unknown key (did you mean 'density'?)"]


@pytest.mark.consumers
@pytest.mark.parametrize("fmt", ["text", "junit", "github", "json"])
def test_a_recipe_that_does_not_load_is_reported_in_every_format(tmp_path, junit_schema, fmt):
    (tmp_path / "bad.yaml").write_text(BAD_RECIPE)
    proc = run_cli("check", "bad.yaml", "--format", fmt, "--out", "out", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == BAD_LINES
    assert not (tmp_path / "out").exists()
    if fmt == "text":
        assert proc.stdout == ""
    elif fmt == "junit":
        doc = junit(junit_schema, proc.stdout)
        assert doc.find("testsuite").get("failures") == "2"
        assert [(c.get("classname"), c.get("name"), c.find("failure").text)
                for c in doc.iter("testcase")] == [
            ("robotkit.input", "links.a.visual.box.size", "bad.yaml:4: error: must have 3 values (got 2)"),
            ("robotkit.input", "links.a.inertial.denisty",
             "bad.yaml:5: error: unknown key (did you mean 'density'?)")]
    elif fmt == "github":
        assert proc.stdout.splitlines() == [
            "::error file=bad.yaml,line=4,title=robotkit input::links.a.visual.box.size: must have 3 values (got 2)",
            "::error file=bad.yaml,line=5,title=robotkit input::links.a.inertial.denisty: unknown key "
            "(did you mean 'density'?)"]
        for line in proc.stdout.splitlines():
            workflow_command(line)
    else:
        data = json.loads(proc.stdout)
        assert (data["errors"], data["failed"]) == (2, 2)
        assert [(f["check"], f["line"]) for f in data["findings"]] == [("input", 4), ("input", 5)]


@pytest.mark.consumers
def test_a_missing_path_is_a_failing_case(tmp_path, junit_schema):
    proc = run_cli("check", "nothing.urdf", "--format", "junit", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr == "nothing.urdf: no such file or folder\n"
    case = junit(junit_schema, proc.stdout).find("testsuite/testcase")
    assert (case.get("classname"), case.get("name")) == ("robotkit.input", "nothing.urdf")
    assert case.find("failure").text == "nothing.urdf: error: no such file or folder"


def test_annotation_escapes_properties_and_message():
    from robotkit.check.findings import Finding
    from robotkit.check.render import annotation

    f = Finding("warning", "mass,odd", "link 'a:b'", "50% off\nsecond line", file="dir,x/r:1.yaml", line=3)
    line = annotation(f)
    assert line == ("::warning file=dir%2Cx/r%3A1.yaml,line=3,title=robotkit mass%2Codd::"
                    "link 'a:b': 50%25 off%0Asecond line")
    command, props, message = workflow_command(line)
    assert unescape(props["file"]) == "dir,x/r:1.yaml" and unescape(message) == "link 'a:b': 50% off\nsecond line"


@pytest.mark.consumers
@pytest.mark.slow
def test_recipe_build_warnings_are_annotated_on_their_line(tmp_path):
    """A build's warnings reach the CI formats on the line that causes them (not the robot's)."""
    import trimesh

    from conftest import write_recipe
    from tests.pipeline.test_build_warnings import RECIPE

    write_recipe(tmp_path, RECIPE, "careless.yaml",
                 {"wheel.stl": trimesh.creation.cylinder(radius=66.0, height=26.0, sections=64)})
    proc = run_cli("check", "careless.yaml", "--temp-out", "--format", "github", cwd=tmp_path)
    builds = [workflow_command(line) for line in proc.stdout.splitlines() if "title=robotkit build" in line]
    assert [(c, p["file"], p["line"], unescape(m)) for c, p, m in builds] == [
        ("warning", "careless.yaml", "11", "links.wheel.visual.mesh: mesh 'wheel.stl' is 132 m across as declared "
         "(scale 1): a mesh in millimetres declared as metres? (units: mm)"),
        ("warning", "careless.yaml", "14", "links.payload.inertial: link 'payload': mass 2000 kg in 0.001 m^3 of "
         "visual geometry implies 2e+06 kg/m^3, outside 10..25000 (grams written as kilograms, or a mesh in "
         "millimetres declared as metres?)"),
        ("warning", "careless.yaml", "6", "materials.blue: material 'blue': used by no geometry"),
        ("warning", "careless.yaml", "23", "actuators.wheel_joint: joint 'wheel_joint': the velocity actuator has no "
         "force range in MuJoCo (unbounded torque) without an effort limit (give the joint limit: {effort: ...})")]
    assert not (tmp_path / "build").exists()  # --temp-out


@pytest.mark.consumers
@pytest.mark.slow
def test_sdf_and_mjcf_findings_name_their_line(tmp_path):
    (tmp_path / "m.sdf").write_text(
        '<?xml version="1.0"?>\n<sdf version="1.9">\n  <model name="m">\n    <link name="a">\n'
        '      <pose>0 0 0 0 0 0</pose>\n    </link>\n  </model>\n</sdf>\n')
    proc = run_cli("check", "m.sdf", "--format", "github", cwd=tmp_path)
    assert proc.returncode == 1
    assert [workflow_command(line)[:2] for line in proc.stdout.splitlines()] == [
        ("error", {"file": "m.sdf", "line": "4", "title": "robotkit consumer"})]
    (tmp_path / "m.xml").write_text('<mujoco model="m">\n  <worldbody>\n    <body name="b">\n'
                                    '      <geom type="box" size="0.1 0.1 0.1" mass="-1"/>\n    </body>\n'
                                    '  </worldbody>\n</mujoco>\n')
    proc = run_cli("check", "m.xml", "--format", "github", cwd=tmp_path)
    assert proc.returncode == 1
    command, props, message = workflow_command(proc.stdout.strip())
    assert (command, props) == ("error", {"file": "m.xml", "line": "1", "title": "robotkit mujoco"}), message
    (tmp_path / "t.xml").write_text(
        '<mujoco model="m">\n  <worldbody>\n    <body name="b">\n'
        '      <inertial pos="0 0 0" mass="5e-7" diaginertia="4e-14 4e-14 4e-14"/>\n'
        '      <geom type="sphere" size="0.0005" contype="0"/>\n    </body>\n  </worldbody>\n</mujoco>\n')
    proc = run_cli("check", "t.xml", "--format", "github", cwd=tmp_path)
    assert proc.returncode == 0
    assert [workflow_command(line)[:2] for line in proc.stdout.splitlines()] == [
        ("warning", {"file": "t.xml", "line": "3", "title": "robotkit tiny-mass"})]  # the <body name="b"> line


@pytest.mark.consumers
@pytest.mark.slow
def test_several_paths_one_missing(urdfs):
    """The paths that can be checked are, the bad one is named, and the exit status is 2."""
    proc = run_cli("check", "warn.urdf", "nothing.urdf", cwd=urdfs)
    assert proc.returncode == 2
    assert proc.stderr == "nothing.urdf: no such file or folder\n"
    assert re.fullmatch(r"warn\.urdf nothing\.urdf: 2 stages passed, 0 errors, 1 warning \(\d+\.\d s\)",
                        proc.stdout.splitlines()[-1])


def test_text_lists_each_stage_then_the_problems_once_per_kind():
    """A stage per line with its verdict; a finding said of several subjects is one, with the
    count and the subjects; a validator whose program is missing is skipped, and says why."""
    from robotkit.check.findings import Finding
    from robotkit.check.render import render

    findings = [Finding("warning", "com-offset", "link 'a'", "centre of mass outside", file="r.urdf", line=3),
                Finding("warning", "com-offset", "link 'b'", "centre of mass outside", file="r.urdf", line=7),
                Finding("error", "tree", "joint 'j'", "its joints form a cycle"),
                Finding("warning", "ign sdf -k", "r.sdf", "ign is not installed", "apt install ignition-tools")]
    cases = [("check_urdf", "r.urdf"), ("ign sdf -k", "r.sdf"), ("lints", "link 'a'"), ("lints", "link 'b'"),
             ("lints", "joint 'j'"), ("consumer", "robot 'r'")]
    assert render(findings, "text", "r.urdf", cases=cases, elapsed=1.23).splitlines() == [
        "  ok                   check_urdf",
        "  skipped              ign sdf -k  (ign is not installed)",
        "  1 error, 2 warnings  lints (3 links and joints)",
        "  ok                   consumers",
        "link 'a' and 1 more (link 'b') (r.urdf:3)",
        "  warning: centre of mass outside [com-offset]",
        "joint 'j'",
        "  error: its joints form a cycle [tree]",
        "r.sdf",
        "  warning: ign is not installed [ign sdf -k]",
        "    hint: apt install ignition-tools",
        "r.urdf: 2 stages passed, 1 error, 3 warnings (1.2 s)"]


def test_junit_has_no_passing_build_case_beside_the_build_s_warnings():
    from robotkit.check.findings import Finding
    from robotkit.check.render import render

    cases = [("build", "robot 'r'"), ("check_urdf", "r.urdf")]
    warned = [Finding("warning", "build", "links.a", "r: MJCF: lost", file="r.yaml", line=3)]
    for findings, expected in ((warned, [("robotkit.build", "links.a"), ("robotkit.check_urdf", "r.urdf")]),
                               ([], [("robotkit.build", "robot 'r'"), ("robotkit.check_urdf", "r.urdf")])):
        suite = ET.fromstring(render(findings, "junit", "r.yaml", cases=cases)).find("testsuite")
        assert [(c.get("classname"), c.get("name")) for c in suite] == expected


def test_json_gives_each_timed_stage_its_seconds():
    from robotkit.check.findings import Finding
    from robotkit.check.render import render

    findings = [Finding("warning", "mass", "link 'a'", "light")]
    cases = [("check_urdf", "r.urdf"), ("mass", "link 'a'")]
    data = json.loads(render(findings, "json", "r", cases=cases, elapsed=2.5, timings={"lints": 1.23456}))
    assert data["stages"] == [{"stage": "check_urdf", "verdict": "ok", "subjects": 1},
                              {"stage": "lints", "verdict": "1 warning", "subjects": 1, "seconds": 1.235}]
    assert data["seconds"] == 2.5
