"""Gazebo, both ways it reads a robot, through libsdformat (`ign sdf -p` prints what it read):
a URDF converted for spawning (fixed joints lumped), and model.sdf from a model:// folder."""

from __future__ import annotations

import re
import shutil

from robotkit.check import programs
from robotkit.check.consumers import Missing, Refused, View
from robotkit import urdfxml
from robotkit.check.kinematics import LIBSDFORMAT_PRECISION, extension_parts, kept_fixed, read_sdf_text


def _parsed(path) -> str:
    if shutil.which("ign") is None:
        raise Missing("`ign` is not installed (apt install ignition-tools libsdformat-dev)")
    proc = programs.libsdformat(path)  # run once for the check (the equivalence stage reads the URDF so too)
    errors = [line for line in (proc.stdout + proc.stderr).splitlines()
              if "Error" in line and "libignition-tools-backward" not in line]
    if proc.returncode != 0 or "<sdf" not in proc.stdout:
        raise Refused(re.sub(r"\x1b\[[0-9;]*m", "", (errors or [f"exit status {proc.returncode}"])[0]).strip())
    if "<link" not in proc.stdout:
        raise Refused("libsdformat's reading has no link at all (an empty model)")
    return proc.stdout  # read_sdf_text copes with its undeclared namespace prefixes


def _view(text: str, source: str, lumped: bool, leave_out=(set(), set()), kept=frozenset()) -> View:
    try:
        model = read_sdf_text(text, source, leave_out)
    except ValueError as exc:  # libsdformat wrote a model it cannot load (a URDF planar joint drops)
        raise Refused(f"libsdformat's reading is not a model it can load: {str(exc).removeprefix(source + ': ')}") \
            from None

    def poses(q: dict[str, float]):
        # model.sdf renames a joint named like a link (robotkit.emit.sdf.joint_names)
        return model.fk({n if n in model.joints else f"{n}_joint": v for n, v in q.items()})

    return View({n: link.mass for n, link in model.links.items() if n != "world"}, poses, lumped=lumped,
                pose_tol=LIBSDFORMAT_PRECISION, kept=kept)


def from_urdf(build) -> View:
    # the links and joints of the URDF's own <gazebo> blocks are Gazebo's additions, not the robot's
    return _view(_parsed(build.urdf), f"URDF {build.urdf} (libsdformat)", lumped=True,
                 leave_out=extension_parts(build.urdf), kept=kept_fixed(urdfxml.parse_file(build.urdf).getroot()))


def from_sdf(build) -> View:
    if build.sdf is None:
        raise Missing("no model.sdf")
    return _view(_parsed(build.sdf), f"SDF {build.sdf} (libsdformat)", lumped=False)
