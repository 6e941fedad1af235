"""Sensor presets: real devices with their real frames, expanded into links, joints and sensors.

d435: Intel RealSense D435 as realsense2_description defines it (Apache-2.0; the mesh and its
licence are in robotkit/presets/meshes/).  Mounting reference: the bottom tripod screw
(``<prefix>_bottom_screw_frame``); frames camera_link, depth, color, infra1, infra2 and
their optical frames with the upstream nominal offsets.  The mass is the datasheet's 72 g;
the inertia is computed from the aluminium case (the upstream collision box), not copied
(upstream's hand-entered tensor is about 70x too large).
"""

from __future__ import annotations

import math
from pathlib import Path

MESHES = Path(__file__).resolve().parent / "meshes"

# realsense2_description/urdf/_d435.urdf.xacro (nominal extrinsics)
D435 = {
    "width": 0.090, "height": 0.025, "depth": 0.02505,
    "mount_from_center": 0.0149, "glass_to_front": 0.1e-3, "zero_depth_to_glass": 4.2e-3,
    "depth_py": 0.0175,
    "infra1": 0.0, "infra2": -0.050, "color": 0.015,
    "mass": 0.072,
    "color_hfov": 1.211,  # 69.4 degrees (datasheet)
    "depth_hfov": 1.518,  # 87 degrees (datasheet)
}
OPTICAL_RPY = (-math.pi / 2, 0.0, -math.pi / 2)


def d435_frames(prefix: str):
    """(links, joints, sensors) of a D435 as plain tuples, relative to its bottom screw frame.

    links: (name, kind) where kind is "frame" or "body"; joints: (name, parent, child, xyz, rpy);
    sensors: (name, type, link, optical frame, hfov).
    """
    d = D435
    mesh_x = d["mount_from_center"] - d["glass_to_front"] - d["zero_depth_to_glass"]
    n = prefix
    links = [(f"{n}_bottom_screw_frame", "frame"), (f"{n}_link", "body")]
    joints = [(f"{n}_link_joint", f"{n}_bottom_screw_frame", f"{n}_link", (mesh_x, d["depth_py"], d["height"] / 2),
               (0.0, 0.0, 0.0))]
    for stream, offset in (("depth", 0.0), ("infra1", d["infra1"]), ("infra2", d["infra2"]), ("color", d["color"])):
        links += [(f"{n}_{stream}_frame", "frame"), (f"{n}_{stream}_optical_frame", "frame")]
        joints += [(f"{n}_{stream}_joint", f"{n}_link", f"{n}_{stream}_frame", (0.0, offset, 0.0), (0.0, 0.0, 0.0)),
                   (f"{n}_{stream}_optical_joint", f"{n}_{stream}_frame", f"{n}_{stream}_optical_frame",
                    (0.0, 0.0, 0.0), OPTICAL_RPY)]
    sensors = [(f"{n}_color", "camera", f"{n}_color_frame", f"{n}_color_optical_frame", d["color_hfov"]),
               (f"{n}_depth", "depth", f"{n}_depth_frame", f"{n}_depth_optical_frame", d["depth_hfov"])]
    return links, joints, sensors


def d435_body():
    """Visual (mesh file, pose) and collision box (size, pose) of the camera link."""
    d = D435
    visual = (str(MESHES / "d435.dae"), (d["zero_depth_to_glass"] + d["glass_to_front"], -d["depth_py"], 0.0),
              (math.pi / 2, 0.0, math.pi / 2))
    box = ((d["depth"], d["width"], d["height"]), (0.0, -d["depth_py"], 0.0))
    return visual, box
