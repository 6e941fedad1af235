"""What a new user and a CI pipeline run, run as they would: the README's quick start verbatim
in a fresh shell on a fresh copy of the repository (one fresh venv for the session, installed by
scripts/setup.sh without the test extra: a plain install), its transcript, the GitHub action's
steps, and the pre-commit hook through pre-commit's own ``try-repo`` on a scratch repository."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

from conftest import REPO

pytestmark = [pytest.mark.slow]

README = REPO / "README.md"


def fresh_env(**extra) -> dict[str, str]:
    """A new shell's environment: no virtualenv active, nothing of this test process on PATH."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    skip = {str(Path(sys.prefix) / "bin"), str(Path(sys.executable).parent)}
    path = [p for p in env.get("PATH", "").split(os.pathsep) if p and p not in skip and "/.venv/" not in p + "/"]
    env["PATH"] = os.pathsep.join(path + [d for d in ("/usr/sbin", "/usr/bin", "/sbin", "/bin") if d not in path])
    env.update(extra)
    return env


def shell(script: str, cwd: Path, env=None, check=True) -> subprocess.CompletedProcess:
    proc = subprocess.run(["bash", "-e", "-c", script], cwd=cwd, env=env or fresh_env(), capture_output=True,
                          text=True)
    if check:
        assert proc.returncode == 0, f"$ {script}\n{proc.stdout}\n{proc.stderr}"
    return proc


def sh_blocks(markdown: str) -> list[str]:
    return re.findall(r"```sh\n(.*?)```", markdown, flags=re.S)


@pytest.fixture(scope="session")
def clone(tmp_path_factory) -> Path:
    """The repository as a fresh clone has it (tracked files, and new ones not yet committed, as
    they are in the working tree), as a git repository of its own."""
    dst = tmp_path_factory.mktemp("fresh") / "robotkit"
    files = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=REPO,
                           capture_output=True, check=True).stdout.decode().split("\0")
    for rel in filter(None, files):
        src = REPO / rel
        if src.is_file():
            (dst / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / rel)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@example.org"]
    for cmd in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "fresh"]):
        subprocess.run(git + cmd, cwd=dst, check=True, capture_output=True)
    return dst


@pytest.fixture(scope="session")
def quick_start(clone) -> subprocess.CompletedProcess:
    """The README's first command block, verbatim, in a fresh shell."""
    block = sh_blocks(README.read_text(encoding="utf-8"))[0]
    return shell(block, clone, check=False)


def test_readme_quick_start_works_verbatim(clone, quick_start):
    assert quick_start.returncode == 0, quick_start.stdout + quick_start.stderr
    assert re.search(r"^built build/turret_bot: \d+ tasks run, 0 up to date \(\d+\.\d\d s\)$",
                     quick_start.stdout, flags=re.M), quick_start.stdout
    assert "Traceback" not in quick_start.stderr
    # a plain install (no test extra) checks with MuJoCo and says what it did not load the robot into
    lines = quick_start.stdout.splitlines()
    assert re.fullmatch(r"build/turret_bot: \d+ stages passed, 0 errors, 4 warnings \(\d+\.\d s\)", lines[-1]), \
        quick_start.stdout
    assert "  4 warnings  consumers" in lines  # Drake, Pinocchio and PyBullet not installed
    assert sorted(line.strip() for line in lines if "not checked" in line) == [
        "warning: Drake (URDF): not checked: Drake is not installed (pip install drake) [consumer]",
        "warning: Drake (model.sdf): not checked: Drake is not installed (pip install drake) [consumer]",
        "warning: Pinocchio (URDF): not checked: Pinocchio is not installed (pip install pin) [consumer]",
        "warning: PyBullet (URDF): not checked: PyBullet is not installed (pip install pybullet) [consumer]"]
    assert (clone / "build" / "turret_bot" / "urdf" / "turret_bot.urdf").is_file()


def test_readme_transcript_matches_the_output(clone, quick_start):
    """The README's transcript of a build and a second build doing nothing, run after
    ``source .venv/bin/activate`` (which the README says the later commands assume)."""
    assert quick_start.returncode == 0
    text = README.read_text(encoding="utf-8")
    transcript = re.search(r"A second build does nothing.*?```\n(.*?)```", text, flags=re.S).group(1)
    commands = [line[2:] for line in transcript.splitlines() if line.startswith("$ ")]
    outputs = [line for line in transcript.splitlines() if not line.startswith("$ ")]
    shutil.rmtree(clone / "build")
    got = []
    for command in commands:
        got += shell(f"source .venv/bin/activate\n{command}", clone).stdout.splitlines()

    def timeless(line: str) -> str:
        return re.sub(r"\d+\.\d\d s\)", "T s)", line)

    assert [timeless(line) for line in got] == [timeless(line) for line in outputs]
    # `doit` in the repository root has the same tasks for every recipe in recipes/
    listed = shell("source .venv/bin/activate\ndoit list", clone).stdout.split()
    assert "turret_bot:urdf" in listed and "ur5:urdf" in listed


