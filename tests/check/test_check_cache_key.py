"""What the check's stage cache is keyed by (robotkit.check.cache): the libraries' versions read
from their dist-info folders as importlib.metadata reads them; the outside programs' files."""

from __future__ import annotations

from robotkit.check.cache import LIBRARIES, installed_versions, programs
from robotkit.mesh.cache import library_versions


def test_the_versions_are_importlib_metadatas():
    assert installed_versions(LIBRARIES) == library_versions(LIBRARIES)
    assert installed_versions(("no-such-distribution",))["no-such-distribution"] == "not installed"


def test_the_programs_are_named_with_their_files():
    lines = programs().splitlines()
    assert len(lines) >= 2  # check_urdf and ign, each found or missing
    assert all(line.endswith(":missing") or line.rsplit(":", 2)[1].isdigit() for line in lines)
