"""Robot -> Gazebo model.config (the ROS package files are robotkit.emit.ros), and the recipe's
verbatim <gazebo> blocks as model.sdf pieces (:func:`carry`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from robotkit.emit import layout
from robotkit.emit.env import render
from robotkit.emit.formats import Format
from robotkit.model.robot import Robot


def render_model_config(robot: Robot, sdf: str) -> str:
    return render("gazebo/model.config.j2", robot=robot, md=robot.metadata, sdf=sdf)


FORMATS = [Format("model.config", render_model_config, layout.MODEL_CONFIG, ("gazebo/model.config.j2",),
                  reads="metadata", options={"sdf": layout.SDF}, needs=("sdf",))]


# ------------------------------------------------------ verbatim <gazebo> blocks -> model.sdf
#
# What libsdformat's URDF conversion does with a URDF's <gazebo> extensions (parser_urdf.cc),
# done for the recipe's urdf_extras: a block without ``reference`` gives its elements to the
# model; one that names a link gives its surface and material tags to the link's collisions and
# visuals and its other elements (sensors, plugins...) to the link; one that names a joint gives
# its elements to the joint.  A link that model.sdf writes as a <frame> (massless, fixed) is
# carried by a link (robotkit.emit.sensors.host_of), as libsdformat lumps it: its sensors go
# there with their pose relative to the frame, and a plugin's <bodyName> naming it names the
# carrier, with the frame's pose as <xyzOffset>/<rpyOffset> (the offsets gazebo_ros reads).

SURFACE = {"mu1": "mu", "mu2": "mu2", "fdir1": "fdir1", "kp": "kp", "kd": "kd", "maxVel": "max_vel",
           "minDepth": "min_depth"}
"""URDF <gazebo reference="link"> surface tags -> SDF collision <surface> element names."""
LINK_TAGS = {"gravity": "gravity", "selfCollide": "self_collide", "self_collide": "self_collide",
             "kinematic": "kinematic"}
"""URDF link tags -> SDF link elements (turnGravityOff and dampingFactor: see :func:`_link_tag`)."""
COLLISION = {"maxContacts": "max_contacts", "laserRetro": "laser_retro"}
"""URDF link tags -> elements of each of the link's SDF collisions."""
JOINT_PHYSICS = {"provideFeedback": ("provide_feedback",), "implicitSpringDamper": ("ode", "implicit_spring_damper"),
                 "cfmDamping": ("ode", "implicit_spring_damper"), "stopCfm": ("ode", "limit", "cfm"),
                 "stopErp": ("ode", "limit", "erp")}
"""URDF joint tags -> paths below the SDF joint's <physics>."""
JOINT_LOST = {"springStiffness", "springReference", "fudgeFactor"}
"""URDF joint tags model.sdf does not carry (the recipe's joint dynamics are its own)."""
MODEL_OWN = {"self_collide"}
"""Model elements robotkit writes itself when the recipe sets them: a block's copy would be a duplicate."""


@dataclass
class Carried:
    """The SDF pieces of a robot's verbatim <gazebo> blocks (:func:`carry`).

    ``model``/``links``/``joints``: XML elements (text, unindented) for the model, each SDF link
    and each joint (by recipe name); ``surfaces``: per recipe link, the collision surface values
    (SDF names); ``collision``: per recipe link, extra collision elements; ``materials``: per
    recipe link, the Gazebo material script of its visuals; ``losses``: what cannot be carried."""
    model: list[str] = field(default_factory=list)
    links: dict[str, list[str]] = field(default_factory=dict)
    joints: dict[str, list[str]] = field(default_factory=dict)
    surfaces: dict[str, dict[str, str]] = field(default_factory=dict)
    collision: dict[str, list[str]] = field(default_factory=dict)
    materials: dict[str, str] = field(default_factory=dict)
    losses: list[str] = field(default_factory=list)
    named: set[tuple[str, str, str]] = field(default_factory=set)
    """(link, tag, name) of the named elements carried into a link so far."""


