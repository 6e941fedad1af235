"""scripts/setup.sh where apt-get cannot install (the dpkg lock held by another apt): it fails with
one line saying what to run when the quick start's build would need the package, and under CI when
a test would; and where pip cannot install robotkit (it used to carry on).  The script is run from a scratch copy of scripts/ (it works in the folder above it) with
PATH limited to the tools it calls and fakes of ``ldconfig`` (what is installed) and ``apt-get``
(which refuses as apt does with the lock held) and ``python3`` (one with venv), so it never reaches
the venv or pip."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from conftest import REPO

LOCKED = "E: Could not get lock /var/lib/dpkg/lock-frontend. It is held by process 4242 (apt-get)"
APT_GET = f'''#!/bin/sh
[ "$1" = update ] && exit 0
echo "{LOCKED}" >&2
echo "E: Unable to acquire the dpkg frontend lock (/var/lib/dpkg/lock-frontend), is another process using it?" >&2
exit 100
'''


def run_setup(tmp_path: Path, osmesa: bool, *args: str, **env) -> subprocess.CompletedProcess:
    (tmp_path / "scripts").mkdir()
    shutil.copy(REPO / "scripts" / "setup.sh", tmp_path / "scripts" / "setup.sh")
    bin_ = tmp_path / "bin"
    bin_.mkdir()
    for tool in ("bash", "dirname", "grep", "id", "tail"):
        os.symlink(shutil.which(tool), bin_ / tool)
    fakes = {"apt-get": APT_GET, "sudo": '#!/bin/sh\nexec "$@"\n', "python3": "#!/bin/sh\n",  # with venv
             "ldconfig": "#!/bin/sh\n" + ("echo '\tlibOSMesa.so.8 (libc6,x86-64) => /lib/libOSMesa.so.8'\n" * osmesa)}
    for name, text in fakes.items():
        (bin_ / name).write_text(text)
        (bin_ / name).chmod(0o755)
    return subprocess.run([str(bin_ / "bash"), "scripts/setup.sh", *args], cwd=tmp_path, capture_output=True,
                          text=True, env={"PATH": str(bin_), "HOME": str(tmp_path), **env})


def sudo() -> str:
    return "" if os.getuid() == 0 else "sudo "


def test_setup_fails_with_what_to_run_when_the_build_needs_a_package_it_cannot_install(tmp_path):
    done = run_setup(tmp_path, osmesa=False)
    assert done.returncode == 1
    assert done.stderr.splitlines()[-1] == (f"setup.sh: could not install libosmesa6 ({LOCKED[3:]}); "
                                            f"run: {sudo()}apt-get install -y libosmesa6")
    assert not (tmp_path / ".venv").exists()


def test_setup_check_fails_under_ci_when_a_validator_cannot_be_installed(tmp_path):
    done = run_setup(tmp_path, True, "--check", CI="true")
    assert done.returncode == 1
    packages = "liburdfdom-tools libsdformat-dev ignition-tools"
    assert done.stderr.splitlines() == [
        f"installing Debian packages: {packages}",
        f"setup.sh: could not install {packages} ({LOCKED[3:]}); run: {sudo()}apt-get install -y {packages}"]
    assert not (tmp_path / ".venv").exists()


def test_setup_fails_with_what_to_run_when_pip_cannot_install_robotkit(tmp_path):
    venv = tmp_path / ".venv" / "bin"
    venv.mkdir(parents=True)
    (venv / "python").write_text('#!/bin/sh\n[ "$2" = pip ] || exit 0\n'
                                 'echo "ERROR: No matching distribution found for mujoco>=3" >&2\nexit 1\n')
    (venv / "python").chmod(0o755)
    done = run_setup(tmp_path, True)
    assert done.returncode == 1
    assert done.stderr.splitlines() == [
        "ERROR: No matching distribution found for mujoco>=3",
        "setup.sh: pip could not install robotkit (its error above); run: .venv/bin/python -m pip install -e '.'"]
