"""``robotkit world MAP.yaml``: a ROS occupancy map into a Gazebo world and a MuJoCo scene."""

from __future__ import annotations

import os
import sys

from robotkit.world import build_world


def run(args) -> int:
    if not args.height > 0:
        print("robotkit: error: --height must be > 0", file=sys.stderr)
        return 2
    paths = build_world(args.map, args.out, name=args.name, height=args.height,
                        unknown_as_wall=args.unknown_as_wall)
    for p in paths:
        print(os.path.relpath(p))
    return 0