def carry(robot: Robot, markup: bool = False) -> Carried:
    """The recipe's <gazebo> urdf_extras as SDF pieces; other extras (transmissions...) are URDF
    only and listed as a loss.  ``markup``: the XML pieces as ``markupsafe.Markup`` (for the
    autoescaping templates)."""
    import xml.etree.ElementTree as ET

    out = _carry(robot, ET)
    if markup:
        from markupsafe import Markup

        out.model = [Markup(x) for x in out.model]
        for d in (out.links, out.joints, out.collision):
            for k, v in d.items():
                d[k] = [Markup(x) for x in v]
    return out


def _carry(robot: Robot, ET) -> Carried:
    """:func:`carry`, block by block and element by element."""
    out = Carried()
    links = {link.name for link in robot.links}
    joints = {j.name for j in robot.joints}
    frames = robot.frame_links()
    other, physics = [], {}
    for text in robot.urdf_extras:
        try:
            block = ET.fromstring(text)
        except ET.ParseError:
            other.append(text)
            continue
        if block.tag != "gazebo":
            other.append(text)
            continue
        ref = block.get("reference")
        for elem in block:
            if not ref:
                _to_model(out, elem, robot, frames)
            elif ref in links:
                _to_link(out, ref, elem, robot, frames)
            elif ref in joints:
                _to_joint(out, ref, elem, robot, frames, physics.setdefault(ref, ET.Element("physics")))
            else:
                out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: '
                                  f"'{ref}' names no link or joint of the robot")
    for ref, elem in physics.items():
        if len(elem):
            out.joints.setdefault(ref, []).insert(0, _text(elem))
    if other:
        heads = [_head(x) for x in other]
        out.losses.append(f"{len(other)} urdf_extras element{'s' * (len(other) != 1)} that "
                          f"{'are not <gazebo> blocks' if len(other) != 1 else 'is not a <gazebo> block'} "
                          f"{'are' if len(other) != 1 else 'is'} in the URDF only, not in model.sdf: "
                          f"{', '.join(heads[:5])}{', ...' if len(heads) > 5 else ''}")
    return out


def _to_model(out: Carried, elem, robot: Robot, frames: set[str]) -> None:
    if elem.tag not in MODEL_CHILDREN:
        out.losses.append(f"<gazebo>: <{elem.tag}> not in model.sdf: an SDF model has no <{elem.tag}>")
        return
    if elem.tag in MODEL_OWN and (robot.self_collide is not None or robot.collision_matrix is not None):
        out.losses.append(f"<gazebo>: <{elem.tag}> not in model.sdf: its self-collision comes from the recipe "
                          "(self_collide, the self-collision matrix)")
        return
    out.model.append(_text(_rebodied(elem, robot, frames)))


def _to_link(out: Carried, ref: str, elem, robot: Robot, frames: set[str]) -> None:
    """One element of a <gazebo reference="link"> block into the SDF link that carries ``ref``."""
    from robotkit.emit.sensors import host_of

    value = _value(elem)
    if elem.tag in ("visual", "collision"):  # libsdformat merges one only into a visual/collision of its name
        out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: the SDF {elem.tag}s are '
                          "the recipe's, named by robotkit")
    elif elem.tag in SURFACE:
        out.surfaces.setdefault(ref, {})[SURFACE[elem.tag]] = value
    elif elem.tag in COLLISION:
        out.collision.setdefault(ref, []).append(_leaf(COLLISION[elem.tag], value))
    elif elem.tag == "material" and len(elem) == 0:
        out.materials[ref] = value
    elif elem.tag in LINK_TAGS or elem.tag in ("turnGravityOff", "dampingFactor"):
        if ref in frames:
            out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: '
                              f"'{ref}' is a frame there (massless, fixed), carried by '{host_of(robot, ref)[0]}'")
        else:
            out.links.setdefault(ref, []).append(_link_tag(elem.tag, value))
    elif elem.tag not in LINK_CHILDREN:  # libsdformat copies it with a warning; Drake refuses the file
        out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: an SDF link has no '
                          f"<{elem.tag}>")
    else:
        elem = _rebodied(elem, robot, frames)
        out.losses += [f'<gazebo reference="{ref}">: {x}' for x in _outdated(elem)]
        host = ref
        if ref in frames:
            host = host_of(robot, ref)[0]
            if elem.tag == "sensor":
                _pose_relative_to(elem, ref)
        key = (host, elem.tag, elem.get("name"))
        if key[2] and key in out.named:  # TALOS' two sensors 'rgbd_frame_sensor': libsdformat refuses the file
            out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag} name="{key[2]}"> not in model.sdf: link '
                              f"'{host}' has a <{elem.tag}> of that name already (SDF needs them apart)")
            return
        out.named.add(key)
        out.links.setdefault(host, []).append(_text(elem))


