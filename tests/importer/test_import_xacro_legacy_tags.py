"""Issue 32, KUKA KR210 (rtb-data): xacro 1's unprefixed tags (``<property name="deg" .../>``,
which ROS 1 xacro read with a deprecation warning until Noetic) are read as ``xacro:`` tags, the
one obvious reading, with one warning per tag name and file naming the line of its first use;
xacro 2 alone leaves them in the output and fails on the undefined name."""

from __future__ import annotations

import textwrap

from robotkit.importer.xacro_expand import expand
from robotkit.urdfxml import parse_text

PARTS = """\
<?xml version="1.0"?>
<robot xmlns:xacro="http://wiki.ros.org/xacro">
  <property name="deg" value="0.017453293"/>
  <property name="length" value="0.5"/>
  <macro name="arm" params="prefix">
    <link name="${prefix}base"/>
    <link name="${prefix}tool"/>
    <joint name="${prefix}a1" type="revolute">
      <parent link="${prefix}base"/><child link="${prefix}tool"/>
      <origin xyz="0 0 ${length}"/><axis xyz="0 0 1"/>
      <limit lower="${-185*deg}" upper="${185*deg}" effort="10" velocity="1"/>
    </joint>
  </macro>
</robot>
"""

TOP = """\
<?xml version="1.0"?>
<robot name="kr" xmlns:xacro="http://wiki.ros.org/xacro">
  <include filename="parts.xacro"/>
  <xacro:arm prefix="r_"/>
  <if value="${length > 1}"><link name="never"/></if>
</robot>
"""


def test_unprefixed_xacro_1_tags_are_read_as_xacro_tags(tmp_path):
    (tmp_path / "parts.xacro").write_text(PARTS, encoding="utf-8")
    (tmp_path / "kr.xacro").write_text(TOP, encoding="utf-8")
    out = expand(tmp_path / "kr.xacro", {})
    root = parse_text(out.text).getroot()
    assert [e.get("name") for e in root.iter("link")] == ["r_base", "r_tool"]
    limit = root.find("joint/limit")
    assert (float(limit.get("lower")), float(limit.get("upper"))) == (-185 * 0.017453293, 185 * 0.017453293)
    assert not [e.tag for e in root.iter() if e.tag in ("property", "macro", "include", "if")]
    top, parts = tmp_path / "kr.xacro", tmp_path / "parts.xacro"
    assert [w for w in out.warnings if "without the xacro: prefix" in w] == [
        f"{top}:3: xacro: <include> without the xacro: prefix read as <xacro:include>, as ROS 1 xacro read it "
        "(xacro 2 leaves it unexpanded)",
        f"{top}:5: xacro: <if> without the xacro: prefix read as <xacro:if>, as ROS 1 xacro read it "
        "(xacro 2 leaves it unexpanded)",
        f"{parts}:3: xacro: <property> without the xacro: prefix (2 tags) read as <xacro:property>, as ROS 1 xacro "
        "read it (xacro 2 leaves it unexpanded)",
        f"{parts}:5: xacro: <macro> without the xacro: prefix read as <xacro:macro>, as ROS 1 xacro read it "
        "(xacro 2 leaves it unexpanded)"]


def test_a_file_without_the_xacro_namespace_keeps_its_tags(tmp_path):
    (tmp_path / "plain.xacro").write_text(textwrap.dedent("""\
        <?xml version="1.0"?>
        <robot name="plain">
          <link name="base"/>
          <gazebo><plugin name="p" filename="libp.so"><arg>--verbose</arg></plugin></gazebo>
        </robot>
        """), encoding="utf-8")
    out = expand(tmp_path / "plain.xacro", {})
    assert parse_text(out.text).getroot().find("gazebo/plugin/arg").text == "--verbose"
    assert not [w for w in out.warnings if "without the xacro: prefix" in w]
