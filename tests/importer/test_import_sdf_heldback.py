"""robotkit import on the kinds of Gazebo model the shared set does not hold (the reviewers keep
such models back: issue 30): nested models with their own name clashes, loops closed by joints
that cannot move, names with '/' in them...  Each case a small synthetic SDF, its import checked
against a known answer and verified through libsdformat."""

from __future__ import annotations

import shutil

import pytest
import yaml

from robotkit.commands.import_ import build_sdf
from robotkit.importer import import_sdf

pytestmark = pytest.mark.skipif(shutil.which("ign") is None, reason="needs libsdformat's ign sdf")

TETRAHEDRON = "solid t\n" + "".join(
    f"facet normal 0 0 0\nouter loop\n{''.join(f'vertex {v}' + chr(10) for v in face)}endloop\nendfacet\n"
    for face in (("0 0 0", "0 0.1 0", "0.1 0 0"), ("0 0 0", "0.1 0 0", "0 0 0.1"), ("0 0 0", "0 0 0.1", "0 0.1 0"),
                 ("0.1 0 0", "0 0.1 0", "0 0 0.1"))) + "endsolid t\n"
"""A closed tetrahedron, an ASCII STL."""
INERTIAL = "<inertial><mass>{m}</mass><inertia><ixx>{i}</ixx><iyy>{i}</iyy><izz>{i}</izz></inertia></inertial>"


def _imported(tmp_path, text: str, name: str = "m"):
    """The import of SDF ``text`` written to ``tmp_path/name/model.sdf`` (its model path
    ``tmp_path``): (result, recipe, the file's path)."""
    (tmp_path / name).mkdir(exist_ok=True)
    (tmp_path / name / "model.sdf").write_text(text)
    result = import_sdf(tmp_path / name / "model.sdf", tmp_path / "out" / f"{name}.yaml", build=build_sdf)
    return result, yaml.safe_load(result.recipe_path.read_text()), str(tmp_path / name / "model.sdf")


def _joints(recipe: dict) -> dict:
    base = recipe.get("defaults", {}).get("joint", {})
    return {name: {**base, **j} for name, j in recipe["joints"].items()}


RIG = f"""<?xml version="1.0"?>
<sdf version="1.6">
  <model name="rig">
    <link name="rack">
      <pose>0 0 0.2 0 0 0</pose>
      {INERTIAL.format(m=1, i=0.01)}
    </link>
    <model name="base">
      <link name="body">
        {INERTIAL.format(m=2, i=0.02)}
      </link>
      <link name="wheel">
        <pose>0 0.1 0 0 0 0</pose>
        {INERTIAL.format(m=0.5, i=0.001)}
      </link>
      <joint name="wheel" type="revolute">
        <parent>body</parent><child>wheel</child>
        <axis><xyz>0 1 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis>
      </joint>
    </model>
    <model name="cam">
      <pose>0.1 0 0.3 0 0 0</pose>
      <link name="link">
        {INERTIAL.format(m=0.1, i=0.001)}
      </link>
    </model>
    <link name="rig/imu_link">
      <pose>0 0 0.25 0 0 0</pose>
      {INERTIAL.format(m=0.1, i=0.001)}
    </link>
    <joint name="rig/imu_joint" type="revolute">
      <parent>rack</parent><child>rig/imu_link</child>
      <axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0</upper></limit></axis>
    </joint>
    <joint name="base_rack" type="fixed"><parent>base::body</parent><child>rack</child></joint>
    <joint name="cam_rack" type="revolute">
      <parent>cam::link</parent><child>rack</child>
      <axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0</upper></limit></axis>
    </joint>
  </model>
</sdf>
"""


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    return _imported(tmp_path_factory.mktemp("rig"), RIG, "rig")


def test_nested_models_joint_named_like_its_link_is_renamed(rig):
    """turtlebot includes create, whose joint 'left_wheel' moves its link 'left_wheel': one frame
    name for two frames, which made the import refuse the model ('the poses relative to
    'create::left_wheel' make a cycle')."""
    result, recipe, sdf = rig
    assert result.verdict.ok, result.verdict.lines()
    assert f"{sdf}:16: joint 'base/wheel': all: renamed 'base/wheel_joint' (a link has its name: libsdformat " \
           "refuses the pair)" in result.ledger
    wheel = _joints(recipe)["base/wheel_joint"]
    assert (wheel["type"], wheel["parent"], wheel["child"], wheel["axis"]) == ("revolute", "base/body", "base/wheel",
                                                                             [0, 1, 0])


