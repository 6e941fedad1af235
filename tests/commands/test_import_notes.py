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
