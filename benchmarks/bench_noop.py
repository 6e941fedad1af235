"""No-op build, whole process: robotkit against doit and xacro, on generated N-link robots.

For each N (default 50 and 1000) the script writes, in a temporary folder:

- ``robot.yaml``: an N-link robot, arms of 10 links in series hanging off the first link
  (every other link a box, the others a shared STL mesh, revolute joints with limits and
  dynamics; ``--serial``: one chain in series, whose MJCF a 1000-link robot cannot have); it is
  built once with
  ``robotkit build``, so the following builds have nothing to do;
- ``dodo.py``: N trivial doit tasks, each copying one small file to another (file_dep
  and targets), run once, so ``doit`` then finds every task up to date: the cost of
  the build tool robotkit runs on;
- ``robot.urdf.xacro``: the same chain as xacro macros (one macro call per link and
  joint), expanded by the ``xacro`` command to a URDF: what a user otherwise runs on
  every launch.

Then ``--repeat`` rounds, each timing one whole process of each command in turn
(``time.perf_counter`` around ``subprocess.run``), so the three share the load of the
moment; prints the medians and the ratios robotkit / doit and robotkit / xacro, and
the load average.  ``python benchmarks/bench_noop.py [--links 50 1000] [--repeat 15] [--serial]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
MESH = REPO / "recipes" / "meshes" / "turret_bot" / "slider.stl"


SERIAL = False
"""``--serial``: one chain of N links in series (deeper than MuJoCo's 496 nested bodies at 1000: the
build leaves the MJCF out, a stated loss, and records its no-op like any other)."""


def parent(i: int) -> int:
    """Arms of 10 links in series, each hanging off link 0 (``--serial``: link i-1)."""
    return i - 1 if SERIAL or i % 10 != 1 else 0


def recipe(n: int) -> str:
    lines = ["robot: chain", "units: m", "density: 1000", "links:"]
    for i in range(n):
        if i % 2:
            lines.append(f"  l{i}: {{visual: {{mesh: slider.stl}}}}")
        else:
            lines.append(f"  l{i}: {{visual: {{box: {{size: [0.1, 0.1, 0.2]}}}}}}")
    lines.append("joints:")
    for i in range(1, n):
        lines += [f"  j{i}:", "    type: revolute", f"    parent: l{parent(i)}", f"    child: l{i}",
                  "    origin: {xyz: [0, 0, 0.2]}", "    axis: [0, 0, 1]",
                  "    limit: {lower: -1.5, upper: 1.5, effort: 10, velocity: 2}",
                  "    dynamics: {damping: 0.01, friction: 0.01}"]
    return "\n".join(lines) + "\n"


def dodo(n: int) -> str:
    return f'''import shutil
DOIT_CONFIG = {{"verbosity": 0, "dep_file": ".doit.db", "backend": "sqlite3"}}
def task_copy():
    for i in range({n}):
        yield {{"name": str(i), "file_dep": [f"in/{{i}}.txt"], "targets": [f"out/{{i}}.txt"],
               "actions": [(shutil.copyfile, (f"in/{{i}}.txt", f"out/{{i}}.txt"))]}}
'''


def xacro_file(n: int) -> str:
    out = ['<?xml version="1.0"?>', '<robot name="chain" xmlns:xacro="http://www.ros.org/wiki/xacro">',
           '  <xacro:property name="density" value="1000"/>',
           '  <xacro:macro name="box_link" params="name">',
           '    <link name="${name}"><visual><geometry><box size="0.1 0.1 0.2"/></geometry></visual>',
           '      <inertial><mass value="${density*0.1*0.1*0.2}"/>',
           '        <inertia ixx="${density*0.002*(0.01+0.04)/12}" ixy="0" ixz="0" iyy="${density*0.002*(0.01+0.04)/12}" '
           'iyz="0" izz="${density*0.002*(0.02)/12}"/></inertial></link>',
           '  </xacro:macro>',
           '  <xacro:macro name="mesh_link" params="name">',
           '    <link name="${name}"><visual><geometry><mesh filename="package://chain/slider.stl"/></geometry></visual>',
           '      <inertial><mass value="1.0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'
           '</inertial></link>',
           '  </xacro:macro>',
           '  <xacro:macro name="joint" params="name parent child">',
           '    <joint name="${name}" type="revolute"><parent link="${parent}"/><child link="${child}"/>',
           '      <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 0 1"/>',
           '      <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>'
           '<dynamics damping="0.01" friction="0.01"/></joint>',
           '  </xacro:macro>']
    for i in range(n):
        out.append(f'  <xacro:{"mesh_link" if i % 2 else "box_link"} name="l{i}"/>')
    for i in range(1, n):
        out.append(f'  <xacro:joint name="j{i}" parent="l{parent(i)}" child="l{i}"/>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def run(cmd, cwd, env=None) -> float:
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, cmd))} failed ({p.returncode}):\n{p.stderr}")
    return dt


def setup(root: Path, n: int) -> dict:
    root.mkdir(parents=True)
    (root / "robot.yaml").write_text(recipe(n))
    shutil.copy(MESH, root / "slider.stl")
    (root / "robot.urdf.xacro").write_text(xacro_file(n))
    d = root / "doit"
    (d / "in").mkdir(parents=True)
    (d / "out").mkdir()
    for i in range(n):
        (d / "in" / f"{i}.txt").write_text(f"{i}\n")
    (d / "dodo.py").write_text(dodo(n))
    env = {**os.environ, "ROBOTKIT_CACHE": str(root / "cache")}
    cmds = {
        "robotkit": ([str(BIN / "robotkit"), "build", "robot.yaml", "--out", "build"], root),
        "doit": ([str(BIN / "doit")], d),
        "xacro": ([str(BIN / "xacro"), "robot.urdf.xacro", "-o", "robot.urdf"], root),
    }
    t0 = time.perf_counter()
    run(cmds["robotkit"][0], root, env)
    first = time.perf_counter() - t0
    run(cmds["doit"][0], d, env)
    return {"cmds": cmds, "env": env, "first_build": first}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, nargs="+", default=[50, 1000])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--serial", action="store_true", help="one chain of N links in series")
    args = ap.parse_args()
    global SERIAL
    SERIAL = args.serial
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start; "
          f"medians of {args.repeat} rounds (one process of each command per round)")
    print(f"{'links':>6} {'first build':>11} {'robotkit no-op':>15} {'doit no-op':>11} {'xacro':>8} "
          f"{'robotkit/doit':>14} {'robotkit/xacro':>15}")
    with tempfile.TemporaryDirectory(prefix="bench_noop.") as tmp:
        for n in args.links:
            s = setup(Path(tmp) / f"n{n}", n)
            times = {k: [] for k in s["cmds"]}
            rk_ratio, xa_ratio = [], []
            for _ in range(args.repeat):
                got = {k: run(cmd, cwd, s["env"]) for k, (cmd, cwd) in s["cmds"].items()}
                for k, v in got.items():
                    times[k].append(v)
                rk_ratio.append(got["robotkit"] / got["doit"])
                xa_ratio.append(got["robotkit"] / got["xacro"])
            med = {k: statistics.median(v) for k, v in times.items()}
            print(f"{n:>6} {s['first_build']:>10.2f}s {med['robotkit']:>14.3f}s {med['doit']:>10.3f}s "
                  f"{med['xacro']:>7.3f}s {statistics.median(rk_ratio):>14.2f} {statistics.median(xa_ratio):>15.2f}",
                  flush=True)
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