def test_joint_that_cannot_move_closing_a_loop_is_turned_round(rig):
    """turtlebot fixes the included kinect to its rack, which the included create already carries:
    the joint, dropped as a loop, left the kinect a free body (a floating joint MuJoCo refuses
    below the top).  A joint that cannot move is the same written from child to parent."""
    result, recipe, sdf = rig
    assert f"{sdf}:36: joint 'cam_rack' (revolute): all: written from 'rack' to 'cam/link' (its child already " \
           "has joint 'base_rack'; a joint that cannot move is the same either way)" in result.ledger
    joints = _joints(recipe)
    cam = joints["cam_rack"]
    assert (cam["type"], cam["parent"], cam["child"]) == ("fixed", "rack", "cam/link")
    assert cam["origin"] == {"xyz": pytest.approx([0.1, 0, 0.1], abs=1e-15)}
    assert [n for n, j in joints.items() if j["type"] == "floating"] == []
    assert not any("second free body" in line for line in result.ledger)


def test_names_with_a_slash_are_found_in_the_file(rig):
    """iris names its links 'iris/imu_link': the ledger gives their line, not the file alone."""
    result, recipe, sdf = rig
    assert f"{sdf}:31: joint 'rig/imu_joint' (revolute): all: a fixed joint: its limits are equal (it cannot " \
           "move)" in result.ledger
    assert _joints(recipe)["rig/imu_joint"]["child"] == "rig/imu_link"


def _stiff_link(name: str, z: float) -> str:
    return f"""    <link name="{name}">
      <pose>0 0 {z} 0 0 0</pose>
      {INERTIAL.format(m=1, i=0.01)}
      <collision name="c">
        <geometry><box><size>0.1 0.1 0.1</size></box></geometry>
        <surface><contact><ode><kp>10000000000000.000000</kp><kd>100000000000.000000</kd><max_vel>-1</max_vel>
        </ode></contact></surface>
      </collision>
    </link>
"""


STIFF = f"""<?xml version="1.0"?>
<sdf version="1.5">
  <model name="stiff">
{_stiff_link("a", 0)}{_stiff_link("b", 0.2)}{_stiff_link("c", 0.4)}    <joint name="ab" type="revolute"><parent>a</parent><child>b</child>
      <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis>
      <physics><ode><implicit_spring_damper>1</implicit_spring_damper></ode></physics></joint>
    <joint name="bc" type="revolute"><parent>b</parent><child>c</child>
      <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis>
      <physics><ode><implicit_spring_damper>1</implicit_spring_damper></ode></physics></joint>
  </model>
</sdf>
"""


def test_contact_stiffness_above_the_recipes_largest_is_written_as_that(tmp_path):
    """youbot's kp of 1e13 (SDF's default is 1e12) made the recipe invalid: the import refused the
    model.  Written 1e12, stated once for every link that has it; what the links (joints) drop
    alike is one ledger line too (youbot: 21 lines of the same; cessna: 10 joints' <physics>)."""
    result, recipe, sdf = _imported(tmp_path, STIFF)
    assert result.verdict.ok, result.verdict.lines()
    base = recipe.get("defaults", {}).get("link", {})
    assert {name: {**base, **link}["contact"] for name, link in recipe["links"].items()} == {
        name: {"kp": 1e12, "kd": 1e11} for name in "abc"}
    assert result.ledger == [
        f"{sdf}:4: contact kp 1e+13 of links 'a', 'b', 'c': all: approximated: written 1e+12, the largest the "
        "recipe takes",
        f"{sdf}:4: links 'a', 'b', 'c': all: dropped (no place in the recipe): its collisions' <max_vel> (the "
        "recipe's contact is a link's mu1, mu2, kp, kd)",
        f"{sdf}:31: joints 'ab', 'bc': all: dropped (no place in the recipe): <physics>"]


