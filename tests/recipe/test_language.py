"""The recipe language (robotkit.recipe.expand): arguments, expressions, units, parts,
mirroring, conditions, variants; their errors word for word; the rewritten examples."""

from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest
import trimesh
import yaml

from conftest import REPO, RECIPES, run_cli, write_recipe
from robotkit.pipeline.runner import build
from robotkit.recipe.expand import units
from robotkit.recipe.expand.expr import ExprError, evaluate
from robotkit.check.kinematics import compare, read_urdf

TOL = 1e-9


# ---------------------------------------------------------------- expressions


@pytest.mark.parametrize("text, scope, expected", [
    ("1 + 2 * 3", {}, 7),
    ("(1 + 2) * 3", {}, 9),
    ("2 ** 10", {}, 1024),
    ("-2 ** 2", {}, -4),
    ("7 // 2 + 7 % 2", {}, 4),
    ("1 / 4", {}, 0.25),
    ("pi / 2", {}, math.pi / 2),
    ("tau - 2 * pi", {}, 0.0),
    ("radians(90)", {}, math.pi / 2),
    ("degrees(pi)", {}, 180.0),
    ("sqrt(w * w + h * h)", {"w": 3, "h": 4}, 5.0),
    ("hypot(3, 4)", {}, 5.0),
    ("atan2(1, 1)", {}, math.pi / 4),
    ("max(1, r, 2)", {"r": 5}, 5),
    ("min(r, 2)", {"r": 5}, 2),
    ("round(2.675, 2)", {}, 2.67),
    ("abs(-3) + floor(2.5) + ceil(2.5)", {}, 8),
    ("log(e)", {}, 1.0),
    ("r if big else r / 2", {"r": 0.1, "big": False}, 0.05),
    ("1 < r <= 5", {"r": 5}, True),
    ("side == 'left' and not flip", {"side": "left", "flip": False}, True),
    ("side != 'left' or 0", {"side": "left"}, 0),
    ("prefix + 'link'", {"prefix": "arm_"}, "arm_link"),
    ("true and false", {}, False),
])
def test_expressions_against_known_answers(text, scope, expected):
    got = evaluate(text, scope)
    assert got == expected and type(got) is type(expected)


@pytest.mark.parametrize("text, message", [
    ("wdth * 2", "unknown name 'wdth' (did you mean 'width'?)"),
    ("9 ** 9 ** 9", "exponent too large"),
    ("10 ** 400 * 1.0", "number too large"),
    ("2 ** 1000 * 2 ** 1000", "number too large"),
    ("1e308 * 10", "number too large"),
    ("1 / 0", "division by zero"),
    ("__import__('os')", "unknown function '__import__' (known: abs, acos, asin, atan, atan2, ceil, cos, cosh, "
                         "degrees, exp, fabs, float, floor, hypot, int, log, log10, log2, max, min, radians, "
                         "round, sin, sinh, sqrt, tan, tanh)"),
    ("width.real", "'width.real' is not allowed (numbers, names, arithmetic, comparisons, 'and', 'or', 'not', "
                   "'a if c else b' and math functions only)"),
    ("[1, 2]", "'[1, 2]' is not allowed (numbers, names, arithmetic, comparisons, 'and', 'or', 'not', "
               "'a if c else b' and math functions only)"),
    ("'ab' * 1000", "cannot apply '*' to 'ab' and 1000"),
    ("sqrt(-1)", "sqrt(): math domain error"),
    ("sqrt(1, 2)", "sqrt() takes 1 argument (got 2)"),
    ("sin", "'sin' is a function: call it as sin(...)"),
    ("1 +", "invalid syntax"),
    ("1" + " + 1" * 300, "longer than 500 characters"),
])
def test_bad_expressions(text, message):
    with pytest.raises(ExprError) as exc:
        evaluate(text, {"width": 1.0})
    assert str(exc.value) == message


UNIT_FUNCTIONS = {unit: to_si for unit, (_, to_si) in units.UNITS.items()}


@pytest.mark.parametrize("text, expected", [
    ("width + 1 cm", 0.21),
    ("width + 1cm", 0.21),
    ("2 * 3 mm", 0.006),
    ("-5 mm", -0.005),
    ("90 deg", math.pi / 2),
    ("300 g + 1 kg", 1.3),
    ("1 in", 0.0254),
    ("1.5e2 mm", 0.15),
    ("width if width > 10 cm else 0", 0.2),
    ("1 if width else 2", 1),          # a keyword after a number is no unit
    ("'5 cm'", "5 cm"),                # nor is anything inside text
])
def test_quantities_inside_expressions_are_their_si_numbers(text, expected):
    got = evaluate(text, {"width": 0.2}, UNIT_FUNCTIONS, units.KNOWN)
    assert got == pytest.approx(expected, rel=1e-15) if isinstance(expected, float) else got == expected


