"""Drake (PyPI ``drake``): the URDF and model.sdf parsed into a MultibodyPlant with its
SceneGraph (so collision geometry is loaded too: Drake takes convex meshes as OBJ, VTK or glTF)."""

from __future__ import annotations

import logging

import numpy as np

from robotkit import urdfxml
from robotkit.check.consumers import Missing, Refused, Unreadable, View, listed, with_mesh_paths
from robotkit.emit.urdf import typed_transmissions


def _load(build, path) -> View:
    try:  # optional and heavy: imported when Drake is asked
        from pydrake.multibody.parsing import Parser
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
        from pydrake.multibody.tree import PrismaticJoint, RevoluteJoint
        from pydrake.systems.framework import DiagramBuilder
    except ImportError:
        raise Missing("Drake is not installed (pip install drake)") from None
    logging.getLogger("drake").setLevel(logging.ERROR)  # its warnings (joint friction, sensors) are not failures
    if _unnamed(path):
        raise Refused('the robot has no name (<robot name="">): Drake stops the whole program on it '
                      "(model_instance.cc: condition '!name.empty()' failed)")
    plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
    parser = Parser(plant)
    for pkg, d in build.package_paths.items():  # the folders given first: a foreign URDF's own package
        if not parser.package_map().Contains(pkg):
            parser.package_map().Add(pkg, d)
    if not parser.package_map().Contains(build.name):  # a build folder is its robot's package
        parser.package_map().Add(build.name, str(build.dir))
    try:
        (model,) = parser.AddModels(str(path))
        plant.Finalize()
    except Exception as exc:  # Drake raises RuntimeError with its parser's message
        message = " ".join(str(exc).split())[:400]
        raise (Unreadable if "unsupported extension" in message else Refused)(message) from None
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(model)]
    masses = {b.name(): float(b.default_mass()) for b in bodies}
    frames = [plant.get_frame(i) for i in plant.GetFrameIndices(model)]
    frames = [f for f in frames if not f.name().startswith("__") and f.name() != ""]

    def poses(q: dict[str, float]) -> dict[str, np.ndarray]:
        context = plant.CreateDefaultContext()
        for name, value in q.items():
            for candidate in (name, f"{name}_joint"):  # model.sdf renames joints named like links
                if plant.HasJointNamed(candidate, model):
                    joint = plant.GetJointByName(candidate, model)
                    if isinstance(joint, RevoluteJoint):
                        joint.set_angle(context, value)
                    elif isinstance(joint, PrismaticJoint):
                        joint.set_translation(context, value)
                    break
        return {f.name(): f.CalcPoseInWorld(context).GetAsMatrix4() for f in frames}

    return View(masses, poses)


def _unnamed(path) -> bool:
    """A URDF whose robot name is empty (checked before Drake, which aborts the process on it)."""
    try:
        root = urdfxml.parse_file(path).getroot()
    except urdfxml.MalformedXML:
        return False  # Drake's parser names the problem
    return root.tag == "robot" and not root.get("name")


DRAKE_MESHES = (".obj", ".vtk", ".gltf")


def from_urdf(build) -> View:
    if not build.foreign:
        return _load(build, build.urdf)
    with with_mesh_paths(build, DRAKE_MESHES) as (urdf, converted):
        text, typed = typed_transmissions(urdf.read_text(encoding="utf-8"))
        urdf.write_text(text, encoding="utf-8")
        view = _load(build, urdf)
    if typed:  # ros2_control's form: the robot is fine, Drake needs what a build writes
        view.notes.append(f"reads a <transmission> only with a <type>: {listed(n for n, _ in typed)} given to it "
                          "with the class of their <plugin> here (a build writes it)")
    if converted:  # the robot is fine; Drake needs the conversion a build makes
        view.notes.append(f"reads meshes only as OBJ, VTK or glTF: {listed(converted)} given to it as OBJ here "
                          "(a build converts them)")
    return view


def from_sdf(build) -> View:
    if build.sdf is None:
        raise Missing("no model.sdf")
    return _load(build, build.sdf)