FRAMES = """<?xml version="1.0"?>
<sdf version="1.8">
  <model name="frames">
    <link name="base"><pose>0 0 1 0 0 0</pose><inertial><mass>1</mass></inertial></link>
    <link name="arm"><pose>0 0 2 0 0 0</pose><inertial><mass>1</mass></inertial></link>
    <frame name="mount" attached_to="arm"><pose>0.5 0 0 0 0 0</pose></frame>
    <joint name="hinge" type="revolute">
      <pose>0 0.1 0 0 0 0</pose>
      <parent>base</parent><child>mount</child>
      <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis>
    </joint>
    <frame name="on_joint" attached_to="hinge"><pose>0 0 0.3 0 0 0</pose></frame>
    <frame name="on_frame" attached_to="on_joint"/>
    <frame name="on_model"><pose>0 0 0.2 0 0 0</pose></frame>
    <model name="tool">
      <pose>0 0 3 0 0 0</pose>
      <link name="tip"><inertial><mass>1</mass></inertial></link>
    </model>
    <joint name="tool_joint" type="fixed"><parent>arm</parent><child>tool</child></joint>
    <joint name="back" type="fixed"><parent>tool::tip</parent><child>base</child></joint>
  </model>
</sdf>
"""


def test_sdf_1_7_frames_as_joint_ends_and_frames_on_joints_frames_and_models(tmp_path):
    """SDF 1.7's frame semantics (libsdformat's own test models: joint_child_frame,
    model_frame_attached_to_joint, joint_nested_parent_child): a joint's child may be a frame or a
    nested model, a frame may be attached to a joint, a frame or (no attached_to) its model; each
    is the link it is attached to.  They were dropped, leaving free bodies.  A joint closing a
    loop through other joints is dropped (it made the recipe a cycle: exit 2), and the
    verification follows the joints the recipe keeps."""
    result, recipe, sdf = _imported(tmp_path, FRAMES)
    assert result.verdict.ok and result.verdict.configurations == 11, result.verdict.lines()
    assert result.ledger == [f"{sdf}:20: joint 'back' (fixed): all: dropped: it closes a loop (link 'tool/tip' "
                             "already hangs from link 'base')"]
    joints = _joints(recipe)
    ends = {name: (j["parent"], j["child"], j.get("origin", {}).get("xyz")) for name, j in joints.items()}
    assert ends == {"hinge": ("base", "arm", [0.5, 0.1, 1]), "tool_joint": ("arm", "tool/tip", [-0.5, -0.1, 1]),
                    "mount_frame": ("arm", "mount", [0, -0.1, 0]), "on_joint_frame": ("arm", "on_joint", pytest.approx(
                        [0, 0, 0.3], abs=1e-15)), "on_frame_frame": ("arm", "on_frame", pytest.approx(
                            [0, 0, 0.3], abs=1e-15)), "on_model_frame": ("base", "on_model", [0, 0, -0.8])}
    assert recipe.get("base") == "free" and "floating" not in {j["type"] for j in joints.values()}


def test_model_settings_at_sdfs_defaults_are_no_loss_and_the_others_have_their_line(tmp_path):
    """demo_joint_stiffness sets <allow_auto_disable>1</allow_auto_disable>, SDF's default: it was
    on the ledger as dropped, and an element without a name had no line."""
    result, _, sdf = _imported(tmp_path, """<?xml version="1.0"?>
<sdf version="1.6">
  <model name="m">
    <link name="base"><inertial><mass>1</mass></inertial></link>
    <allow_auto_disable>1</allow_auto_disable>
    <enable_wind>true</enable_wind>
  </model>
</sdf>
""")
    assert result.ledger == [f"{sdf}:6: model <enable_wind>: all: dropped: no place in the recipe"]


