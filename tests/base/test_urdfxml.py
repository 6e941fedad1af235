"""robotkit.urdfxml: the one URDF reader (hardened lxml, source lines, urdfdom's XML versions)."""

from __future__ import annotations

import pytest

from robotkit import urdfxml

ENTITIES = "".join(f'<!ENTITY l{i} "' + f"&l{i - 1};" * 10 + '">' for i in range(1, 10))
LAUGHS = f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY l0 "lol">{ENTITIES}]><robot name="r"><link>&l9;</link></robot>'


def test_a_text_and_a_file_give_the_tree_with_source_lines(tmp_path):
    text = '<?xml version="1.0"?>\n<robot name="r">\n  <link name="a"/>\n  <joint name="j"/>\n</robot>\n'
    (tmp_path / "r.urdf").write_text(text, encoding="utf-8")
    for tree in (urdfxml.parse_text(text), urdfxml.parse_file(tmp_path / "r.urdf")):
        root = tree.getroot()
        assert root.tag == "robot" and root.get("name") == "r"
        assert [(e.tag, e.sourceline) for e in root] == [("link", 3), ("joint", 4)]


def test_any_declared_xml_version_is_read_as_urdfdom_reads_it(tmp_path):
    (tmp_path / "h.urdf").write_bytes(b'<?xml version="0.0" ?>\n<robot name="humanoid"/>\n')
    assert urdfxml.parse_file(tmp_path / "h.urdf").getroot().get("name") == "humanoid"


def test_entities_in_text_are_not_expanded_and_a_billion_laughs_is_refused():
    link = urdfxml.parse_text(LAUGHS.replace("&l9;", "&l1;")).getroot().find("link")
    assert link.text is None and "lol" not in "".join(link.itertext())
    with pytest.raises(urdfxml.MalformedXML):  # in an attribute (which libxml2 always expands): refused
        urdfxml.parse_text(LAUGHS.replace('name="r"', 'name="&l9;"'))


def test_a_text_ignores_its_declared_encoding_as_python_does():
    text = '<?xml version="1.0" encoding="ISO-8859-1"?><robot name="\u00e9"/>'
    assert urdfxml.parse_text(text).getroot().get("name") == "\u00e9"


def test_comments_are_dropped_unless_asked_for():
    text = "<robot><!-- c --><link name='a'>x<!-- c -->y</link><?pi x?></robot>"
    root = urdfxml.parse_text(text).getroot()
    assert [e.tag for e in root] == ["link"] and root[0].text == "xy"
    kept = urdfxml.parse_text(text, comments=True).getroot()
    assert [urdfxml.is_element(e) for e in kept] == [False, True, False]


def test_malformed_xml_in_both_readers_words():
    with pytest.raises(urdfxml.MalformedXML) as err:
        urdfxml.parse_text('<robot name="r">\n<link name="a"></robot>')
    assert err.value.expat == "mismatched tag: line 2, column 17"
    assert err.value.expat_line == 2
    assert str(err.value).startswith("Opening and ending tag mismatch: link line 2 and robot")
    assert err.value.line == 2
