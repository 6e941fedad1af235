"""The robotkit command line: argparse only.  Each verb is one module of
:mod:`robotkit.commands` (``run(args)``); a RobotkitError becomes one line per problem and
its exit status (2 for bad input).

A verb's module is imported only when it runs, so ``robotkit --help``, argument errors and a
no-op build stay instant.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from robotkit import __version__
from robotkit.commands.build import cores  # light: the no-op build's own module

# verb -> module of robotkit.commands
COMMANDS = {"build": "build", "world": "world", "schema": "schema", "check": "check", "import": "import_",
            "report": "report", "catalogue": "catalogue", "view": "view", "expand": "expand", "new": "new"}


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # usage errors: exit 2 with one line, like every bad input
        self.print_usage(sys.stderr)
        print(f"robotkit: error: {message}", file=sys.stderr)
        raise SystemExit(2)


def parser() -> argparse.ArgumentParser:
    """Every verb's parser (robotkit --help; the tests read the options of each)."""
    p = _Parser(prog="robotkit", description="Declarative build system for robot description assets.")
    p.add_argument("--version", action="store_true", help="print the version and exit")
    sub = p.add_subparsers(dest="command", parser_class=_Parser)

    _add_build(sub)
    _add_world(sub)
    _add_catalogue(sub)
    _add_check(sub)
    _add_expand(sub)
    _add_import(sub)
    _add_report(sub)
    _add_view(sub)
    _add_new(sub)
    _add_schema(sub)
    return p


def _add_world(sub) -> None:
    w = sub.add_parser("world", help="turn a ROS map_server occupancy map into a Gazebo world and MuJoCo scene",
                       description="Write OUT/<name>/ with model.config, model.sdf, meshes/<name>.stl, "
                                   "<name>.world and scene.xml.")
    w.add_argument("map", metavar="MAP.yaml", help="map_server YAML file")
    w.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    w.add_argument("--name", help="world name (default: the YAML file's stem)")
    w.add_argument("--height", type=float, default=2.0, metavar="H", help="wall height in metres (default: 2.0)")
    w.add_argument("--unknown-as-wall", action="store_true", help="treat unknown cells as walls")
    _add_root_option(w)


def _add_catalogue(sub) -> None:
    k = sub.add_parser("catalogue", help="turn a folder of object meshes into simulation-ready objects",
                       description="Build every STL/OBJ/DAE mesh below DIR (or listed in a text file, one path "
                                   "a line) into OUT/<object>/ (URDF, SDF, MJCF, collision decomposition, mass "
                                   "properties) and write OUT/catalogue.json and OUT/catalogue.csv. A bad mesh is "
                                   "reported and skipped; a rerun builds only what is missing or changed. Exit 0 "
                                   "when every object was made, 1 when some failed, 2 for bad input.")
    k.add_argument("source", metavar="DIR", help="folder of meshes (searched recursively) or a list file")
    k.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    k.add_argument("--density", type=float, default=1000.0, metavar="KG_M3",
                   help="density for objects without a mass in the table (default: 1000)")
    k.add_argument("--masses", metavar="CSV", help="table with columns name (object name or relative path), "
                                                   "mass (kg) and optionally units (m, cm, mm, in)")
    k.add_argument("--units", choices=["m", "cm", "mm", "in"],
                   help="units of every mesh (default: guessed from each mesh's size and reported)")
    k.add_argument("--collision", choices=["decompose", "hull", "box", "cylinder", "sphere", "capsule", "none"],
                   default="decompose", help="collision geometry (default: decompose, CoACD)")
    k.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help="parallel processes (default: the cores; with --scheduler, the cluster's threads)")
    k.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the mesh work to this Dask scheduler (default: $DASK_SCHEDULER_ADDRESS); "
                        "'local' starts one worker per core")


