"""``robotkit new NAME``: a starter recipe that builds as written (a link, a joint, a mesh in
millimetres, a material, the editor modeline) with its mesh and the JSON Schema beside it."""

from __future__ import annotations

import os
from pathlib import Path

from robotkit.errors import Problem, RobotkitError
from robotkit.mesh.export import stl_bytes
from robotkit.paths import name_problem
from robotkit.recipe.reference import json_schema

RECIPE = """\
# yaml-language-server: $schema=recipe.schema.json
# {name}: a starter robot written by `robotkit new`. Build it into build/{name}/ with
#   robotkit build {name}.yaml
# and check the build with `robotkit check build/{name}`. The editor modeline above points at
# recipe.schema.json (written by `robotkit schema`), so editors complete and check every key.
robot: {name}
density: 1200                  # kg/m^3 (a plastic): inertials are computed from the geometry

metadata:                      # package.xml of the ROS package: put your own name and address
  description: {name}, a robot described with robotkit
  maintainers: [{{name: Your Name, email: you@example.org}}]
  license: MIT

materials:
  grey: {{rgba: [0.6, 0.6, 0.62, 1]}}
  orange: {{rgba: [0.95, 0.45, 0.1, 1]}}

links:
  base:
    visual: {{box: {{size: [0.3, 0.2, 0.05]}}, material: grey}}    # collision: the same box
  arm:
    # a 20 x 20 x 200 mm bar, its foot at the mesh origin; the file is in millimetres
    visual: {{mesh: meshes/{name}/arm.stl, units: mm, material: orange}}

joints:
  shoulder:
    type: revolute
    parent: base
    child: arm
    origin: {{xyz: [0, 0, 0.025]}}   # the top of the base
    axis: [0, 1, 0]
    limit: {{lower: -1.57, upper: 1.57, effort: 5, velocity: 2}}
"""


def arm_mesh():
    """The starter's mesh: a 20 x 20 x 200 mm bar standing on the origin, in millimetres."""
    import trimesh  # heavy: only when the starter is written

    return trimesh.creation.box(extents=(20.0, 20.0, 200.0)).apply_translation((0.0, 0.0, 100.0))


def new(name: str, folder: str = ".") -> list[Path]:
    """Write ``folder/NAME.yaml``, its mesh and ``recipe.schema.json``; refuse to overwrite."""
    why = name_problem(name)
    if why:
        raise RobotkitError(Problem(f"robot name '{name}' {why}"))
    root = Path(folder)
    files = {root / f"{name}.yaml": RECIPE.format(name=name).encode(),
             root / "meshes" / name / "arm.stl": stl_bytes(arm_mesh()),
             root / "recipe.schema.json": json_schema().encode()}
    taken = [p for p in files if p.exists() and not (p.name == "recipe.schema.json" and p.read_bytes() == files[p])]
    if taken:
        raise RobotkitError([Problem("already exists; robotkit new writes no file over another", file=str(p))
                             for p in taken])
    for path, data in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return list(files)


def run(args) -> int:
    for path in new(args.name, args.dir):
        print(os.path.relpath(path))
    print(f"build it: robotkit build {os.path.relpath(os.path.join(args.dir, args.name + '.yaml'))}")
    return 0
