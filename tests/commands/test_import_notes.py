"""robotkit import on the command line: where the metadata came from is a note, not a warning."""

from __future__ import annotations

import shutil

from conftest import ASSETS, run_cli


def test_package_metadata_is_a_note(tmp_path):
    pkg = tmp_path / "kinova_description"
    (pkg / "urdf").mkdir(parents=True)
    shutil.copyfile(ASSETS / "robots" / "kinova_description" / "package.xml", pkg / "package.xml")
    (pkg / "urdf" / "box.urdf").write_text(
        '<robot name="box"><link name="base"><visual><geometry><box size="1 1 1"/></geometry></visual></link></robot>')
    proc = run_cli("import", pkg / "urdf" / "box.urdf", "-o", "box.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == ["note: metadata from kinova_description/package.xml"]


INERTIAL = ('<inertial><mass value="1"/><inertia ixx="0.001667" ixy="0" ixz="0" iyy="0.001667" iyz="0" '
            'izz="0.001667"/></inertial>')


def test_each_repair_is_one_warning_line(tmp_path):
    """A name that loses its leading '/' and a joint limit of about 1e16 ("unlimited"): one line each."""
    (tmp_path / "arm.urdf").write_text(
        '<robot name="arm"><link name="/base">' + INERTIAL + '<visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>'
        '<link name="rotor">' + INERTIAL + '<visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>'
        '<joint name="spin" type="revolute"><parent link="/base"/><child link="rotor"/><axis xyz="0 0 1"/>'
        '<limit lower="-1e16" upper="1e16" effort="1" velocity="1"/></joint></robot>')
    proc = run_cli("import", "arm.urdf", "-o", "arm.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == [
        "warning: joint 'spin': limit lower -1e+16 and upper 1e+16 in the original, beyond any physical range (a "
        "recipe's is +-10000): read as no position limit, the joint is continuous",
        "warning: link 'base': named '/base' in the original: a recipe name cannot start with '/' (the old tf_prefix "
        "style), so the '/' is dropped here and where its joints and gazebo blocks name it"]