def _add_check(sub) -> None:
    c = sub.add_parser("check", help="validate recipes, build folders, or URDF/SDF/MJCF files",
                       description="Run the validators, the URDF/SDF/MJCF equivalence check and a MuJoCo "
                                   "smoke test. Exit 0 when clean, 1 when problems are found, 2 for bad input "
                                   "(reported in every format too).")
    c.add_argument("paths", nargs="+", metavar="PATH",
                   help="recipe .yaml, build folder, or .urdf/.xacro/.sdf/.xml file")
    c.add_argument("--format", choices=["text", "json", "junit", "github"], default="text",
                   help="report format: text for people, json, junit (CI test reporters), github (annotations)")
    c.add_argument("--fail-on", choices=["error", "warning"], default="error",
                   help="lowest severity that makes the exit status 1 (default: error)")
    c.add_argument("--junit", metavar="FILE", help="also write the JUnit report to FILE (whatever --format says)")
    out = c.add_mutually_exclusive_group()
    out.add_argument("--out", "-o", default="build", metavar="DIR",
                     help="output folder: where a recipe is built (default: build)")
    out.add_argument("--temp-out", action="store_true",
                     help="build recipes in a temporary folder, removed afterwards (pre-commit: never the user's tree)")
    _add_recipe_options(c, "check only this variant of a recipe (default: every variant)", "xacro")
    c.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help=f"build a recipe with N tasks in parallel processes (default: the {cores()} cores this "
                        "process may use)")
    _add_ros_option(c)
    c.add_argument("--no-report", action="store_true",
                   help="do not write a recipe's picture report (<robot>/report/report.html); check draws "
                        "it only for --format github, and keeps one an earlier build wrote; never with --temp-out")
    _add_root_option(c)


def _add_expand(sub) -> None:
    e = sub.add_parser("expand", help="print the flat recipe that a recipe's arguments, expressions, units, "
                                      "parts, conditions and variants expand to",
                       description="Print RECIPE expanded (one YAML document per variant).")
    e.add_argument("recipe", metavar="RECIPE", help="recipe YAML file")
    _add_recipe_options(e, "print only this variant (default: every variant)")
    _add_root_option(e)


def _add_report(sub) -> None:
    r = sub.add_parser("report", help="write a picture report (report.html and its pictures) of a robot",
                       description="Render the robot offscreen (sides, collision, inertia boxes, frames, "
                                   "joints at their limits) and write DIR/report.html with the pictures "
                                   "beside it and a table per link and joint.")
    r.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf/.sdf/.xml file")
    r.add_argument("-o", "--out", metavar="DIR",
                   help="output folder: where report.html and its pictures are written (default: <build "
                        "folder>/report; for a file written elsewhere, <file>-report beside it)")
    r.add_argument("--output", dest="out", help=argparse.SUPPRESS)  # its name before -o/--out meant this
    r.add_argument("--build-dir", default="build", metavar="DIR",
                   help="where a recipe is built first (default: build; -o/--out is the report's folder)")
    _add_recipe_options(r, "report this variant of a recipe (default: its first)", "urdf")
    _add_root_option(r)


def _add_view(sub) -> None:
    v = sub.add_parser("view", help="show the robot in the browser, rebuilt live as its recipe changes",
                       description="Serve a 3D view of the robot (joint sliders, visual/collision/inertia/"
                                   "frame toggles); a recipe is rebuilt on every save.")
    v.add_argument("path", metavar="PATH", help="recipe .yaml, build folder, or .urdf file")
    v.add_argument("--port", type=int, default=8080, metavar="N", help="port to serve on (default: 8080)")
    v.add_argument("--no-browser", action="store_true", help="do not open a web browser")
    v.add_argument("--out", "-o", default="build", metavar="DIR",
                   help="output folder: where a recipe is built (default: build)")
    _add_recipe_options(v, "show only this variant of a recipe (default: every variant)", "urdf")
    _add_root_option(v)


def _add_new(sub) -> None:
    n = sub.add_parser("new", help="write a starter recipe (a link, a joint and a mesh) that builds as written",
                       description="Write NAME.yaml, meshes/NAME/arm.stl and recipe.schema.json (for the editor "
                                   "modeline) into DIR; no existing file is overwritten.")
    n.add_argument("name", metavar="NAME", help="the robot's name (letters, digits, '_', '.', '-')")
    n.add_argument("--dir", "-C", "--out", "-o", default=".", metavar="DIR",
                   help="output folder: the folder to write into (default: .)")


