"""One option set for every command: the recipe options (--arg, --variant, --package-path) on
every verb that reads a recipe, -o/--out the output folder everywhere (import's recipe file the
one stated exception), and check building a recipe as build does (--ros, -j, --no-report)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from robotkit.cli import build_parser, parser
from tests.conftest import RECIPES, run_cli, write_recipe

RECIPE_VERBS = ("build", "check", "report", "view", "expand")
QUADRUPED = RECIPES / "quadruped.yaml"
UNKNOWN = (f"{QUADRUPED.relative_to(RECIPES.parent)}: --variant: no variant named 'explorr' "
           "(did you mean 'explorer'? variants: compact, explorer)\n")


def verbs(p: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def options(p: argparse.ArgumentParser) -> dict[str, str]:
    """Option string -> dest."""
    return {s: a.dest for a in p._actions for s in a.option_strings}


def cart(folder: Path) -> Path:
    """A recipe with two variants, primitives only (builds in a second)."""
    return write_recipe(folder, """
        robot: cart
        args:
          width: 30 cm
          height: 10 cm
        variants:
          small: {width: 20 cm}
          wide: {width: 40 cm}
        links:
          base: {visual: {box: {size: ["${width}", 0.2, "${height}"]}}}
        metadata: {maintainers: [{name: A, email: a@example.org}]}
        """, name="cart.yaml")


@pytest.mark.parametrize("verb", RECIPE_VERBS)
def test_every_verb_that_reads_a_recipe_has_the_recipe_options(verb):
    p = verbs(parser())[verb]
    assert {s: d for s, d in options(p).items() if s in ("--arg", "--variant", "--package-path")} == {
        "--arg": "arg", "--variant": "variant", "--package-path": "package_path"}
    first = {"build": ["r.yaml"], "check": ["r.yaml"], "report": ["r.yaml"], "view": ["r.yaml"], "expand": ["r.yaml"]}
    args = p.parse_args([*first[verb], "--arg", "a:=1", "--arg", "b:=", "--variant", "v",
                         "--package-path", "pkg=dir"])
    assert (args.arg, args.variant, args.package_path) == ([("a", "1"), ("b", "")], "v", ["pkg=dir"])
    args = p.parse_args(first[verb])
    assert (args.arg, args.variant, args.package_path) == ([], None, [])


def test_the_fast_build_parser_has_the_same_build_options():
    """``robotkit build`` parses with its own light parser: the same options as in the full one."""
    assert options(verbs(build_parser())["build"]) == options(verbs(parser())["build"])


def test_o_and_out_are_the_output_everywhere():
    every = verbs(parser())
    for verb in ("build", "world", "catalogue", "check", "report", "view", "new"):
        opts = options(every[verb])
        assert opts["-o"] == opts["--out"], verb
    report = every["report"].parse_args(["r.yaml", "-o", "pages", "--build-dir", "b"])
    assert (report.out, report.build_dir) == ("pages", "b")
    assert every["report"].parse_args(["r.yaml", "--output", "pages"]).out == "pages"  # the old name, hidden
    assert "--output" not in every["report"].format_help()
    assert every["report"].parse_args(["r.yaml"]).build_dir == "build"
    imp = every["import"]
    assert options(imp)["-o"] == options(imp)["--out"] == options(imp)["--output"] == "output"
    assert "the one command whose output is a file" in " ".join(imp.format_help().split())
    for verb in ("build", "check"):
        opts = options(every[verb])
        assert {opts["-j"], opts["--jobs"], opts["--ros"], opts["--no-report"]} == {"jobs", "ros", "no_report"}


def test_schema_help_has_a_description():
    assert "JSON Schema" in (verbs(parser())["schema"].description or "")


@pytest.mark.parametrize("verb", ("build", "check", "report", "expand"))
def test_an_unknown_variant_is_bad_input_naming_the_ones_there_are(verb, tmp_path):
    proc = run_cli(verb, QUADRUPED.relative_to(RECIPES.parent), "--variant", "explorr", *(
        ["-o", tmp_path / "out"] if verb != "expand" else []), cwd=RECIPES.parent)
    assert (proc.returncode, proc.stderr, proc.stdout) == (2, UNKNOWN, "")
    assert not (tmp_path / "out").exists()  # nothing half-written


def test_a_variant_of_a_recipe_without_variants(tmp_path):
    recipe = write_recipe(tmp_path, "robot: plain\nlinks:\n  base: {visual: {box: {size: [0.1, 0.1, 0.1]}}}\n")
    proc = run_cli("build", recipe, "--variant", "small", "-o", tmp_path / "out")
    assert (proc.returncode, proc.stderr) == (2, f"{recipe}: --variant: no variant named 'small' "
                                                 "(the recipe has no variants)\n")


def test_build_variant_builds_only_that_variant(tmp_path):
    recipe = cart(tmp_path)
    out = tmp_path / "out"
    proc = run_cli("build", recipe, "--variant", "small", "-o", out, "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert re.fullmatch(r"built \S*out/cart_small: \d+ tasks run, 0 up to date \(\d+\.\d\d s\)\n", proc.stdout)
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["cart_small"]
    assert '<box size="0.2 0.2 0.1"/>' in (out / "cart_small/urdf/cart_small.urdf").read_text()
    # the no-op stamp knows the variant: the whole recipe is another build
    proc = run_cli("build", recipe, "-o", out, "--no-report")
    assert proc.returncode == 0, proc.stderr
    assert re.match(r"built \S*out/cart_small, \S*out/cart_wide: ", proc.stdout), proc.stdout
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["cart_small", "cart_wide"]
    proc = run_cli("build", recipe, "--variant", "small", "-o", out, "--no-report")
    assert "cart_small: up to date" in proc.stdout


def test_a_malformed_package_path_is_bad_input_on_every_verb(tmp_path):
    recipe = cart(tmp_path)
    for verb in ("build", "check", "report", "expand"):
        proc = run_cli(verb, recipe, "--package-path", "nodir", *(["-o", tmp_path / "out"] if verb != "expand" else []))
        assert (proc.returncode, proc.stderr) == (2, "robotkit: error: --package-path takes PKG=DIR (got 'nodir')\n")
    assert not (tmp_path / "out").exists()
    proc = run_cli("check", recipe, "-j", "0")
    assert (proc.returncode, proc.stderr) == (2, "robotkit: error: -j must be at least 1\n")


def test_package_paths_are_harmless_for_a_recipe(tmp_path):
    recipe = cart(tmp_path)
    proc = run_cli("expand", recipe, "--variant", "wide", "--package-path", f"cart={tmp_path}")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("# variant wide\nrobot: cart_wide\n")


@pytest.mark.slow
def test_report_o_is_the_report_folder_and_build_dir_the_build(tmp_path):
    recipe = cart(tmp_path)
    proc = run_cli("report", recipe, "-o", tmp_path / "pages", "--build-dir", tmp_path / "b", "--variant", "wide",
                   "--arg", "height:=5 cm", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert re.fullmatch(r"wrote \S*pages/report\.html \(\d+\.\d\d s\)\n", proc.stdout), proc.stdout
    assert "<title>cart_wide: robotkit report</title>" in (tmp_path / "pages" / "report.html").read_text()
    assert sorted(p.name for p in (tmp_path / "b").iterdir() if not p.name.startswith(".")) == ["cart_wide"]
    assert '<box size="0.4 0.2 0.05"/>' in (tmp_path / "b/cart_wide/urdf/cart_wide.urdf").read_text()
    assert not (tmp_path / "build").exists()  # the default build folder, in the working folder, is not used


@pytest.mark.slow
@pytest.mark.consumers
def test_check_builds_a_recipe_as_build_does(tmp_path):
    """--variant, --ros, -j and --no-report reach check's build; check draws no picture report
    of its own, but keeps the one a build wrote (a check after a build rebuilds nothing)."""
    recipe = cart(tmp_path)
    out = tmp_path / "out"
    proc = run_cli("check", recipe, "-o", out, "--variant", "small", "--ros", "ros1", "-j", "2", "--no-report",
                   "--format", "json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["cart_small"]
    assert "<buildtool_depend>catkin</buildtool_depend>" in (out / "cart_small/package.xml").read_text()
    assert not (out / "cart_small/report").exists()
    proc = run_cli("check", recipe, "-o", out, "--variant", "small", "--format", "json")
    assert not (out / "cart_small/report").exists()  # not drawn for a check
    proc = run_cli("build", recipe, "-o", out, "--variant", "small")
    assert (out / "cart_small/report/report.html").is_file()
    proc = run_cli("check", recipe, "-o", out, "--variant", "small", "--format", "json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (out / "cart_small/report/report.html").is_file()  # kept: the same build as build's
