"""``robotkit report PATH [-o DIR] [--build-dir DIR]``: the picture report of a recipe (built first), a build
folder, a URDF (imported and built in a temporary folder for its pictures: meshes of any format,
DAE among them, become what MuJoCo reads) or an SDF/MJCF file."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

from robotkit.check import mjcf_left_out
from robotkit.check.motion.stage import has_actuators, motion_stage
from robotkit.commands.inputs import classify, enclosing_build, package_paths
from robotkit.emit.layout import robot_layout
from robotkit.errors import RobotkitError
from robotkit.picture import report_build_dir, report_model_file, report_urdf

# a build folder's report imports neither the recipe schema (pydantic) nor the build nor the
# importer: those are imported where a recipe is built or a URDF imported

KINDS = ("recipe", "build", "urdf", "sdf", "mjcf")


def run(args) -> int:
    packages = package_paths(args.package_path)
    if packages is None:
        return 2
    start = time.perf_counter()
    page = write_report(args.path, args.out, args.build_dir, packages, dict(args.arg), args.variant)
    print(f"wrote {os.path.relpath(page)} ({time.perf_counter() - start:.2f} s)")
    return 0


def write_report(path: str | os.PathLike, out_dir: str | os.PathLike | None = None, build_out: str = "build",
                 package_paths: dict[str, str] | None = None, args: dict[str, str] | None = None,
                 variant: str | None = None) -> Path:
    """Write ``out_dir/report.html`` and its pictures for PATH; return the page's path.  A recipe
    is built in ``build_out`` first, with its arguments ``args`` (``--arg``); ``variant``: the robot
    of that variant (default: the first)."""
    what = classify(path, KINDS, "a recipe .yaml, .urdf, .sdf or MJCF .xml")
    p = what.path
    if what.kind == "build":
        robot = what.one_robot()
        return report_build_dir(robot.root, Path(out_dir) if out_dir else robot.pictures, str(p),
                                no_pictures=no_pictures(robot), motion=step_responses(robot))
    if what.kind == "recipe":
        from robotkit.pipeline.runner import build
        from robotkit.recipe.load import load_recipe

        loaded = load_recipe(p, args, variant)
        build([p], build_out, report=False, args=args, variant=variant or loaded.variant)
        robot = robot_layout(Path(build_out) / loaded.recipe.robot)
        return report_build_dir(robot.root, Path(out_dir) if out_dir else robot.pictures, str(p),
                                loaded.recipe.measured_mass, no_pictures(robot), step_responses(robot))
    if what.kind == "sdf" and (robot := enclosing_build(p)) is not None:  # a build folder's SDF is drawn
        return report_build_dir(robot.root, Path(out_dir) if out_dir else robot.pictures, str(p))
    out = Path(out_dir) if out_dir else p.parent / f"{p.stem}-report"
    if what.kind == "urdf":
        with tempfile.TemporaryDirectory(prefix="robotkit-report-") as tmp:
            mjcf, notes = _built_mjcf(p, Path(tmp), package_paths or {})
            return report_urdf(p, out, package_paths or {}, mjcf, notes)
    return report_model_file(p, out, what.kind)


def no_pictures(robot) -> str | None:
    """Why a build folder's report has no pictures (they are drawn in MuJoCo, from its MJCF, which
    the build left out at the format's own limit); None when it has them."""
    lost = mjcf_left_out(robot.root)
    return None if lost is None else f"No pictures: {lost} (the pictures are drawn in MuJoCo, from the MJCF)"


def step_responses(robot) -> dict | None:
    """The motion stage's results for a build folder with drives (its step responses are plotted);
    None without drives or when the stage cannot run (``robotkit check`` says why)."""
    if not robot.mjcf.is_file() or "<actuator" not in robot.mjcf.read_text(encoding="utf-8"):
        return None  # robotkit's MJCF has no includes: no actuator element, no drives (MuJoCo not asked)
    if not has_actuators(robot.mjcf):
        return None
    try:
        return motion_stage(robot.mjcf, robot.urdf, {robot.name: robot.root})[1]
    except Exception:  # noqa: BLE001  (the page is drawn without them; check names the problem)
        return None


def _built_mjcf(urdf: Path, tmp: Path, package_paths: dict[str, str]) -> tuple[Path | None, list[str]]:
    """The MJCF of a build of the URDF's import in ``tmp``, or None and the reason."""
    from robotkit.importer import import_file
    from robotkit.pipeline.runner import build

    try:
        result = import_file(str(urdf), tmp / "recipe.yaml", package_paths, {})
        build([tmp / "recipe.yaml"], tmp / "build", report=False)
    except RobotkitError as exc:
        return None, ["No pictures: the URDF could not be built for MuJoCo: " + "; ".join(exc.lines())]
    return robot_layout(tmp / "build" / result.robot).mjcf, []