def _add_schema(sub) -> None:
    s = sub.add_parser("schema", help="print the recipe JSON Schema (for editors)",
                       description="Print the JSON Schema of a recipe on stdout, for an editor's completion and "
                                   "checking of keys: save it as recipe.schema.json beside the recipes, whose first "
                                   "line '# yaml-language-server: $schema=recipe.schema.json' points at it (robotkit "
                                   "new writes both). --part prints a part file's schema, --markdown the recipe "
                                   "reference (docs/recipe.md).")
    s.add_argument("--markdown", action="store_true", help="print the recipe reference as Markdown instead")
    s.add_argument("--part", action="store_true", help="print the JSON Schema of a part file instead")


def _package_path(text: str) -> tuple[str, str]:
    name, sep, folder = text.partition("=")
    if not sep or not name or not folder:
        raise argparse.ArgumentTypeError(f"'{text}' is not PKG=DIR")
    return name, folder


def _xacro_arg(text: str) -> tuple[str, str]:
    name, sep, value = text.partition(":=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME:=VALUE")
    return name, value


def _add_import(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "import", help="turn an existing URDF, xacro, MJCF or SDF file (or Gazebo model folder) into a recipe",
        description="Expand FILE (.urdf, or .xacro with $(find PKG) and package://PKG resolved through "
                    "--package-path) and write a recipe that builds into an equivalent URDF. Physical "
                    "inertials are kept as given, the others get --inertia-policy (each stated in a comment "
                    "above its link) unless --recompute-inertials; <gazebo>, <transmission> and other "
                    "elements the recipe cannot express are carried verbatim in urdf_extras. An MJCF (.xml) "
                    "is read through MuJoCo; what the recipe cannot hold is listed (the ledger), and the "
                    "recipe is built and compared with the original in MuJoCo. An SDF (.sdf, or a Gazebo "
                    "model folder with model.config) is read through libsdformat the same way, and compared "
                    "with the rebuilt model.sdf through libsdformat.")
    p.add_argument("file", metavar="FILE", help="URDF, xacro, MJCF (.xml) or SDF (.sdf) file, or a Gazebo model folder")
    p.add_argument("-o", "--out", "--output", dest="output", required=True, metavar="RECIPE.yaml",
                   help="the recipe file written: -o/--out is a file here, the one command whose output is a "
                        "file (the others' -o/--out is a folder); its meshes are referenced from there")
    p.add_argument("--package-path", action="append", type=_package_path, default=[], metavar="PKG=DIR",
                   help="folder of ROS package PKG (repeatable)")
    p.add_argument("--arg", action="append", type=_xacro_arg, default=[], metavar="NAME:=VALUE",
                   help="xacro argument (repeatable)")
    p.add_argument("--inertia-policy", choices=("keep", "repair", "recompute", "estimate"), default=None,
                   help="for each link whose given inertia no real body has: keep it (the import stops on it, "
                        "as the build would), repair it with the smallest change, recompute it from "
                        "the link's geometry or estimate it from its bounding primitive, keeping the mass "
                        "(a link without geometry is repaired); default: repair, and recompute (estimate "
                        "without a closed geometry) where a tensor, given or repaired, does not fit the geometry, "
                        "and compute at the recipe's density a mass that is its geometry's volume at density 1 "
                        "(MeshLab's); keep keeps those too")
    p.add_argument("--recompute-inertials", action="store_true",
                   help="compute every link's inertial from its geometry, physical or not (keeping each "
                        "link's mass, or at --density) and report the difference per link")
    p.add_argument("--density", type=float, metavar="KG_M3",
                   help="with --recompute-inertials: density in kg/m^3 instead of keeping the given masses")
    p.add_argument("--copy-meshes", action="store_true",
                   help="copy every mesh below the recipe's folder (meshes/) instead of referencing them "
                        "(those outside the project, which its build does not read, are always copied)")
    return p