def test_an_unknown_unit_inside_an_expression_says_so():
    with pytest.raises(ExprError) as exc:
        evaluate("width + 2 furlong", {"width": 0.2}, UNIT_FUNCTIONS, units.KNOWN)
    assert str(exc.value) == ("unknown unit 'furlong' in '2 furlong' (lengths: m, cm, mm, um, km, in, ft; "
                              "angles: rad, deg; masses: kg, g, mg, lb)")


def test_a_recipe_with_units_inside_expressions(tmp_path):
    write_recipe(tmp_path, """
        robot: r
        values: {body_width: 20 cm}
        links:
          base: {visual: {box: {size: ["${body_width + 1 cm}", 0.1, "${2 * 5 mm}"]}}}
        """)
    proc = run_cli("expand", "robot.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    size = yaml.safe_load(proc.stdout)["links"]["base"]["visual"]["box"]["size"]
    assert size == [pytest.approx(0.21, rel=1e-15), 0.1, 0.01]


def test_float_overflow_is_an_error_not_inf():
    with pytest.raises(ExprError, match=r"^exp\(\): number too large$"):
        evaluate("exp(1000)", {})


# ---------------------------------------------------------------- units


@pytest.mark.parametrize("text, value, dim", [
    ("5 cm", 0.05, "length"), ("5cm", 0.05, "length"), ("-32 mm", -0.032, "length"), ("31.5 mm", 0.0315, "length"),
    ("2 in", 0.0508, "length"), ("1 ft", 0.3048, "length"), ("1.5 km", 1500.0, "length"), ("3 m", 3.0, "length"),
    ("90 deg", math.pi / 2, "angle"), ("-45 deg", -math.pi / 4, "angle"), ("0.5 rad", 0.5, "angle"),
    ("300 g", 0.3, "mass"), ("1 lb", 0.45359237, "mass"), ("2 kg", 2.0, "mass"), ("5 mg", 5e-6, "mass"),
])
def test_quantities_convert_to_si_exactly(text, value, dim):
    assert units.parse(text) == (value, dim)


def test_a_recipe_with_units_builds_the_same_bytes_as_the_si_recipe(tmp_path):
    common = """
        links:
          base: {visual: {box: {size: [%s, %s, %s]}, origin: {xyz: [0, 0, %s]}}, inertial: {mass: %s}}
          arm: {visual: {cylinder: {radius: %s, length: %s}, origin: {rpy: [%s, 0, 0]}}}
        joints:
          j: {type: revolute, parent: base, child: arm, origin: {xyz: [0, %s, 0], rpy: [0, 0, %s]}, axis: [0, 0, 1],
              limit: {lower: %s, upper: %s, effort: 1, velocity: 1}}
          """
    with_units = ("20 cm", "4 in", "5 mm", "2.5 cm", "300 g", "1 cm", "1 ft", "90 deg", "'${half}'", "-45 deg",
                  "-120 deg", "120 deg")
    si = ("0.2", "0.1016", "0.005", "0.025", "0.3", "0.01", "0.3048", "1.5707963267948966", "0.1",
          "-0.7853981633974483", "-2.0943951023931953", "2.0943951023931953")
    a = write_recipe(tmp_path / "a", "robot: r\nvalues: {half: 10 cm}\n" + textwrap.dedent(common % with_units))
    b = write_recipe(tmp_path / "b", "robot: r\n" + textwrap.dedent(common % si))
    for recipe in (a, b):
        assert not build([recipe], recipe.parent / "out").errors
    for rel in ("urdf/r.urdf", "model.sdf", "mjcf/r.xml"):
        assert (tmp_path / "a/out/r" / rel).read_bytes() == (tmp_path / "b/out/r" / rel).read_bytes(), rel


# ---------------------------------------------------------------- errors, word for word

BAD = {
    "unknown_name": ("""
        robot: r
        values: {width: 0.2}
        links:
          base: {visual: {box: {size: ["${widht}", 1, 1]}}}
        """, ["robot.yaml:4: links.base.visual.box.size[0]: in ${widht}: unknown name 'widht' "
              "(did you mean 'width'?)"]),
    "bad_syntax_and_division": ("""
        robot: r
        values:
          a: ${1 +}
          b: ${1 / 0}
        links:
          base: {}
        """, ["robot.yaml:3: values.a: in ${1 +}: invalid syntax",
              "robot.yaml:4: values.b: in ${1 / 0}: division by zero"]),
    "wrong_dimension": ("""
        robot: r
        links:
          base: {visual: {box: {size: [5 cm, 1 kg, 1]}, origin: {rpy: [5 cm, 0, 0]}}, inertial: {mass: 90 deg}}
        """, ["robot.yaml:3: links.base.visual.box.size[1]: expects a length, got a mass ('1 kg')",
              "robot.yaml:3: links.base.visual.origin.rpy[0]: expects an angle, got a length ('5 cm')",
              "robot.yaml:3: links.base.inertial.mass: expects a mass, got an angle ('90 deg')"]),
    "unknown_unit_and_unitless_field": ("""
        robot: r
        density: 5 cm
        links:
          base: {visual: {sphere: {radius: 3 furlongs}}}
        """, ["robot.yaml:2: density: takes a plain number, not a quantity with units (got '5 cm')",
              "robot.yaml:4: links.base.visual.sphere.radius: unknown unit 'furlongs' in '3 furlongs' "
              "(lengths: m, cm, mm, um, km, in, ft; angles: rad, deg; masses: kg, g, mg, lb)"]),
    "joint_limits_take_the_joint_unit": ("""
        robot: r
        links: {a: {}, b: {}, c: {}}
        joints:
          slide: {type: prismatic, parent: a, child: b, limit: {lower: 0, upper: 10 deg, effort: 1, velocity: 1}}
          turn: {type: revolute, parent: b, child: c, limit: {lower: -90 deg, upper: 5 cm, effort: 1, velocity: 1}}
        """, ["robot.yaml:4: joints.slide.limit.upper: expects a length, got an angle ('10 deg')",
              "robot.yaml:5: joints.turn.limit.upper: expects an angle, got a length ('5 cm')"]),
    "args": ("""
        robot: r
        args:
          wheels: {default: 4, choices: [2, 4]}
          color: red
        variants:
          big: {wheles: 6}
          odd: {wheels: 3}
        links:
          base: {}
        """, ["robot.yaml:6: variants.big.wheles: unknown argument 'wheles' of the recipe (did you mean 'wheels'?)",
              "robot.yaml:7: variants.odd.wheels: argument 'wheels' must be one of 2, 4 (got 3)"]),
    "if_not_a_bool": ("""
        robot: r
        links:
          base: {}
          extra: {if: maybe}
        """, ["robot.yaml:2: links: the links form 2 separate trees with roots 'base', 'extra'; connect them with "
              "joints so one root remains",
              "robot.yaml:4: links.extra.if: must be true or false (got 'maybe')"]),
    "instances": ("""
        robot: r
        parts:
          wheel:
            args: {radius: 0.1}
            links:
              tyre: {visual: {cylinder: {radius: "${radius}", length: 0.05}}}
            joints:
              axle: {type: continuous, parent: "${parent}", child: tyre}
        links:
          base: {}
        instances:
          a: {part: wheeel, parent: base}
          b: {part: wheel, parent: base, args: {radios: 1}, mirror: yx}
          c: {part: wheel, parent: base, args: {radius: -1}, orgin: {}}
          d: {part: wheel, parent: base, args: {radius: -1}}
        """, ["robot.yaml:12: instances.a.part: no part named 'wheeel' (did you mean 'wheel'?)",
              "robot.yaml:13: instances.b.mirror: must be one of xz, yz, xy (got 'yx')",
              "robot.yaml:14: instances.c.orgin: unknown key (did you mean 'origin'?)",
              "robot.yaml:15: instances.d.args.radius: must be > 0 (via part 'wheel': robot.yaml:6: "
              "parts.wheel.links.tyre.visual.cylinder.radius)"]),
}


BAD["instance_args_not_a_mapping"] = ("""
    robot: r
    parts:
      wheel:
        links: {tyre: {visual: {cylinder: {radius: 0.1, length: 0.05}}}}
        joints: {axle: {type: continuous, parent: "${parent}", child: tyre}}
    links: {base: {}}
    instances:
      a: {part: wheel, parent: base, args: .nan}
    """, ["robot.yaml:8: instances.a.args: must be a mapping of argument values (got nan)"])

BAD["expression_errors_without_knock_on"] = ("""
    robot: r
    values:
      width: 20 cm
      wide: ${widht + 1 cm}
      wider: ${wide * 2}
      odd: ${width + 2 furlong}
    args:
      half: {default: "${1 +}"}
    links:
      base: {visual: {box: {size: ["${wide}", "${wider}", "${half}"]}}}
      arm: {visual: {box: {size: ["${odd}", 1, "${wider} m"]}}}
    joints:
      j: {type: fixed, parent: base, child: arm}
    """, ["robot.yaml:4: values.wide: in ${widht + 1 cm}: unknown name 'widht' (did you mean 'width'?)",
          "robot.yaml:6: values.odd: in ${width + 2 furlong}: unknown unit 'furlong' in '2 furlong' "
          "(lengths: m, cm, mm, um, km, in, ft; angles: rad, deg; masses: kg, g, mg, lb)",
          "robot.yaml:8: args.half.default: in ${1 +}: invalid syntax"])


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_recipes(tmp_path, case):
    text, expected = BAD[case]
    write_recipe(tmp_path, text)
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.splitlines() == expected
    assert not (tmp_path / "out").exists()


def test_a_typo_in_an_instance_names_the_instance_line(tmp_path):
    """The part file writes ``parent: ${parent}``; the typo is the instance's, so is the line."""
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "wheel.yaml").write_text(textwrap.dedent("""\
        args: {radius: 5 cm}
        links:
          wheel: {visual: {cylinder: {radius: "${radius}", length: 2 cm}}}
        joints:
          axle: {type: continuous, parent: "${parent}", child: wheel, axis: [0, 1, 0]}
        """))
    write_recipe(tmp_path, """
        robot: r
        links:
          base_link: {visual: {box: {size: [0.1, 0.1, 0.1]}}}
        parts:
          wheel: parts/wheel.yaml
        instances:
          left: {part: wheel, parent: bsae_link}
          right: {part: wheel, parent: base_link, args: {radius: 0 cm}}
        """)
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "robot.yaml:7: instances.left.parent: no link named 'bsae_link' (did you mean 'base_link'?) "
        "(via part 'wheel': parts/wheel.yaml:5: joints.axle.parent)",
        "robot.yaml:8: instances.right.args.radius: must be > 0 (via part 'wheel': parts/wheel.yaml:3: "
        "links.wheel.visual.cylinder.radius)"]


