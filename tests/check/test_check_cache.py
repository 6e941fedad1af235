"""The check's pure stages cached by content (robotkit.check.cache): a second check of the same
build folder gives the same findings and motion results from the cache, a changed file is a
miss, ROBOTKIT_CHECK_CACHE=0 stores nothing."""

from __future__ import annotations

import dataclasses
import shutil

import pytest

from conftest import RECIPES
from robotkit.check import check_build_dir
from robotkit.check.cache import StageCache, stage_cache
from robotkit.check.findings import Finding
from robotkit.emit.layout import robot_layout

pytestmark = [pytest.mark.consumers]

CACHED = ("consumers", "self-collision", "motion mujoco", "motion pybullet", "motion drake")


@pytest.fixture(scope="module")
def ur5(tmp_path_factory):
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ur5")
    result = build([RECIPES / "ur5.yaml"], out, report=False)
    assert not result.errors, result.errors
    return out / "ur5"


def without_walls(value):
    """Motion results without their wall times (a cached run keeps the time it took when computed)."""
    if isinstance(value, dict):
        return {k: without_walls(v) for k, v in value.items() if k not in ("wall", "wall_per_joint")}
    if isinstance(value, list):
        return [without_walls(v) for v in value]
    return value


def test_a_second_check_takes_the_pure_stages_from_the_cache(ur5, tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    assert not any(StageCache(ur5).has(stage) for stage in CACHED)
    first_motion, second_motion = {}, {}
    first = check_build_dir(ur5, motion=first_motion)
    assert all(StageCache(ur5).has(stage) for stage in CACHED)
    second = check_build_dir(ur5, motion=second_motion)
    assert second == first
    assert without_walls(second_motion) == without_walls(first_motion)
    # what comes out is what the cache holds: a finding put there is reported
    planted = Finding("warning", "self-collision", "robot 'ur5'", "planted in the cache")
    StageCache(ur5).put("self-collision", [dataclasses.asdict(planted)])
    assert planted in check_build_dir(ur5)


def test_a_changed_file_is_a_miss(ur5, tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    copy = tmp_path / "ur5"
    shutil.copytree(ur5, copy)
    StageCache(copy).put("consumers", [])
    assert StageCache(copy).has("consumers")
    urdf = copy / "urdf" / "ur5.urdf"
    urdf.write_text(urdf.read_text(encoding="utf-8") + "<!-- changed -->\n", encoding="utf-8")
    assert not StageCache(copy).has("consumers")
    report = robot_layout(copy).report_html  # the picture report: no stage reads it
    report.parent.mkdir(exist_ok=True)
    report.write_text("<html></html>", encoding="utf-8")
    StageCache(copy).put("consumers", [])
    report.write_text("<html>again</html>", encoding="utf-8")
    assert StageCache(copy).has("consumers")


def test_turned_off_it_stores_nothing(ur5, tmp_path, monkeypatch):
    monkeypatch.setenv("ROBOTKIT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("ROBOTKIT_CHECK_CACHE", "0")
    assert stage_cache(ur5) is None
    check_build_dir(ur5)
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").rglob("*.json"))