def _recipe_arg(text: str) -> tuple[str, str]:
    name, sep, value = text.partition(":=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"'{text}' is not NAME:=VALUE")
    return name, value


def _add_recipe_options(p: argparse.ArgumentParser, variant_help: str, inputs: str = "") -> None:
    """The options of every command that reads a recipe (build, check, report, view, expand):
    ``--arg`` (dest ``arg``: (name, value) pairs), ``--variant`` (``variant``: a name or None) and
    ``--package-path`` (``package_path``: the raw PKG=DIR texts, read by
    :func:`robotkit.commands.inputs.package_paths`). ``inputs``: "urdf" or "xacro" when the
    command also reads URDF (and xacro) files, the ones package paths are for."""
    p.add_argument("--arg", action="append", type=_recipe_arg, default=[], metavar="NAME:=VALUE",
                   help="set an argument of the recipe (see its args:" + ("; or of a xacro file" if inputs == "xacro"
                                                                        else "") + "; repeatable)")
    p.add_argument("--variant", metavar="NAME", help=f"{variant_help}; see the recipe's variants:")
    where = {"urdf": "the package://PKG/ meshes of a URDF", "xacro": "the package://PKG/ meshes of a URDF, "
             "$(find PKG) in a xacro file"}.get(inputs, "package://PKG/ in a URDF given to check, report or view")
    p.add_argument("--package-path", action="append", default=[], metavar="PKG=DIR",
                   help=f"folder of ROS package PKG: {where} (repeatable); a recipe names its files by path, "
                        "relative to itself, and needs none")


def _add_ros_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--ros", choices=["ros1", "ros2"], help="build the ROS package for this ROS (overrides the "
                                                           "recipes' `ros` key)")


ROOT_ENV = "ROBOTKIT_ROOT"  # robotkit.paths.ROOT_ENV, not imported: the no-op build stays light


def _add_root_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--root", action="append", default=[], metavar="DIR",
                   help="also read files below DIR (repeatable; default: only the recipe's repository and "
                        "ROBOTKIT_ROOT)")


def _widen_roots(roots: list[str]) -> None:
    """``--root DIR``: widen the reads on purpose (robotkit.paths), also for worker processes."""
    if roots:
        old = [p for p in os.environ.get(ROOT_ENV, "").split(os.pathsep) if p]
        os.environ[ROOT_ENV] = os.pathsep.join(dict.fromkeys([os.path.abspath(r) for r in roots] + old))


def _add_build(sub) -> None:
    b = sub.add_parser("build", help="build recipes into URDF, Gazebo model folders and meshes",
                       description="Build each RECIPE into OUT/<robot>/ (incremental: only what changed reruns).")
    b.add_argument("recipes", nargs="+", metavar="RECIPE", help="recipe YAML file(s)")
    b.add_argument("--out", "-o", default="build", metavar="DIR", help="output folder (default: build)")
    _add_recipe_options(b, "build only this variant of each recipe (default: every variant)")
    b.add_argument("-j", "--jobs", type=int, default=None, metavar="N",
                   help=f"run N tasks in parallel processes (default: the {cores()} cores this process may use; "
                        "with --scheduler, the cluster's threads)")
    b.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the expensive mesh work (CoACD, hulls, decimation) to this Dask scheduler "
                        "(default: $DASK_SCHEDULER_ADDRESS); 'local' starts one worker per core")
    b.add_argument("-v", "--verbose", action="store_true", help="name every task that runs")
    _add_ros_option(b)
    b.add_argument("--moveit", action="store_true",
                   help="also write the MoveIt 2 configuration (config/moveit/, launch/moveit.launch.py) of every "
                        "robot (as the recipes' `moveit: true`)")
    b.add_argument("--no-report", action="store_true",
                   help="do not write the picture report (<robot>/report/report.html)")
    _add_root_option(b)


def build_parser() -> argparse.ArgumentParser:
    """Only ``build``: a no-op build does not import the other commands' modules."""
    p = _Parser(prog="robotkit", description="Declarative build system for robot description assets.")
    p.add_argument("--version", action="store_true", help="print the version and exit")
    _add_build(p.add_subparsers(dest="command", parser_class=_Parser))
    return p


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = (build_parser() if argv[:1] == ["build"] else parser()).parse_args(argv)
    if args.version:
        print(f"robotkit {__version__}")
        return 0
    if args.command is None:
        parser().print_help()
        return 2
    _widen_roots(getattr(args, "root", []))
    try:
        return importlib.import_module(f"robotkit.commands.{COMMANDS[args.command]}").run(args)
    except Exception as exc:
        from robotkit.errors import RobotkitError  # imported late: dataclasses costs a no-op build 10 ms

        if not isinstance(exc, RobotkitError):
            raise
        for line in exc.lines():
            print(line, file=sys.stderr)
        return exc.exit_status
    except KeyboardInterrupt:
        print("robotkit: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