def test_joint_ends_named_with_the_models_own_name_first(tmp_path):
    """ArduPilot's Gazebo models fix their IMU to 'dolly_ardupilot::dolly::base_link': Gazebo
    classic finds it, libsdformat does not.  Dropped, it left the robot a second free body; read
    as Gazebo reads it, stated (a child so named, whose frame the joint's pose is relative to, too).
    A plugin naming a nested model's element names it as the recipe does ('/' for '::')."""
    (tmp_path / "dolly").mkdir()
    (tmp_path / "dolly" / "model.config").write_text(
        '<model><name>dolly</name><sdf version="1.7">model.sdf</sdf></model>')
    (tmp_path / "dolly" / "model.sdf").write_text(f"""<sdf version="1.7"><model name="dolly">
  <link name="base_link"><pose>0 0 0.1 0 0 0</pose>{INERTIAL.format(m=1, i=0.01)}</link>
</model></sdf>""")
    result, recipe, sdf = _imported(tmp_path, f"""<sdf version="1.7">
<model name="dolly_ardupilot">
  <include><uri>model://dolly</uri></include>
  <link name="imu_link"><pose>0 0 0.2 0 0 0</pose>{INERTIAL.format(m=0.01, i=1e-6)}</link>
  <link name="tag"><pose>0 0 0.3 0 0 0</pose>{INERTIAL.format(m=0.01, i=1e-6)}</link>
  <joint name="imu_joint" type="fixed">
    <parent>dolly_ardupilot::dolly::base_link</parent><child>imu_link</child>
  </joint>
  <joint name="tag_joint" type="fixed">
    <pose relative_to="dolly_ardupilot::dolly::base_link">0 0 0.2 0 0 0</pose>
    <parent>imu_link</parent><child>tag</child>
  </joint>
  <plugin name="ardupilot_plugin" filename="libArduPilotPlugin.so">
    <imuName>dolly_ardupilot::imu_link::imu_sensor</imuName>
    <control channel="0"><jointName>dolly_ardupilot::dolly::base_link</jointName></control>
    <link_name>dolly::base_link</link_name>
  </plugin>
</model></sdf>
""", "dolly_ardupilot")
    assert result.verdict.ok, result.verdict.lines()
    assert result.ledger == [
        f"{sdf}:6: joint 'imu_joint': all: 'dolly_ardupilot::dolly::base_link' read as 'dolly::base_link' (the "
        "model's own name first: Gazebo classic finds it, libsdformat does not)",
        f"{sdf}:13: plugin 'ardupilot_plugin' (libArduPilotPlugin.so): MJCF: dropped (kept verbatim in a <gazebo> "
        "block of urdf_extras, for model.sdf and the URDF); the names in it of 2 nested model elements written as "
        "the recipe's (a::b as a/b)"]
    plugin = recipe["urdf_extras"][0]
    assert "<imuName>dolly_ardupilot::imu_link::imu_sensor</imuName>" in plugin
    assert "<jointName>dolly_ardupilot::dolly/base_link</jointName>" in plugin
    assert "<link_name>dolly/base_link</link_name>" in plugin
    joints = _joints(recipe)
    assert (joints["imu_joint"]["parent"], joints["imu_joint"]["origin"]) == ("dolly/base_link", {"xyz": [0, 0, 0.1]})
    assert joints["tag_joint"]["origin"] == {"xyz": pytest.approx([0, 0, 0.1], abs=1e-15)}
    assert recipe.get("base") == "free" and "floating" not in {j["type"] for j in joints.values()}


def test_model_jointed_to_the_world_keeps_where_it_stands(tmp_path):
    """double_pendulum_inertia_ratio hangs from the world, its model turned 45 degrees about x:
    where it stands is how gravity pulls it.  The model's <pose> was dropped (the pendulum hung
    straight); it is kept in the joint to the world, and nothing is on the ledger."""
    result, recipe, _ = _imported(tmp_path, f"""<sdf version="1.4"><model name="pendulum">
  <pose>0 0 0.9 0.785398163397448 0 0</pose>
  <link name="upper"><pose>0 0 -0.05 0 0 0</pose>{INERTIAL.format(m=0.5, i=0.001)}</link>
  <joint name="upper_joint" type="revolute"><pose>0 0 0.05 0 0 0</pose>
    <parent>world</parent><child>upper</child><axis><xyz>1 0 0</xyz></axis></joint>
</model></sdf>""")
    assert result.verdict.ok, result.verdict.lines()
    assert result.ledger == []
    joint = _joints(recipe)["upper_joint"]
    assert (joint["type"], joint["parent"], joint["axis"]) == ("continuous", "world", [1, 0, 0])
    assert joint["origin"] == {"xyz": pytest.approx([0, 0, 0.9], abs=1e-15),
                               "rpy": pytest.approx([0.785398163397448, 0, 0], abs=1e-15)}