@pytest.mark.slow
def test_arguments_from_the_command_line(tmp_path):
    write_recipe(tmp_path, """
        robot: r
        args:
          size: 10 cm
          solid: true
          mode: {default: a, choices: [a, b]}
        links:
          base: {visual: {box: {size: ["${size}", "${size}", "${size}"]}}, inertial: {mass: "${1.0 if solid else 2.0}"}}
        """)
    proc = run_cli("build", "robot.yaml", "--out", "out", "--arg", "siz:=1", "--arg", "solid:=yes please",
                   "--arg", "size:=2 kg", "--arg", "mode:=c", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "robot.yaml:2: --arg siz: unknown argument 'siz' of the recipe (did you mean 'size'?)",
        "robot.yaml:2: --arg solid: argument 'solid' must be true or false (got 'yes please')",
        "robot.yaml:2: --arg size: argument 'size' must be a length (got '2 kg')",
        "robot.yaml:2: --arg mode: argument 'mode' must be one of 'a', 'b' (got 'c')"]
    proc = run_cli("expand", "robot.yaml", "--arg", "size:=5 cm", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert yaml.safe_load(proc.stdout)["links"]["base"]["visual"]["box"]["size"] == [0.05, 0.05, 0.05]
    proc = run_cli("expand", "robot.yaml", "--arg", "size:=0.3", cwd=tmp_path)
    assert yaml.safe_load(proc.stdout)["links"]["base"]["visual"]["box"]["size"] == [0.3, 0.3, 0.3]


@pytest.mark.slow
def test_an_error_in_a_part_file_names_the_file_and_the_instances(tmp_path):
    (tmp_path / "parts").mkdir()
    write_recipe(tmp_path, """
        args: {length: 0.3}
        links:
          body: {visual: {box: {size: [0.04, 0.04, "${length}"]}}}
        joints:
          hinge: {type: revolute, parent: "${parent}", child: body, axis: [0, 1, 0],
                  limit: {lower: -1, upper: 1, effort: 1, velocity: "${speed}"}}
        """, name="parts/segment.yaml")
    write_recipe(tmp_path, """
        robot: r
        parts:
          segment: parts/segment.yaml
          arm:
            instances:
              upper: {part: segment, parent: "${parent}"}
              lower: {part: segment, parent: upper_body, origin: {xyz: [0, 0, 0.3]}, args: {length: -1}}
        links:
          base: {}
        instances:
          left: {part: arm, parent: base}
        """)
    proc = run_cli("build", "robot.yaml", "--out", "out", cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [
        "robot.yaml:7: parts.arm.instances.lower.args.length: must be > 0 (via part 'segment': "
        "parts/segment.yaml:3: links.body.visual.box.size[2]) (in instance left at robot.yaml:11)",
        "parts/segment.yaml:6: joints.hinge.limit.velocity: in ${speed}: unknown name 'speed' "
        "(in instance left at robot.yaml:11 > upper at robot.yaml:6)",
        "parts/segment.yaml:6: joints.hinge.limit.velocity: in ${speed}: unknown name 'speed' "
        "(in instance left at robot.yaml:11 > lower at robot.yaml:7)",
    ]


# ---------------------------------------------------------------- parts and mirroring

LEGS = """
    robot: legs
    density: 1000
    links:
      base: {visual: {box: {size: [0.4, 0.2, 0.1]}}}
    parts:
      leg:
        args: {upper: 20 cm}
        links:
          hip: {visual: {box: {size: [0.04, 0.05, 0.06]}, origin: {xyz: [0.01, 0.02, 0.03], rpy: [0.1, 0.2, 0.3]}}}
          shin:
            inertial: {mass: 0.5, com: [0.01, 0.02, -0.1],
                       inertia: {ixx: 0.02, iyy: 0.025, izz: 0.03, ixy: 0.001, ixz: 0.002, iyz: 0.003}}
          foot: {visual: {mesh: foot.stl, units: cm}}
          toe: {visual: {sphere: {radius: 0.01}, origin: {xyz: [0.01, 0.01, 0]}}}
        joints:
          hip_joint: {type: revolute, parent: "${parent}", child: hip, origin: {xyz: [0.1, 0.05, 0],
                      rpy: [0.2, 0.3, 0.4]}, axis: [1, 0, 0], limit: {lower: -0.5, upper: 1.0, effort: 10, velocity: 2}}
          knee: {type: revolute, parent: hip, child: shin, origin: {xyz: [0, 0.03, "${-upper}"]}, axis: [0, 1, 0],
                 limit: {lower: -2, upper: 0.1, effort: 10, velocity: 2}}
          ankle: {type: prismatic, parent: shin, child: foot, origin: {xyz: [0, 0, -0.2]}, axis: [0.6, 0.8, 0],
                  limit: {lower: 0, upper: 0.05, effort: 10, velocity: 1}}
          toe_joint: {type: revolute, parent: foot, child: toe, axis: [0, 0, 1],
                      limit: {lower: -1, upper: 1, effort: 1, velocity: 1}, mimic: {joint: hip_joint, multiplier: 2, offset: 0.1}}
    instances:
      left: {part: leg, parent: base, origin: {xyz: [0.2, 0.1, 0]}}
      right: {part: leg, parent: base, origin: {xyz: [0.2, 0.1, 0]}, mirror: xz}
    """

# the same robot written out by hand: the right leg mirrored across the base's xz plane
LEGS_BY_HAND = """
    robot: legs
    density: 1000
    links:
      base: {visual: {box: {size: [0.4, 0.2, 0.1]}}}
      left_hip: {visual: {box: {size: [0.04, 0.05, 0.06]}, origin: {xyz: [0.01, 0.02, 0.03], rpy: [0.1, 0.2, 0.3]}}}
      left_shin:
        inertial: {mass: 0.5, com: [0.01, 0.02, -0.1],
                   inertia: {ixx: 0.02, iyy: 0.025, izz: 0.03, ixy: 0.001, ixz: 0.002, iyz: 0.003}}
      left_foot: {visual: {mesh: foot.stl, units: cm}}
      left_toe: {visual: {sphere: {radius: 0.01}, origin: {xyz: [0.01, 0.01, 0]}}}
      right_hip: {visual: {box: {size: [0.04, 0.05, 0.06]}, origin: {xyz: [0.01, -0.02, 0.03], rpy: [-0.1, 0.2, -0.3]}}}
      right_shin:
        inertial: {mass: 0.5, com: [0.01, -0.02, -0.1],
                   inertia: {ixx: 0.02, iyy: 0.025, izz: 0.03, ixy: -0.001, ixz: 0.002, iyz: -0.003}}
      right_foot: {visual: {mesh: foot_mirrored.stl, units: cm}}
      right_toe: {visual: {sphere: {radius: 0.01}, origin: {xyz: [0.01, -0.01, 0]}}}
    joints:
      left_hip_joint: {type: revolute, parent: base, child: left_hip, origin: {xyz: [0.3, 0.15, 0], rpy: [0.2, 0.3, 0.4]},
                       axis: [1, 0, 0], limit: {lower: -0.5, upper: 1.0, effort: 10, velocity: 2}}
      left_knee: {type: revolute, parent: left_hip, child: left_shin, origin: {xyz: [0, 0.03, -0.2]}, axis: [0, 1, 0],
                  limit: {lower: -2, upper: 0.1, effort: 10, velocity: 2}}
      left_ankle: {type: prismatic, parent: left_shin, child: left_foot, origin: {xyz: [0, 0, -0.2]}, axis: [0.6, 0.8, 0],
                   limit: {lower: 0, upper: 0.05, effort: 10, velocity: 1}}
      left_toe_joint: {type: revolute, parent: left_foot, child: left_toe, axis: [0, 0, 1],
                       limit: {lower: -1, upper: 1, effort: 1, velocity: 1},
                       mimic: {joint: left_hip_joint, multiplier: 2, offset: 0.1}}
      right_hip_joint: {type: revolute, parent: base, child: right_hip, origin: {xyz: [0.3, -0.15, 0], rpy: [-0.2, 0.3, -0.4]},
                        axis: [1, 0, 0], limit: {lower: -1.0, upper: 0.5, effort: 10, velocity: 2}}
      right_knee: {type: revolute, parent: right_hip, child: right_shin, origin: {xyz: [0, -0.03, -0.2]}, axis: [0, 1, 0],
                   limit: {lower: -2, upper: 0.1, effort: 10, velocity: 2}}
      right_ankle: {type: prismatic, parent: right_shin, child: right_foot, origin: {xyz: [0, 0, -0.2]},
                    axis: [-0.6, 0.8, 0], limit: {lower: -0.05, upper: 0, effort: 10, velocity: 1}}
      right_toe_joint: {type: revolute, parent: right_foot, child: right_toe, axis: [0, 0, 1],
                        limit: {lower: -1, upper: 1, effort: 1, velocity: 1},
                        mimic: {joint: right_hip_joint, multiplier: 2, offset: -0.1}}
    """


def _foot_meshes():
    """An asymmetric tetrahedron (in cm) and its mirror image across y = 0, faces flipped, made by hand."""
    v = np.array([[0, 0, 0], [3, 0, 0], [0, 2, 0], [0.5, 1, 4.0]])
    f = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    return trimesh.Trimesh(v, f), trimesh.Trimesh(v * [1, -1, 1], f[:, ::-1])


@pytest.fixture(scope="module")
def legs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("legs")
    foot, mirrored = _foot_meshes()
    meshes = {"foot.stl": foot, "foot_mirrored.stl": mirrored}
    a = write_recipe(tmp / "parts", LEGS, meshes=meshes)
    b = write_recipe(tmp / "hand", LEGS_BY_HAND, meshes=meshes)
    for recipe in (a, b):
        result = build([recipe], recipe.parent / "out")
        assert not result.errors
    return tmp


def test_a_mirrored_part_equals_the_hand_written_robot(legs):
    got = read_urdf(legs / "parts/out/legs/urdf/legs.urdf")
    ref = read_urdf(legs / "hand/out/legs/urdf/legs.urdf")
    assert compare(got, ref, TOL, configs=100) == []


def test_the_mirrored_leg_is_the_mirror_image_at_every_configuration(legs):
    """Independent of the axis convention: with the joint values a mirrored joint negates,
    every right link's pose, centre of mass and inertia tensor (in base axes) are the left
    one's reflected across the base's xz plane."""
    model = read_urdf(legs / "parts/out/legs/urdf/legs.urdf")
    M = np.diag([1.0, -1.0, 1.0])
    negated = {"hip_joint": -1, "knee": 1, "ankle": -1}  # roll and slanted slide: axis kept, value negated
    rng = np.random.default_rng(1)
    for _ in range(50):
        q = {}
        for j, s in negated.items():
            lim = model.joints[f"left_{j}"]
            q[f"left_{j}"] = float(rng.uniform(lim.lower, lim.upper))
            q[f"right_{j}"] = s * q[f"left_{j}"]
        T = model.fk(q)
        for link in ("hip", "shin", "foot", "toe"):
            L, R = T[f"left_{link}"], T[f"right_{link}"]
            np.testing.assert_allclose(R[:3, 3], M @ L[:3, 3], atol=1e-12)
            np.testing.assert_allclose(R[:3, :3], M @ L[:3, :3] @ M, atol=1e-12)
            kl, kr = model.links[f"left_{link}"], model.links[f"right_{link}"]
            assert kr.mass == pytest.approx(kl.mass, rel=1e-12)
            np.testing.assert_allclose(R[:3, :3] @ kr.com + R[:3, 3], M @ (L[:3, :3] @ kl.com + L[:3, 3]), atol=1e-12)
            world_l = L[:3, :3] @ kl.inertia @ L[:3, :3].T
            world_r = R[:3, :3] @ kr.inertia @ R[:3, :3].T
            np.testing.assert_allclose(world_r, M @ world_l @ M, atol=1e-12 * max(1.0, np.abs(world_l).max()))


def test_mirrored_meshes_are_written_mirrored_with_outward_faces(legs):
    out = legs / "parts/out/legs"
    urdf = (out / "urdf/legs.urdf").read_text()
    assert 'filename="package://legs/meshes/visual/foot_mirrored.stl"/>' in urdf and 'scale="0.01 -0.01' not in urdf
    written = trimesh.load(out / "meshes/visual/foot_mirrored.stl")
    foot, mirrored = _foot_meshes()
    assert written.volume == pytest.approx(mirrored.volume * 1e-6, rel=1e-6) and written.volume > 0
    np.testing.assert_allclose(written.center_mass, mirrored.center_mass * 0.01, atol=1e-7)


@pytest.mark.consumers
@pytest.mark.slow
def test_every_format_of_the_mirrored_build_agrees(legs):
    proc = run_cli("check", legs / "parts/out/legs", "--format", "json")
    import json

    data = json.loads(proc.stdout)
    # libsdformat's URDF reading holds no mimic relations; main at 9c95f6e compares them anyway
    # (a fix is under way there): those two lines aside, every comparison must agree
    errors = [f for f in data["findings"] if f["severity"] == "error"
              and not ("URDF (libsdformat) vs URDF lumped" in f["message"] and "vs None" in f["message"]
                       and "mimic" in f["message"])]
    assert errors == [], proc.stdout


@pytest.mark.slow
def test_expand_prints_a_flat_recipe_that_builds_the_same_robot(legs, tmp_path):
    proc = run_cli("expand", legs / "parts/robot.yaml")
    assert proc.returncode == 0, proc.stderr
    flat = yaml.safe_load(proc.stdout)
    assert set(flat) == {"robot", "links", "joints"}  # density 1000 is the default
    assert flat["joints"]["right_ankle"]["axis"] == [-0.6, 0.8, 0.0]
    assert flat["joints"]["right_ankle"]["limit"]["lower"] == -0.05
    assert flat["links"]["right_foot"]["visual"]["scale"] == [0.01, -0.01, 0.01]
    (legs / "parts/flat.yaml").write_text(proc.stdout)
    assert not build([legs / "parts/flat.yaml"], tmp_path).errors
    assert compare(read_urdf(tmp_path / "legs/urdf/legs.urdf"),
                   read_urdf(legs / "parts/out/legs/urdf/legs.urdf"), TOL) == []


def test_instance_origin_with_a_rotation_composes_with_the_joint_origin(tmp_path):
    from robotkit.check.kinematics import rpy_matrix

    write_recipe(tmp_path, """
        robot: r
        parts:
          p:
            links: {l: {}}
            joints: {j: {type: fixed, parent: "${parent}", child: l, origin: {xyz: [0.1, 0.2, 0.3], rpy: [0.3, -0.2, 0.1]}}}
        links: {base: {}}
        instances:
          i: {part: p, parent: base, origin: {xyz: [1, 2, 3], rpy: [0.5, 0.4, -0.7]}}
        """)
    proc = run_cli("expand", "robot.yaml", cwd=tmp_path)
    origin = yaml.safe_load(proc.stdout)["joints"]["i_j"]["origin"]
    R0, R1 = rpy_matrix(0.5, 0.4, -0.7), rpy_matrix(0.3, -0.2, 0.1)
    np.testing.assert_allclose(origin["xyz"], np.array([1, 2, 3]) + R0 @ [0.1, 0.2, 0.3], atol=1e-15)
    np.testing.assert_allclose(rpy_matrix(*origin["rpy"]), R0 @ R1, atol=1e-15)


# ---------------------------------------------------------------- conditions, variants, dependencies


@pytest.mark.slow
def test_conditions_and_variants_build_one_folder_each(tmp_path):
    recipe = write_recipe(tmp_path, """
        robot: cart
        args:
          gripper: false
          width: 30 cm
        variants:
          small: {width: 20 cm}
          handy: {gripper: true}
        links:
          base: {visual: {box: {size: ["${width}", 0.2, 0.1]}}}
          gripper: {if: "${gripper}", visual: {sphere: {radius: 0.02}}}
        joints:
          grip: {if: "${gripper}", type: fixed, parent: base, child: gripper, origin: {xyz: ["${width / 2}", 0, 0]}}
        """)
    result = build([recipe], tmp_path / "out")
    assert result.robots == ["cart_small", "cart_handy"]
    small = read_urdf(tmp_path / "out/cart_small/urdf/cart_small.urdf")
    handy = read_urdf(tmp_path / "out/cart_handy/urdf/cart_handy.urdf")
    assert set(small.links) == {"base"} and set(handy.links) == {"base", "gripper"}
    assert small.links["base"].mass == pytest.approx(1000 * 0.2 * 0.2 * 0.1, rel=1e-12)
    assert handy.links["base"].mass == pytest.approx(1000 * 0.3 * 0.2 * 0.1, rel=1e-12)
    assert handy.joints["grip"].T_pj[0, 3] == pytest.approx(0.15, abs=1e-15)
    proc = run_cli("expand", recipe, "--variant", "small")
    assert proc.stdout.startswith("# variant small\nrobot: cart_small\n")
    proc = run_cli("expand", recipe, "--variant", "big")
    assert proc.returncode == 2
    assert proc.stderr == f"{recipe}: --variant: no variant named 'big' (variants: small, handy)\n"


def test_a_plain_if_false_drops_the_entry(tmp_path):
    write_recipe(tmp_path, """
        robot: r
        links: {base: {}, spare: {if: false}}
        joints: {j: {if: false, type: fixed, parent: base, child: spare}}
        """)
    proc = run_cli("expand", "robot.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "robot: r\nlinks:\n  base: {}\n"


def test_changing_an_argument_reruns_only_what_reads_it(tmp_path):
    box = trimesh.creation.box([0.1, 0.1, 0.1])
    recipe = write_recipe(tmp_path, """
        robot: r
        args: {arm_mass: 1.0}
        links:
          base: {visual: {mesh: box.stl}}
          arm: {visual: {mesh: box.stl, scale: 0.5}, inertial: {mass: "${arm_mass}"}}
        joints:
          j: {type: revolute, parent: base, child: arm, axis: [0, 0, 1], limit: {lower: -1, upper: 1, effort: 1, velocity: 1}}
        """, meshes={"box.stl": box})
    first = build([recipe], tmp_path / "out")
    assert not build([recipe], tmp_path / "out").ran
    again = build([recipe], tmp_path / "out", args={"arm_mass": "2"})
    # the arm's inertial, the outputs that hold inertials and the scene (it reads the robot: its floor makes
    # room for a robot fixed to the world below z = 0); no mesh work, no metadata file
    assert sorted(again.ran) == ["r:inertial:arm", "r:mjcf", "r:mjcf-scene", "r:report", "r:sdf", "r:urdf",
                                 "r:xacro"]
    assert len(first.ran) > len(again.ran)
    assert read_urdf(tmp_path / "out/r/urdf/r.urdf").links["arm"].mass == 2.0
    assert not build([recipe], tmp_path / "out", args={"arm_mass": "2"}).ran


@pytest.mark.slow
def test_the_no_op_fast_path_sees_arguments_and_part_files(tmp_path):
    (tmp_path / "parts").mkdir()
    part = write_recipe(tmp_path, """
        args: {r: 0.05}
        links: {ball: {visual: {sphere: {radius: "${r}"}}}}
        joints: {fix: {type: fixed, parent: "${parent}", child: ball}}
        """, name="parts/ball.yaml")
    write_recipe(tmp_path, """
        robot: r
        args: {size: 0.1}
        parts: {ball: parts/ball.yaml}
        links: {base: {visual: {box: {size: ["${size}", 0.1, 0.1]}}}}
        instances: {top: {part: ball, parent: base}}
        """)

    def build_says(*extra):
        proc = run_cli("build", "robot.yaml", "--out", "out", *extra, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        return proc.stdout.split(":")[0].split()[0]

    assert build_says() == "built"
    assert build_says() == "out/r"  # "out/r: up to date"
    assert build_says("--arg", "size:=0.2") == "built"
    assert build_says("--arg", "size:=0.2") == "out/r"
    part.write_text(part.read_text().replace("0.05", "0.06"))
    assert build_says("--arg", "size:=0.2") == "built"
    assert read_urdf(tmp_path / "out/r/urdf/r.urdf").links["top_ball"].mass == pytest.approx(
        1000 * 4 / 3 * math.pi * 0.06 ** 3, rel=1e-9)


def test_doit_takes_arguments_for_the_recipes_that_declare_them(tmp_path):
    from robotkit.errors import RobotkitError
    from robotkit.pipeline.tasks import all_tasks

    a = write_recipe(tmp_path, "robot: a\nargs: {size: 0.1}\nlinks: {base: {visual: {sphere: {radius: '${size}'}}}}\n",
                     name="a.yaml")
    b = write_recipe(tmp_path, "robot: b\nlinks: {base: {}}\n", name="b.yaml")
    tasks = all_tasks([a, b], tmp_path / "out", args={"size": "0.2"}, ignore_unknown_args=True)
    assert tasks
    with pytest.raises(RobotkitError) as exc:
        all_tasks([a, b], tmp_path / "out", {"colour": "red"}, ignore_unknown_args=True)
    assert exc.value.lines() == ["--arg colour: unknown argument 'colour': no recipe declares it"]


# ---------------------------------------------------------------- the rewritten examples


@pytest.mark.slow
def test_turtlebot3_burger_written_with_parts_is_the_imported_robot(tmp_path):
    """The hand-written recipe (at most half the xacro's 165 lines) builds the robot the
    imported flat recipe builds, to 1e-9."""
    lines = (RECIPES / "turtlebot3_burger.yaml").read_text().count("\n")
    assert lines <= 165 // 2
    new = build([RECIPES / "turtlebot3_burger.yaml"], tmp_path / "new")
    old = build([REPO / "tests/data/turtlebot3_burger_imported.yaml"], tmp_path / "old")
    assert not new.errors and not old.errors
    name = "turtlebot3_burger/urdf/turtlebot3_burger.urdf"
    assert compare(read_urdf(tmp_path / "new" / name), read_urdf(tmp_path / "old" / name), TOL, configs=100) == []
    a, b = (tmp_path / "new" / name).read_text(), (tmp_path / "old" / name).read_text()
    assert sorted(a.splitlines()) == sorted(b.splitlines())  # the same URDF, links in another order
    # and its flat expansion (Gazebo XML as blocks) builds the very same bytes
    proc = run_cli("expand", RECIPES / "turtlebot3_burger.yaml")
    assert proc.returncode == 0, proc.stderr
    assert "urdf_extras:\n- |-\n  <gazebo reference=\"wheel_left_link\">\n" in proc.stdout
    (tmp_path / "meshes").symlink_to(RECIPES / "meshes")  # the flat recipe names them relative to itself
    flat = tmp_path / "flat.yaml"
    flat.write_text(proc.stdout, encoding="utf-8")
    assert not build([flat], tmp_path / "flat").errors
    assert (tmp_path / "flat" / name).read_text() == a
