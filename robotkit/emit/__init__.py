"""Emitters: a finalized Robot -> the text of one output file.

Each emitter is registered by name; the doit tasks and the tests loop over
this registry.  An emitter reads only the resolved model, never the recipe.
"""

from __future__ import annotations


def _urdf(robot, **_):
    from robotkit.emit.urdf import render_urdf

    return render_urdf(robot)


def _model_config(robot, sdf: str, **_):
    from robotkit.emit.gazebo import render_model_config

    return render_model_config(robot, sdf)


def _package_xml(robot, **_):
    from robotkit.emit.ros import render_package_xml

    return render_package_xml(robot)


def _cmakelists(robot, **_):
    from robotkit.emit.ros import render_cmakelists

    return render_cmakelists(robot)


def _env_hook(robot, **_):
    from robotkit.emit.ros import render_env_hook

    return render_env_hook(robot)


def _display_launch(robot, **_):
    from robotkit.emit.ros import render_display_launch

    return render_display_launch(robot)


def _gazebo_launch(robot, **_):
    from robotkit.emit.ros import render_gazebo_launch

    return render_gazebo_launch(robot)


def _rviz(robot, facts=None, **_):
    from robotkit.emit.ros import render_rviz

    return render_rviz(robot, facts or {})


def _sdf(robot, **_):
    from robotkit.emit.sdf import render_sdf

    return render_sdf(robot)


def _mjcf(robot, meshes=None, **_):
    from robotkit.emit.mjcf import render_mjcf

    return render_mjcf(robot, meshes if isinstance(meshes, str) else None)


def _mjcf_scene(robot, **_):
    from robotkit.emit.mjcf import render_scene

    return render_scene(robot)


def _report(robot, facts=None, **_):
    import json

    from robotkit.emit.report import report

    return json.dumps(report(robot, facts or {}), indent=1, sort_keys=True) + "\n"


def _controllers(robot, raw=True, **_):
    from robotkit.emit.controllers import render_controllers

    return render_controllers(robot)


def _xacro(robot, **_):
    from robotkit.emit.xacro_macro import render_xacro_macro

    return render_xacro_macro(robot)


EMITTERS = {
    "urdf": _urdf,
    "sdf": _sdf,
    "mjcf": _mjcf,
    "mjcf-scene": _mjcf_scene,
    "model.config": _model_config,
    "package.xml": _package_xml,
    "CMakeLists.txt": _cmakelists,
    "env-hook": _env_hook,
    "display-launch": _display_launch,
    "gazebo-launch": _gazebo_launch,
    "rviz": _rviz,
    "report": _report,
    "controllers": _controllers,
    "xacro": _xacro,
}

# outputs that programs load as robots: not written when a consumer would refuse the robot
CONSUMED = ("urdf", "sdf", "mjcf")

# the templates each emitter renders (their edits must rebuild the output)
TEMPLATES = {
    "urdf": ["urdf/robot.urdf.j2", "sensors/sdf.j2", "sensors/classic.j2"],
    "sdf": ["sdf/model.sdf.j2", "sensors/sdf.j2"],
    "mjcf": ["mjcf/robot.xml.j2"],
    "mjcf-scene": ["mjcf/scene.xml.j2"],
    "model.config": ["gazebo/model.config.j2"],
    "package.xml": ["ros/package.xml.j2"],
    "CMakeLists.txt": ["ros/CMakeLists.txt.j2"],
    "env-hook": ["ros/env-hook.sh.in.j2", "ros/env-hook.dsv.in.j2"],
    "display-launch": ["ros/display.launch.j2", "ros/display.launch.py.j2"],
    "gazebo-launch": ["ros/gazebo.launch.j2", "ros/gazebo.launch.py.j2"],
    "rviz": [],
    "report": [],
    "controllers": [],
    "xacro": ["urdf/robot.urdf.xacro.j2", "urdf/robot.urdf.j2", "sensors/sdf.j2", "sensors/classic.j2"],
}
