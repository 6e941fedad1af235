"""A program's own limit is stated as the program's loss, a warning, not an error of the robot
(issue 33): PyBullet holds at most 128 links in one body; a 200-link chain it loads but cannot place."""

from __future__ import annotations

import pytest

from robotkit.check.consumers import Build, consumer_findings

pytestmark = [pytest.mark.consumers]


def chain_urdf(n: int) -> str:
    inertial = ('<inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/>'
                "</inertial>")
    links = [f'<link name="l{i}">{inertial}</link>' for i in range(n)]
    joints = [f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
              '<origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>'
              '<limit lower="-0.01" upper="0.01" effort="1" velocity="1"/></joint>' for i in range(1, n)]
    return '<?xml version="1.0"?>\n<robot name="chain">\n' + "\n".join(links + joints) + "\n</robot>\n"


@pytest.mark.parametrize("links, limited", [(128, False), (200, True)])
def test_pybullets_link_limit_is_a_warning(tmp_path, links, limited):
    urdf = tmp_path / "chain.urdf"
    urdf.write_text(chain_urdf(links), encoding="utf-8")
    findings, summary = consumer_findings(Build("chain", tmp_path, urdf, None, None, foreign=True),
                                          ["PyBullet (URDF)"], configs=2)
    if not limited:  # loaded (what it then sees is test_consumers' matter)
        assert summary["PyBullet (URDF)"]["loaded"] and not any("limit" in f.message for f in findings)
        return
    assert [(f.severity, f.check, f.message, f.hint) for f in findings] == [
        ("warning", "consumer", "PyBullet (URDF): not checked, a limit of the program: loadURDF made a body of 200 "
         "links that PyBullet cannot place (one PyBullet body holds at most 128 links)",
         "a limit of the program, not a defect of the robot")]
    assert summary["PyBullet (URDF)"] == {"loaded": False, "limit": True, "reason": (
        "loadURDF made a body of 200 links that PyBullet cannot place (one PyBullet body holds at most 128 links)")}
