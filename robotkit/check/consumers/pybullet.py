"""PyBullet (PyPI ``pybullet``, DIRECT mode): the URDF with the file's inertia
(``URDF_USE_INERTIA_FROM_FILE``); a link without ``<inertial>`` gets 1 kg there."""

from __future__ import annotations


import numpy as np

from robotkit import urdfxml
from robotkit.ioutil import quiet
from robotkit.check.consumers import Limit, Missing, Refused, View, listed, with_mesh_paths


MAX_LINKS = 128
PRECISION = 1e-5
"""PyBullet's wheels compute kinematics in single precision: a six-joint chain at joint values up to
7 rad loses 5.5e-7 of its reach in float32 (measured, numpy), PyBullet's frames through each link's
inertial frame more (ABB IRB 140's link_5 1.02e-6 off at 1.01 m): ten times the chain's."""




DEFAULT_MASS = 1.0  # what PyBullet gives a link without <inertial>


def _without_inertial(urdf) -> set[str]:
    root = urdfxml.parse_file(urdf).getroot()
    return {el.get("name") for el in root.iter("link") if el.find("inertial") is None}


def _T(pos, orn) -> np.ndarray:
    import pybullet as p

    T = np.eye(4)
    T[:3, :3] = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
    T[:3, 3] = pos
    return T


def from_urdf(build) -> View:
    try:  # optional: imported when PyBullet is asked (quietly: it prints its build banner)
        with quiet():
            import pybullet as p
    except ImportError:
        raise Missing("PyBullet is not installed (pip install pybullet)") from None
    with quiet(), with_mesh_paths(build) as (urdf, _):  # PyBullet knows no ROS packages
        client = p.connect(p.DIRECT)
        try:
            # loaded free, so the base keeps its mass from the file (a fixed base is reported massless)
            body = p.loadURDF(str(urdf), useFixedBase=False,
                              flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
        except p.error as exc:
            p.disconnect(client)
            raise Refused(f"loadURDF failed: {exc}") from None
    n = p.getNumJoints(body, physicsClientId=client)
    try:
        p.getBasePositionAndOrientation(body, physicsClientId=client)
    except p.error:  # measured with 3.2.7: a body of 128 links works, one of 129 does not
        p.disconnect(client)
        raise Limit(f"loadURDF made a body of {n + 1} links that PyBullet cannot place "
                      f"(one PyBullet body holds at most {MAX_LINKS} links)") from None
    base = p.getBodyInfo(body, physicsClientId=client)[0].decode()
    info = [p.getJointInfo(body, i, physicsClientId=client) for i in range(n)]
    masses = {base: p.getDynamicsInfo(body, -1, physicsClientId=client)[0]}
    masses.update({info[i][12].decode(): p.getDynamicsInfo(body, i, physicsClientId=client)[0] for i in range(n)})
    local = p.getDynamicsInfo(body, -1, physicsClientId=client)
    notes = []
    defaulted = sorted(n for n in _without_inertial(build.urdf) if masses.get(n) == DEFAULT_MASS)
    if defaulted:  # URDF's frames (no <inertial>, massless to urdfdom): PyBullet's own default, not the robot's
        notes.append(f"gives each link without <inertial> {DEFAULT_MASS:g} kg: {listed(defaulted)} "
                     f"({len(defaulted) * DEFAULT_MASS:g} kg more than the description; a build writes a token "
                     "mass that PyBullet keeps)")
        masses.update({n: 0.0 for n in defaulted})

    def poses(q: dict[str, float]) -> dict[str, np.ndarray]:
        for i in range(n):
            name = info[i][1].decode()
            if name in q:
                p.resetJointState(body, i, q[name], physicsClientId=client)
        com = _T(*p.getBasePositionAndOrientation(body, physicsClientId=client))
        out = {base: com @ np.linalg.inv(_T(local[3], local[4]))}
        for i in range(n):
            s = p.getLinkState(body, i, computeForwardKinematics=1, physicsClientId=client)
            out[info[i][12].decode()] = _T(s[4], s[5])
        return out

    return View(masses, poses, pose_tol=PRECISION, notes=notes)