def test_ledger_lines_of_an_included_models_elements_name_its_file(tmp_path):
    """turtlebot includes create: what create's file holds (a joint renamed, its sensors, its
    inertial repaired) was put at turtlebot's file, without a line."""
    (tmp_path / "cart").mkdir()
    (tmp_path / "cart" / "model.config").write_text('<model><name>cart</name><sdf version="1.6">cart.sdf</sdf></model>')
    cart = tmp_path / "cart" / "cart.sdf"
    cart.write_text(f"""<sdf version="1.6"><model name="cart">
  <link name="body">{INERTIAL.format(m=1, i=0.01)}
    <sensor name="imu" type="imu"><update_rate>10</update_rate></sensor>
  </link>
  <link name="wheel"><pose>0 0.2 0 0 0 0</pose>{INERTIAL.format(m=0.1, i=0.001)}
    <visual name="v"><geometry><ellipsoid><radii>0.1 0.1 0.05</radii></ellipsoid></geometry></visual>
  </link>
  <joint name="wheel" type="revolute"><parent>body</parent><child>wheel</child>
    <axis><xyz>0 1 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>
</model></sdf>""")
    result, _, sdf = _imported(tmp_path, """<sdf version="1.6"><model name="train">
  <include><uri>model://cart</uri><name>front</name></include>
  <include><uri>model://cart</uri><name>back</name><pose>-1 0 0 0 0 0</pose></include>
  <joint name="hitch" type="fixed"><parent>front::body</parent><child>back::body</child></joint>
</model></sdf>""", "train")
    assert result.verdict.ok, result.verdict.lines()
    assert [line for line in result.ledger if "front/" in line] == [
        f"{cart}:8: joint 'front/wheel': all: renamed 'front/wheel_joint' (a link has its name: libsdformat "
        "refuses the pair)",
        f"{cart}:6: visual 'v' of link 'front/wheel' (ellipsoid): all: approximated: the box of its half-axes 0.1 0.1 0.05",
        f"{cart}:3: sensor 'imu' (imu) of link 'front/body': MJCF: dropped (kept verbatim in a <gazebo> block of "
        "urdf_extras, for model.sdf and the URDF)"]


def test_mass_without_inertia_says_sdfs_default_moments_above_the_link(tmp_path):
    """kinect (0.1 kg) gives no <inertia>: SDF's 1 kg m^2, which Gazebo simulates and the recipe
    keeps; `robotkit check` calls it implausible, so the recipe says where it comes from."""
    result, recipe, _ = _imported(tmp_path, """<sdf version="1.5"><model name="kinect">
  <link name="link"><inertial><mass>0.1</mass></inertial>
    <collision name="c"><geometry><box><size>0.07 0.28 0.07</size></box></geometry></collision></link>
</model></sdf>""")
    assert result.verdict.ok and result.ledger == [], result.ledger
    assert recipe["links"]["link"]["inertial"] == {"mass": 0.1, "inertia": {"ixx": 1, "iyy": 1, "izz": 1}}
    assert ("  # the SDF gives its mass and no <inertia>: SDF's default moments, 1 kg m^2 about each axis, as\n"
            "  # Gazebo simulates it\n  link:\n") in result.recipe_path.read_text()


def test_shapes_without_thickness_and_massless_links(tmp_path):
    """libsdformat validates a box 0 thick, a sphere of radius 0, a mesh scaled by 0 (Gazebo loads
    them); the recipe refused them (exit 2).  Written at the recipe's least length, stated.  A
    link of mass 0 fixed to a moving one is a <frame> of the rebuilt model.sdf: the verification
    compares its pose there (it said 'missing in the rebuild')."""
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "part.stl").write_text(TETRAHEDRON)
    result, recipe, sdf = _imported(tmp_path, f"""<sdf version="1.6"><model name="m">
  <link name="base">{INERTIAL.format(m=1, i=0.01)}
    <collision name="plate"><geometry><box><size>0.1 0.1 0</size></box></geometry></collision>
    <visual name="dot"><geometry><sphere><radius>0</radius></sphere></geometry></visual>
    <visual name="flat"><geometry><mesh><uri>part.stl</uri><scale>0 1 1</scale></mesh></geometry></visual>
  </link>
  <link name="arm"><pose>0 0 0.5 0 0 0</pose>{INERTIAL.format(m=1, i=0.01)}</link>
  <link name="tool"><pose>0.2 0 0.5 0 0 0</pose><inertial><mass>0</mass></inertial></link>
  <joint name="hinge" type="revolute"><parent>base</parent><child>arm</child>
    <axis><xyz>0 1 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>
  <joint name="tool_joint" type="fixed"><parent>arm</parent><child>tool</child></joint>
</model></sdf>""")
    assert result.verdict.ok and result.verdict.configurations == 11, result.verdict.lines()
    assert result.ledger == [
        f"{sdf}:4: visual 'dot' of link 'base' (sphere): all: approximated: its length 0 written 1e-06 m, the "
        "least the recipe takes",
        f"{sdf}:5: visual 'flat' of link 'base' (mesh part.stl): all: approximated: its scale 0 1 1 written with "
        "1e-06 for 0",
        f"{sdf}:3: collision 'plate' of link 'base' (box): all: approximated: its length 0 written 1e-06 m, the "
        "least the recipe takes"]
    base = recipe["links"]["base"]
    assert base["collision"] == {"box": {"size": [0.1, 0.1, 1e-6]}}
    assert [base["visual"][0], base["visual"][1]["scale"]] == [{"sphere": {"radius": 1e-6}}, [1e-6, 1, 1]]
    assert "inertial" not in recipe["links"]["tool"]


