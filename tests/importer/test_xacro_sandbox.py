"""Issue 14 (and #20's xacro part): the xacro sandbox blocks only what would run code, read
outside the project and declared packages, read the environment or never end; ordinary xacro
works.  Every message names the file and the line."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from robotkit.errors import RobotkitError
from robotkit.importer.xacro_expand import expand


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def test_ordinary_xacro_works(tmp_path):
    """A macro parameter named ``type``, a property named ``_tokens_``, block parameters, an
    include with a namespace through $(find-pkg-share), load_yaml inside a package with
    attribute access to a key named ``type``, math, $(optenv) and $(dirname)."""
    pkg = tmp_path / "pkg"
    _write(pkg / "config" / "j.yaml", "joint: {type: revolute, lower: -1.5}\n")
    _write(pkg / "urdf" / "parts.xacro", """
        <robot xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:macro name="part" params="name type:=fixed *origin **extra">
            <link name="${name}_${type}"/>
            <xacro:insert_block name="extra"/>
          </xacro:macro>
        </robot>
    """)
    top = _write(tmp_path / "proj" / "r.urdf.xacro", """
        <robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:include filename="$(find-pkg-share pkg)/urdf/parts.xacro" ns="p"/>
          <xacro:property name="cfg" value="${xacro.load_yaml('$(find pkg)/config/j.yaml')}"/>
          <xacro:property name="_tokens_" value="${python.set(['a']) - python.set(['b'])}"/>
          <link name="base"><visual><geometry><box size="${2**3/10} 0.1 $(optenv NOT_SET 0.1)"/></geometry></visual></link>
          <xacro:p.part name="tip" type="${cfg['joint']['type']}"><origin/><extra><gazebo/></extra></xacro:p.part>
          <joint name="j" type="${cfg.joint.type}"><parent link="base"/><child link="tip_revolute"/>
            <limit lower="${cfg['joint']['lower']}" upper="${radians(90)}" effort="1" velocity="1"/></joint>
          <xacro:if value="${_tokens_}"><link name="$(dirname)"/></xacro:if>
        </robot>
    """)
    text = expand(top, {"pkg": str(pkg)}, {}).text
    assert '<box size="0.8 0.1 0.1"/>' in text and '<link name="tip_revolute"/><gazebo/>' in text
    assert 'type="revolute"' in text and 'lower="-1.5" upper="1.5707963267948966"' in text
    assert f'<link name="{tmp_path / "proj"}"/>' in text


BLOCKED = {
    "include outside": ('<xacro:include filename="../outside.xacro"/>',
                        "reading {out}/outside.xacro is outside the project proj/: robotkit reads only the project "
                        "and declared package paths (widen on purpose with --root DIR or ROBOTKIT_ROOT)"),
    "load_yaml outside": ("<xacro:property name=\"c\" value=\"${xacro.load_yaml('../outside.yaml')}\"/>"
                          '<link name="${c.a}"/>',
                          "reading {out}/outside.yaml is outside the project proj/: robotkit reads only the project "
                          "and declared package paths (widen on purpose with --root DIR or ROBOTKIT_ROOT)"),
    "env": ('<link name="$(env HOME)"/>',
            "$(env HOME) is blocked: an imported file does not read the environment (give the value as an "
            "argument, or use $(optenv HOME DEFAULT))"),
    "huge power": ('<link name="${9**9**9}"/>', "xacro: expansion stopped: 9**387420489 has more than 65536 bits"),
    "huge string": ("<link name=\"${'a'*10**9}\"/>",
                    "xacro: expansion stopped: a repetition of more than 4194304 items"),
    "huge range": ('<link name="${len(python.range(10**9))}"/>',
                   "xacro: expansion stopped: a range of more than 4194304 items"),
    "dunder": ('<link name="${[1][0].__class__}"/>',
               "refusing to evaluate xacro expression '[1][0].__class__': names starting with '_' ('__class__') "
               "are not allowed (an imported file may only compute values)"),
}


@pytest.mark.parametrize("case", sorted(BLOCKED))
def test_what_is_blocked_is_named_with_file_and_line(tmp_path, monkeypatch, case):
    monkeypatch.delenv("ROBOTKIT_ROOT", raising=False)  # the read rules as a user has them (conftest widens them)
    body, message = BLOCKED[case]
    _write(tmp_path / "outside.xacro", '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="x"/></robot>')
    _write(tmp_path / "outside.yaml", "a: 1\n")
    (tmp_path / "proj").mkdir()
    (tmp_path / "proj" / "r.urdf.xacro").write_text(
        f'<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n  <link name="base"/>\n  {body}\n</robot>\n',
        encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(RobotkitError) as info:
        expand(tmp_path / "proj" / "r.urdf.xacro", {}, {})
    assert info.value.lines() == ["proj/r.urdf.xacro:3: " + message.format(out=tmp_path)]


def test_an_expansion_has_a_time_limit(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "r.urdf.xacro", """
        <robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <link name="base"/>
        </robot>
    """)
    with pytest.raises(RobotkitError) as info:
        expand(tmp_path / "r.urdf.xacro", {}, {}, time_limit=0.0)
    assert info.value.lines() == ["r.urdf.xacro: xacro: expansion stopped: the expansion takes longer than 0 s"]
