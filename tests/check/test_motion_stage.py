"""The motion stage of robotkit check: the UR5 example's auto drives step cleanly and alike in
MuJoCo, PyBullet and Drake; a drive made absurdly stiff fails the check with its figure and
fix; the Kinova Gen3 as Menagerie had it before its armature fix fails on joint_7."""

from __future__ import annotations

import re
import shutil

import pytest

from conftest import ASSETS, RECIPES, run_cli
from robotkit.check.motion.stage import drives_from_mjcf, motion_stage

pytestmark = [pytest.mark.consumers, pytest.mark.slow]

UR5_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint"]
GEN3 = ASSETS / "menagerie" / "kinova_gen3" / "gen3.xml"


@pytest.fixture(scope="module")
def ur5(tmp_path_factory):
    """The UR5 example built once for this module (its folder OUT/ur5)."""
    from robotkit.pipeline.runner import build

    out = tmp_path_factory.mktemp("ur5")
    result = build([RECIPES / "ur5.yaml"], out, report=False)
    assert not result.errors, result.errors
    return out / "ur5"


@pytest.fixture(scope="module")
def ur5_motion(ur5):
    return motion_stage(ur5 / "mjcf" / "ur5.xml", ur5 / "urdf" / "ur5.urdf", {"ur5": ur5})


def test_drives_read_from_the_mjcf(ur5):
    drives, poses, integrator, timestep = drives_from_mjcf(ur5 / "mjcf" / "ur5.xml")
    assert [d.joint for d in drives] == UR5_JOINTS
    assert all(d.interface == "position" and d.kp > 0 and d.kd > 0 and d.gravcomp for d in drives)
    assert list(poses) == ["home"] and poses["home"]["elbow_joint"] == pytest.approx(1.5707963267948966)
    assert (integrator, timestep) == ("implicitfast", 0.002)


def test_ur5_steps_cleanly_and_alike(ur5_motion):
    findings, results = ur5_motion
    assert [f for f in findings if f.severity == "error"] == []
    assert set(results["joints"]) == set(UR5_JOINTS)
    for joint, j in results["joints"].items():
        sims = j["poses"]["home"]["simulators"]
        assert set(sims) == {"mujoco", "pybullet", "drake"}, joint
        mj = sims["mujoco"]
        size = abs(mj["target"] - mj["start"])
        assert mj["diverged"] is None and mj["final_error"] < 0.01 * size, joint  # within 1 % after 1 s
        assert mj["overshoot"] < 0.2 and mj["rise_time"] < 1.0, joint
        for other in ("pybullet", "drake"):
            assert sims[other]["rise_time"] == pytest.approx(mj["rise_time"], rel=0.15), (joint, other)
        assert len(mj["trace"]["t"]) == 100
    assert all(s["status"] == "ok" for s in results["simulators"].values())


def stiff_copy(ur5, folder):
    """The UR5 build with wrist_3's drive at kp 1e7, kv 0 and no armature (its MJCF only)."""
    robot = folder / "ur5"
    shutil.copytree(ur5, robot)
    mjcf = robot / "mjcf" / "ur5.xml"
    text = mjcf.read_text(encoding="utf-8")
    text, n = re.subn(r'(<position name="wrist_3_joint_position" joint="wrist_3_joint" )kp="[^"]*" kv="[^"]*"',
                      r'\1kp="1e7" kv="0"', text)
    text, m = re.subn(r'(<joint name="wrist_3_joint"[^>]*armature=")[^"]*"', r'\g<1>0"', text)
    assert n == m == 1
    mjcf.write_text(text, encoding="utf-8")
    return robot


def test_a_stiff_drive_fails_the_check(ur5, tmp_path):
    proc = run_cli("check", stiff_copy(ur5, tmp_path))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    wrist = proc.stdout.split("joint 'wrist_3_joint'")[1]
    assert "error: unstable with integrator implicitfast: w*dt = sqrt(kp/M)*dt = 550 > 2 at pose 'home'" in wrist
    assert "hint: add armature (about 40 kg m^2 brings w*dt to 1) or lower kp to 33 N m/rad" in wrist


def test_json_has_the_motion_results(ur5):
    import json

    proc = run_cli("check", ur5, "--format", "json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    motion = json.loads(proc.stdout)["motion"]["ur5"]
    assert set(motion["simulators"]) == {"mujoco", "pybullet", "drake"} and motion["wall"] > 0
    assert motion["joints"]["elbow_joint"]["poses"]["home"]["simulators"]["drake"]["rise_time"] > 0
    # each stage timed (issue 33): they run at once, so the longest is at most the check's own time
    data = json.loads(proc.stdout)
    stages = {s["stage"]: s["seconds"] for s in data["stages"]}
    assert list(stages) == ["check_urdf", "ign sdf -k", "mujoco", "lints", "equivalence", "consumers",
                            "simulation", "self-collision", "motion"]
    assert all(s > 0 for s in stages.values()) and max(stages.values()) <= data["seconds"]


def test_kinova_gen3_before_its_fix_fails_on_joint_7():
    """Menagerie's Gen3 without armature (integrator implicitfast): joint_7's kv*dt/M is 148 at
    home; its saturated step is explicit again and overshoots; armature about 0.1 fixes it."""
    if not GEN3.is_file():
        pytest.fail(f"test assets not found at {GEN3}")
    proc = run_cli("check", GEN3)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    joint7 = proc.stdout.split("joint 'joint_7'")[1]
    assert ("error: unstable at its force limit: kv*dt/M = 148 > 2 at pose 'home' (kv 50, M 0.000674 kg m^2 incl. "
            "armature 0, dt 0.002 s); integrator implicitfast takes the damping implicitly only within the force "
            "range") in joint7
    assert "hint: add armature (about 0.0993 kg m^2 brings kv*dt/M to 1) or lower kv to 0.337" in joint7
    assert "motion of robot 'gen3' (implicitfast, dt 0.002 s;" in proc.stdout and "pybullet not run" in proc.stdout


def test_kinova_gen3_with_euler_fails_statically(tmp_path):
    """The same model with MuJoCo's default integrator (Euler): kv*dt/M > 2 is an error by itself."""
    folder = tmp_path / "kinova_gen3"
    shutil.copytree(GEN3.parent, folder)
    model = folder / "gen3.xml"
    model.write_text(model.read_text(encoding="utf-8").replace('<option integrator="implicitfast"/>', ""))
    proc = run_cli("check", model)
    assert proc.returncode == 1
    joint7 = proc.stdout.split("joint 'joint_7'")[1]
    assert ("error: unstable with integrator Euler: kv*dt/M = 148 > 2 at pose 'home' (M 0.000674 kg m^2 incl. "
            "armature 0, dt 0.002 s), kv 50: explicit integration diverges") in joint7
    assert "or use integrator implicitfast" in joint7