def test_names_the_recipe_refuses_are_renamed_and_values_above_its_largest_written_so(tmp_path):
    """libsdformat takes a link 'base link', a joint '1 hinge' and a frame 'tool tip', and a
    damping of 1e13; the recipe refused them all (exit 2).  Renamed as a ROS frame name holds
    them, the damping written 1e12, each stated at the original's line."""
    result, recipe, sdf = _imported(tmp_path, f"""<sdf version="1.7"><model name="m">
  <link name="base link">{INERTIAL.format(m=1, i=0.01)}</link>
  <link name="arm"><pose>0 0 0.5 0 0 0</pose>{INERTIAL.format(m=1, i=0.01)}</link>
  <joint name="1 hinge" type="revolute"><parent>base link</parent><child>arm</child>
    <axis><xyz>0 1 0</xyz><limit><lower>-1</lower><upper>1</upper></limit>
      <dynamics><damping>1e13</damping></dynamics></axis></joint>
  <frame name="tool tip" attached_to="arm"><pose>0.1 0 0 0 0 0</pose></frame>
</model></sdf>""")
    assert result.verdict.ok and result.verdict.configurations == 11, result.verdict.lines()
    why = "(a recipe name holds letters, digits, '_', '-' and '.', a letter or '_' first, with '/' between parts)"
    assert result.ledger == [
        f"{sdf}:2: link 'base link': all: renamed 'base_link' {why}",
        f"{sdf}:4: joint '1 hinge': all: renamed '_1_hinge' {why}",
        f"{sdf}:7: frame 'tool tip': all: renamed 'tool_tip' {why}",
        f"{sdf}:4: joint '_1_hinge' damping 1e+13: all: approximated: written 1e+12, the largest the recipe takes"]
    joints = _joints(recipe)
    assert (joints["_1_hinge"]["parent"], joints["_1_hinge"]["dynamics"]) == ("base_link", {"damping": 1e12})
    assert (joints["tool_tip_frame"]["parent"], joints["tool_tip_frame"]["child"]) == ("arm", "tool_tip")


def test_masses_beyond_the_recipes_range_written_at_its_bound_moments_scaled(tmp_path):
    """libsdformat and Gazebo take a 1e7 kg block and a 1e-12 kg speck; the recipe refused them
    (it takes 1e-9 to 1e6 kg).  Written at the bound, the moments scaled by the same factor (the
    same radius of gyration), stated; the verification compares their poses only."""
    result, recipe, sdf = _imported(tmp_path, """<sdf version="1.6"><model name="m">
  <link name="block"><inertial><mass>1e7</mass><inertia><ixx>1e12</ixx><iyy>2e12</iyy><izz>3e12</izz></inertia>
    </inertial></link>
  <link name="speck"><pose>0 0 6 0 0 0</pose>
    <inertial><mass>1e-12</mass><inertia><ixx>1e-15</ixx><iyy>1e-15</iyy><izz>1e-15</izz></inertia></inertial></link>
  <joint name="j" type="revolute"><parent>block</parent><child>speck</child>
    <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>
</model></sdf>""")
    assert result.verdict.ok and result.verdict.configurations == 11, result.verdict.lines()
    assert result.ledger == [
        f"{sdf}:2: link 'block' mass 1e+07 kg: all: approximated: written 1e+06 kg, the largest the recipe takes (its "
        "moments scaled alike)",
        f"{sdf}:4: link 'speck' mass 1e-12 kg: all: approximated: written 1e-09 kg, the least the recipe takes (its "
        "moments scaled alike)"]
    assert recipe["links"]["block"]["inertial"] == {"mass": 1e6, "inertia": {"ixx": 1e11, "iyy": 2e11, "izz": 3e11}}
    speck = recipe["links"]["speck"]["inertial"]
    assert speck["mass"] == 1e-9 and speck["inertia"]["ixx"] == pytest.approx(1e-12, rel=1e-12)