GOOD = """\
robot: box_bot
metadata: {maintainers: [{name: A, email: a@example.org}]}
links:
  base: {visual: {box: {size: [0.2, 0.2, 0.1]}}}
"""
BAD = "robot: bad_bot\nlinks:\n  a:\n    visual: {box: {size: [0.1, 0.1, 0.1]}}\n    inertial: {denisty: 3}\n"
BAD_LINE = "recipes/bad.yaml:5: links.a.inertial.denisty: unknown key (did you mean 'density'?)"


def scratch_repo(folder: Path) -> Path:
    (folder / "recipes").mkdir(parents=True)
    (folder / "recipes" / "good.yaml").write_text(GOOD)
    (folder / "recipes" / "bad.yaml").write_text(BAD)
    subprocess.run(["git", "init", "-q"], cwd=folder, check=True)
    subprocess.run(["git", "add", "-A"], cwd=folder, check=True)
    return folder


def test_github_action_steps_run_locally(clone, quick_start, tmp_path):
    """action.yml's steps as GitHub runs a composite action's bash steps (bash -eo pipefail,
    GITHUB_ACTION_PATH, inputs through env), on a workspace with a good and a bad recipe."""
    import xmlschema

    assert quick_start.returncode == 0
    action = yaml.safe_load((clone / "action.yml").read_text(encoding="utf-8"))
    assert action["runs"]["using"] == "composite"
    inputs = {name: spec.get("default", "") for name, spec in action["inputs"].items()}
    workspace = scratch_repo(tmp_path / "workspace")
    summary = tmp_path / "summary.md"
    results = []
    for step in action["runs"]["steps"]:
        assert step["shell"] == "bash" and "${{" not in step["run"]  # inputs reach scripts through env only
        env = fresh_env(GITHUB_ACTION_PATH=str(clone), GITHUB_WORKSPACE=str(workspace),
                        GITHUB_STEP_SUMMARY=str(summary))
        for key, value in step.get("env", {}).items():
            env[key] = re.sub(r"\$\{\{ inputs\.([\w-]+) \}\}", lambda m: inputs[m.group(1)], value)
        results.append(subprocess.run(["bash", "--noprofile", "--norc", "-eo", "pipefail", "-c", step["run"]],
                                      cwd=workspace, env=env, capture_output=True, text=True))
    setup, check = results
    assert setup.returncode == 0, setup.stderr
    assert check.returncode == 2, check.stdout + check.stderr  # bad input fails the step
    assert check.stderr.splitlines() == [BAD_LINE]
    annotations = check.stdout.splitlines()
    assert annotations[0] == ("::error file=recipes/bad.yaml,line=5,title=robotkit input::links.a.inertial.denisty: "
                              "unknown key (did you mean 'density'?)")
    assert not [line for line in annotations if line.startswith("::error") and "bad.yaml" not in line]
    report = workspace / "build" / "robotkit-check.xml"
    xmlschema.XMLSchema(REPO / "tests" / "data" / "schemas" / "junit-10.xsd").validate(str(report))
    suite = ET.parse(report).getroot().find("testsuite")
    assert suite.get("failures") == "1"
    assert (workspace / "build" / "box_bot" / "report" / "report.html").is_file()
    assert "## robotkit check recipes/bad.yaml recipes/good.yaml" in summary.read_text()


def test_pre_commit_hook_through_try_repo(clone, tmp_path):
    """pre-commit's own try-repo on a scratch repository: several files in one run, the hook's
    environment built from the declared dependencies, nothing written into the repository."""
    scratch = scratch_repo(tmp_path / "scratch")
    env = fresh_env(PRE_COMMIT_HOME=str(tmp_path / "pre-commit-home"))
    run = [sys.executable, "-m", "pre_commit", "try-repo", str(clone), "robotkit-check", "--verbose", "--files"]
    both = subprocess.run(run + ["recipes/good.yaml", "recipes/bad.yaml"], cwd=scratch, env=env,
                          capture_output=True, text=True)
    assert both.returncode == 1, both.stdout + both.stderr
    assert re.search(r"^robotkit check\.+Failed$", both.stdout, flags=re.M), both.stdout
    assert BAD_LINE in both.stdout.splitlines()
    good = subprocess.run(run + ["recipes/good.yaml"], cwd=scratch, env=env, capture_output=True, text=True)
    assert good.returncode == 0, good.stdout + good.stderr
    assert re.search(r"^robotkit check\.+Passed$", good.stdout, flags=re.M), good.stdout
    status = subprocess.run(["git", "status", "--porcelain", "--ignored"], cwd=scratch, capture_output=True,
                            text=True, check=True).stdout
    assert status.splitlines() == ["A  recipes/bad.yaml", "A  recipes/good.yaml"]