def _to_joint(out: Carried, ref: str, elem, robot: Robot, frames: set[str], physics) -> None:
    """One element of a <gazebo reference="joint"> block into the SDF joint (``physics``: its
    <physics> element, filled here)."""
    import xml.etree.ElementTree as ET

    child = next(j.child for j in robot.joints if j.name == ref)
    unwritten = child in frames or child == robot.anchor()
    if unwritten or elem.tag in JOINT_LOST:
        why = (f"the joint is not there (it fixes a frame to '{child}' or '{child}' to a link)" if unwritten else
               "model.sdf writes the recipe's joint dynamics")
        out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: {why}')
    elif elem.tag not in JOINT_PHYSICS and elem.tag not in JOINT_CHILDREN:  # Drake refuses it (the PR2's stopKd)
        out.losses.append(f'<gazebo reference="{ref}">: <{elem.tag}> not in model.sdf: an SDF joint has no '
                          f"<{elem.tag}>")
    elif elem.tag in JOINT_PHYSICS:
        node = physics
        for tag in JOINT_PHYSICS[elem.tag]:
            node = node.find(tag) if node.find(tag) is not None else ET.SubElement(node, tag)
        node.text = _value(elem)
    else:
        out.joints.setdefault(ref, []).append(_text(_rebodied(elem, robot, frames)))


def _pose_relative_to(sensor, frame: str) -> None:
    """A sensor of a frame link, in the link that carries it: its pose relative to the frame."""
    import xml.etree.ElementTree as ET

    pose = sensor.find("pose")
    if pose is None:
        pose = ET.Element("pose")
        pose.text = "0 0 0 0 0 0"
        sensor.insert(0, pose)
    if pose.get("relative_to") is None:
        pose.set("relative_to", frame)


def _rebodied(elem, robot: Robot, frames: set[str]):
    """A copy of ``elem`` whose plugins' <bodyName> naming a frame link names the link that
    carries it, with the frame's pose in it as <xyzOffset> and <rpyOffset> (as libsdformat does
    for a lumped link; unless the plugin gives offsets of its own)."""
    import copy
    import xml.etree.ElementTree as ET

    from robotkit.emit.env import vec
    from robotkit.emit.sensors import host_of

    elem = copy.deepcopy(elem)
    for plugin in elem.iter("plugin"):
        body = plugin.find("bodyName")
        if body is None or (body.text or "").strip() not in frames:
            continue
        host, pose = host_of(robot, body.text.strip())
        body.text = host
        if plugin.find("xyzOffset") is None and plugin.find("rpyOffset") is None:
            for tag, v in (("xyzOffset", pose.xyz), ("rpyOffset", pose.rpy)):
                ET.SubElement(plugin, tag).text = vec(v)
    return elem


LINK_CHILDREN = {"sensor", "projector", "audio_sink", "audio_source", "battery", "light", "particle_emitter",
                 "enable_wind", "must_be_base_link"}
