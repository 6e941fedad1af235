from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from robotkit.ioutil import environ
from robotkit.paths import ROOT_ENV

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO.parent / "shared" / "assets"
RECIPES = REPO / "recipes"
GOLDEN = Path(__file__).resolve().parent / "golden"


def example_robots() -> list[str]:
    """The robot folders the example recipes build (a recipe with variants builds several)."""
    from robotkit.recipe.load import load_recipes

    return sorted(one.recipe.robot for p in RECIPES.glob("*.yaml") for one in load_recipes(p))


@pytest.fixture(scope="session", autouse=True)
def mesh_cache(tmp_path_factory):
    """One mesh cache for the test session (builds in subprocesses inherit it): CoACD and
    friends run once per session, and the user's own cache is never touched."""
    folder = tmp_path_factory.mktemp("robotkit-cache")
    with environ({"ROBOTKIT_CACHE": str(folder)}):
        yield folder


@pytest.fixture(scope="session", autouse=True)
def read_roots(tmp_path_factory):
    """Test recipes written to temporary folders read the example meshes, the shared assets and
    the packages other tests lay out beside them: widened on purpose, as a user would with
    ``--root`` (tests of the read rules unset it)."""
    with environ({ROOT_ENV: os.pathsep.join([str(REPO), str(ASSETS), str(tmp_path_factory.getbasetemp())])}):
        yield


@pytest.fixture(scope="session")
def examples(tmp_path_factory) -> Path:
    """Every example recipe of recipes/ built once per session (tests that change a build copy it first)."""
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("examples")
    result = build(sorted(RECIPES.glob("*.yaml")), out)
    assert not result.errors, result.errors
    return out


@pytest.fixture
def assets() -> Path:
    if not ASSETS.is_dir():
        pytest.fail(f"test assets not found at {ASSETS} (CI clones the repository next to shared/)")
    return ASSETS


def write_recipe(folder: Path, text: str, name: str = "robot.yaml", meshes: dict | None = None) -> Path:
    """Write a recipe (dedented) and optional meshes {file name: trimesh or path} into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for file_name, mesh in (meshes or {}).items():
        dst = folder / file_name
        dst.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(mesh, (str, Path)):
            shutil.copyfile(mesh, dst)
        else:
            mesh.export(dst)
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """Run the robotkit command in a separate process, as a user would."""
    return subprocess.run([sys.executable, "-m", "robotkit", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd)


def tree_bytes(folder: Path) -> dict[str, bytes]:
    """Every output file below ``folder`` (state folder excluded), by relative path."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and ".robotkit" not in p.parts}


def assert_golden(got_path: Path, golden: Path):
    """Compare a generated file with its checked-in golden copy (ROBOTKIT_UPDATE_GOLDEN=1 rewrites it)."""
    import os

    got = got_path.read_text(encoding="utf-8")
    if os.environ.get("ROBOTKIT_UPDATE_GOLDEN"):
        golden.parent.mkdir(parents=True, exist_ok=True)
        golden.write_text(got, encoding="utf-8")
    assert got == golden.read_text(encoding="utf-8"), f"{got_path.name} differs from {golden}"