"""What a <gazebo reference="link"> block may add to an SDF 1.9 link as it is (libsdformat's
link.sdf; the link tags of LINK_TAGS are translated)."""
JOINT_CHILDREN = {"sensor", "gearbox_ratio", "gearbox_reference_body", "thread_pitch", "screw_thread_pitch"}
"""What a <gazebo reference="joint"> block may add to an SDF 1.9 joint as it is (libsdformat's
joint.sdf; the joint tags of JOINT_PHYSICS are translated, Gazebo classic's stopKp/stopKd are not
SDF)."""
MODEL_CHILDREN = {"static", "self_collide", "allow_auto_disable", "enable_wind", "plugin", "gripper", "frame",
                  "include", "model"}
"""What a <gazebo> block without reference may add to an SDF 1.9 model (libsdformat's model.sdf)."""
OUTDATED = {("imu", "noise"): "SDF 1.5 moved an IMU's noise into <angular_velocity> and <linear_acceleration>"}
"""(parent, child) elements of Gazebo classic's old sensor syntax that today's SDF does not define
(libsdformat only warns, Drake refuses the file): dropped from a carried sensor, and listed."""


def _outdated(elem) -> list[str]:
    """Remove the OUTDATED elements below ``elem`` (a carried <sensor>); what was removed."""
    said = []
    for (parent, child), why in OUTDATED.items():
        for node in list(elem.iter(parent)):
            for old in node.findall(child):
                node.remove(old)
                said.append(f"<{elem.tag} name=\"{elem.get('name', '')}\">: <{parent}><{child}> not in model.sdf: {why}")
    return said


def _value(elem) -> str:
    """A URDF <gazebo> tag's value: its ``value`` attribute when it has one (``<kp value="1e6"/>``),
    else its text (libsdformat's GetKeyValueAsString)."""
    return (elem.get("value") if elem.get("value") is not None else elem.text or "").strip()


def _link_tag(tag: str, value: str) -> str:
    """A URDF link tag as its SDF link element (libsdformat's translation)."""
    import xml.etree.ElementTree as ET

    if tag == "turnGravityOff":
        return _leaf("gravity", "false" if value.lower() in ("true", "1") else "true")
    if tag == "dampingFactor":
        decay = ET.Element("velocity_decay")
        ET.SubElement(decay, "linear").text = value
        ET.SubElement(decay, "angular").text = value
        return _text(decay)
    return _leaf(LINK_TAGS[tag], value)


def _leaf(tag: str, value: str) -> str:
    import xml.etree.ElementTree as ET

    elem = ET.Element(tag)
    elem.text = value
    return _text(elem)


def _text(elem) -> str:
    import xml.etree.ElementTree as ET

    elem.tail = None
    ET.indent(elem, space="  ")
    return ET.tostring(elem, encoding="unicode")


def _head(text: str) -> str:
    import re

    m = re.match(r"\s*(<[^>]*>)", text)
    return m.group(1) if m else text[:40]


def kept_fixed_joints(robot: Robot) -> list[str]:
    """The fixed joints the URDF asks libsdformat to keep (``<preserveFixedJoint>``): those whose
    child link a ``<joint>`` of a model-level <gazebo> block names as its parent or child (the
    PR2's parallel-gripper joints name ``r_gripper_palm_link``).  Its URDF conversion would lump
    the link into its parent and then refuse the block's joint, whose link and pose frame it no
    longer has."""
    import xml.etree.ElementTree as ET

    named = set()
    for text in robot.urdf_extras:
        try:
            block = ET.fromstring(text)
        except ET.ParseError:
            continue
        if block.tag == "gazebo" and not block.get("reference"):
            named |= {(el.text or "").strip() for j in block.iter("joint") for el in j if el.tag in ("parent", "child")}
    return [j.name for j in robot.joints if j.type == "fixed" and j.child in named and j.parent != "world"]
