"""Parts: named, parametrised groups of links, joints, sensors and actuators.

An instance (``instances: {NAME: {part, parent, origin, args, prefix, mirror, if}}``)
evaluates the part's body with its arguments, prefixes every name the part
defines (default ``NAME_``), places the joints and sensors whose parent is
``${parent}`` at ``origin`` in the parent link, and, with ``mirror: xz`` (or
``yz``, ``xy``), reflects the whole placed part across that plane of the parent.

Mirroring with M the reflection (diag with one -1): every pose (R, p) becomes
(M R M, M p), which is a proper rotation, so each mirrored frame is a right-
handed frame; geometry is reflected in its link frame (mesh scale times M, so
mesh winding is flipped where meshes are loaded); explicit inertials become
com' = M com and I' = M I M.  A revolute axis a becomes -M a (the mirror image of
the motion at the same joint value), a prismatic axis M a; when that axis would
point against the original (axes lying in the mirror plane: roll and yaw joints
for ``xz``), the original direction is kept and the joint value negated instead:
limits [lower, upper] become [-upper, -lower] and mimic gains follow.
"""

from __future__ import annotations

import difflib
import math
import os
from pathlib import Path

from robotkit.errors import display_path
from robotkit.geometry import matrix_rpy, rpy_rows
from robotkit.recipe import schema
from robotkit.recipe.expand.language import (
    ITEM_SECTIONS, WHOLE_RE, Source, bind_args, declare_args, declare_values, dotted, evaluate_tree, keep,
)
from robotkit.recipe.expand.units import convert_tree

INSTANCE_KEYS = ("part", "parent", "origin", "args", "prefix", "mirror", "if")
PART_KEYS = ("description", "args", "values", "parts", "links", "joints", "sensors", "actuators", "instances")
MIRRORS = {"yz": 0, "xz": 1, "xy": 2}  # the plane -> the axis the reflection flips
UNIT_FACTORS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}  # as robotkit.recipe.schema.UNITS


MODELS = {"links": schema.Link, "joints": schema.Joint, "sensors": schema.Sensor, "actuators": schema.Actuator}
"""The schema model of each item section (quantities in an instance are converted by it)."""


def expand_instances(block, src: Source, scope: dict, parts_env: list, ctx, flat: dict, items: dict,
                     default_units: str, chain: tuple):
    """Expand every instance of ``block`` into the sections of ``flat`` (and ``items``: where each came from)."""
    if block is None:
        return
    if not isinstance(block, dict):
        ctx.report(src, (), f"must be a mapping of instance names to instances (got {block!r})")
        return
    for name, spec in block.items():
        _instance(name, spec, src.sub(name), scope, parts_env, ctx, flat, items, default_units, chain)


def _find_part(part: str, parts_env: list, ctx):
    """(body, body Source, defining scope, parts environment inside the body) or None."""
    for block, bsrc, def_scope, def_file in parts_env:
        if not isinstance(block, dict) or part not in block:
            continue
        definition = block[part]
        if isinstance(definition, str):
            file, _ = bsrc.locate((part,))
            path = os.path.normpath(str(Path(file or def_file).parent / definition))
            if path not in ctx.part_files:
                why = ctx.reads.refusal(path) if ctx.reads is not None else None
                if why is not None:
                    ctx.report(bsrc, (part,), f"part file '{definition}' {why}")
                    ctx.part_files[path] = (None, {})
                elif not os.path.isfile(path):
                    ctx.report(bsrc, (part,), f"part file '{definition}' does not exist")
                    ctx.part_files[path] = (None, {})
                else:
                    ctx.part_files[path] = ctx.read_yaml(Path(path), ctx.problems)
            data, marks = ctx.part_files[path]
            if data is None:
                return None
            body_src = Source(marks)
            if not isinstance(data, dict):
                ctx.report(body_src, (), "a part file must be a mapping of keys")
                return None
            return data, body_src, {}, [(data.get("parts"), body_src.sub("parts"), {}, path)]
        if not isinstance(definition, dict):
            ctx.report(bsrc, (part,), f"a part is a mapping (links, joints, ...) or a file name (got {definition!r})")
            return None
        body_src = bsrc.sub(part)
        return definition, body_src, def_scope, [(definition.get("parts"), body_src.sub("parts"), def_scope,
                                                  def_file)] + parts_env
    return None


def _instance(name, spec, isrc: Source, scope, parts_env, ctx, flat, items, default_units, chain):
    """Expand one instance into ``flat``: its spec checked, its part found, the part's body
    evaluated with the instance's arguments (nested instances too), then its items renamed,
    placed at the parent, mirrored and merged."""
    spec = evaluate_tree(spec, scope, ctx, isrc)
    checked = _checked_spec(name, spec, isrc, ctx)
    if checked is None:
        return
    prefix, mirror, pose = checked
    found = _find_part(spec["part"], parts_env, ctx)
    if found is None:
        _report_unknown_part(spec["part"], parts_env, isrc, ctx)
        return
    body, bsrc, def_scope, env = found
    file, line = isrc.locate(())
    chain = chain + (f"{name} at {display_path(file)}:{line}",)
    bsrc = Source(bsrc.where, bsrc.prefix, f" (in instance {' > '.join(chain)})")
    for key in body:
        if key not in PART_KEYS:
            ctx.report(bsrc, (key,), f"unknown key (expected one of: {', '.join(PART_KEYS)})")
    pscope = _part_scope(spec, body, bsrc, def_scope, prefix, isrc, ctx)
    args = spec.get("args") if isinstance(spec.get("args"), dict) else {}
    given = {"parent": ("parent",)} | {a: ("args", a) for a in args}
    given = {n: (*isrc.locate(rel), dotted(isrc.prefix + rel), isrc.via) for n, rel in given.items()}
    local, local_items = _part_items(body, bsrc, pscope, ctx, given, spec["part"])
    expand_instances(body.get("instances"), bsrc.sub("instances"), pscope, env, ctx, local, local_items,
                     default_units, chain)
    renamed = _rename(local, prefix)
    _attach(renamed, spec["part"], spec["parent"], pose, isrc, ctx)
    if mirror is not None:
        _mirror(renamed, MIRRORS[mirror], default_units, set(renamed["joints"]))
    _merge(renamed, local_items, flat, items, isrc, ctx)


def _checked_spec(name, spec, isrc: Source, ctx):
    """(prefix, mirror, pose) of an evaluated instance spec, or None when it is not usable (the
    problems reported) or its ``if:`` is false."""
    if not isinstance(spec, dict):
        ctx.report(isrc, (), f"an instance is a mapping with 'part' and 'parent' (got {spec!r})")
        return None
    if not keep(spec, ctx, isrc, ()):
        return None
    bad = False
    for key in spec:
        if key not in INSTANCE_KEYS:
            close = difflib.get_close_matches(str(key), INSTANCE_KEYS, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else f" (expected one of: {', '.join(INSTANCE_KEYS)})"
            ctx.report(isrc, (key,), "unknown key" + hint)
            bad = True
    for key in ("part", "parent"):
        if not isinstance(spec.get(key), str):
            ctx.report(isrc, (key,) if key in spec else (), "required key is missing" if key not in spec
                       else f"must be a name (got {spec[key]!r})")
            bad = True
    mirror = spec.get("mirror")
    if mirror is not None and (not isinstance(mirror, str) or mirror not in MIRRORS):
        ctx.report(isrc, ("mirror",), f"must be one of xz, yz, xy (got {mirror!r})")
        bad = True
    prefix = spec.get("prefix", f"{name}_")
    if not isinstance(prefix, str):
        ctx.report(isrc, ("prefix",), f"must be text (got {prefix!r})")
        bad = True
    origin = spec.get("origin") or {}
    if not isinstance(origin, dict) or any(k not in ("xyz", "rpy") for k in origin):
        ctx.report(isrc, ("origin",), "must be a mapping with xyz and rpy")
        bad = True
    if bad:
        return None
    pose = _instance_pose(origin, isrc, ctx)
    return None if pose is None else (prefix, mirror, pose)


def _instance_pose(origin: dict, isrc: Source, ctx):
    """[xyz, rpy] of an instance's ``origin`` (quantities converted), or None (reported)."""
    convert_tree(origin, schema.Origin, (), None, lambda p, m: ctx.report(isrc, ("origin",) + p, m))
    pose = []
    for key in ("xyz", "rpy"):
        v = origin.get(key, [0, 0, 0])
        if not (isinstance(v, list) and len(v) == 3 and all(_is_num(x) for x in v)):
            ctx.report(isrc, ("origin", key), f"must be 3 numbers (got {v!r})")
            return None
        pose.append([float(x) for x in v])
    return pose


def _report_unknown_part(part: str, parts_env: list, isrc: Source, ctx):
    """'no part named' with a did-you-mean, unless the part exists and its own problem is reported."""
    if any(isinstance(b, dict) and part in b for b, *_ in parts_env):
        return
    known = sorted({k for b, *_ in parts_env if isinstance(b, dict) for k in b})
    close = difflib.get_close_matches(part, known, n=1)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    ctx.report(isrc, ("part",), f"no part named '{part}'{hint}")


def _part_scope(spec: dict, body: dict, bsrc: Source, def_scope: dict, prefix: str, isrc: Source, ctx) -> dict:
    """The names the part's body sees: its defining scope, its arguments bound to the instance's
    ``args``, ``parent``, ``prefix`` and its own ``values``."""
    declared = declare_args(body.get("args"), def_scope, ctx, bsrc.sub("args"))
    given = spec.get("args") or {}
    if not isinstance(given, dict):
        ctx.report(isrc, ("args",), f"must be a mapping of argument values (got {given!r})")
        given = {}
    values = bind_args(declared, given, ctx, f"part '{spec['part']}'", lambda n: (isrc, ("args", n)),
                       from_text=False)
    pscope = {**def_scope, **values, "parent": spec["parent"], "prefix": prefix}
    return declare_values(body.get("values"), pscope, ctx, bsrc.sub("values"))


def _part_items(body: dict, bsrc: Source, pscope: dict, ctx, given: dict, part: str) -> tuple[dict, dict]:
    """The part's own items evaluated in ``pscope`` (those whose ``if:`` holds), by section, and
    where each was written: (source, key path, redirects).  ``given``: {name: (file, line, key,
    the instance's own chain of instances)} of what the instance gives (``parent``, its ``args``); a key whose whole value is ``${name}``
    of one of them is redirected there (a problem with that value is the instance's)."""
    local = {s: {} for s in ITEM_SECTIONS}
    local_items: dict = {}
    for section in ITEM_SECTIONS:
        block = body.get(section)
        if block is None:
            continue
        if not isinstance(block, dict):
            ctx.report(bsrc, (section,), f"must be a mapping of names (got {block!r})")
            continue
        for n, item in block.items():
            isrc_item = bsrc.sub(section, n)
            redirects = _redirects(item, given, isrc_item, part)
            item = evaluate_tree(item, pscope, ctx, isrc_item)
            if not keep(item, ctx, isrc_item, ()):
                continue
            if isinstance(item, dict):
                convert_tree(item, MODELS[section], (), None, lambda p, m, s=isrc_item: ctx.report(s, p, m))
            local[section][n] = item if item is not None else {}
            local_items[(section, n)] = (bsrc, bsrc.prefix + (section, n), redirects)
    return local, local_items


def _redirects(node, given: dict, src: Source, part: str, rel=()) -> dict:
    """{key path in the item: (file, line, key, note)} of the keys of ``node`` whose whole value is
    ``${name}`` of a name in ``given``: the instance's line, and a note naming the part's."""
    if isinstance(node, dict):
        return {k: v for key, sub in node.items() for k, v in _redirects(sub, given, src, part, rel + (key,)).items()}
    if isinstance(node, list):
        return {k: v for i, sub in enumerate(node) for k, v in _redirects(sub, given, src, part, rel + (i,)).items()}
    m = WHOLE_RE.match(node) if isinstance(node, str) else None
    if m is None or m.group(1).strip() not in given:
        return {}
    file, line = src.locate(rel)
    where = f"{display_path(file)}:{line}: " if file is not None else ""
    ifile, iline, ikey, chain = given[m.group(1).strip()]
    return {rel: (ifile, iline, ikey, f" (via part '{part}': {where}{dotted(src.prefix + rel)}){chain}")}


def _attach(renamed: dict, part: str, parent: str, pose, isrc: Source, ctx):
    """Place the joints and sensors whose parent is the instance's ``parent`` at its pose; a
    part with links and nothing attached is a problem."""
    attached = False
    for j in renamed["joints"].values():
        if isinstance(j, dict) and j.get("parent") == parent and parent not in renamed["links"]:
            j["origin"] = _compose(pose, j.get("origin"))
            attached = True
    for s in renamed["sensors"].values():
        if isinstance(s, dict) and s.get("parent") == parent and parent not in renamed["links"]:
            s["origin"] = _compose(pose, s.get("origin"))
            attached = True
    if not attached and renamed["links"]:
        ctx.report(isrc, ("parent",), f"no joint of part '{part}' has parent ${{parent}}: the instance "
                                      "would not be attached to link '" + parent + "'")


def _merge(renamed: dict, local_items: dict, flat: dict, items: dict, isrc: Source, ctx):
    """The instance's renamed items into ``flat`` (a name that exists already is a problem)."""
    for section in ITEM_SECTIONS:
        target = flat.setdefault(section, {})
        if not isinstance(target, dict):
            continue
        for n, item in renamed[section].items():
            old = renamed["_old"][(section, n)]
            if n in target:
                ctx.report(isrc, (), f"defines {section[:-1]} '{n}', which already exists")
                continue
            target[n] = item
            items[(section, n)] = local_items[(section, old)]


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _rename(local: dict, prefix: str) -> dict:
    links = set(local["links"])
    for s, spec in local["sensors"].items():
        frame = spec.get("frame") if isinstance(spec, dict) else None
        links.add(frame if isinstance(frame, str) else f"{s}_link")
    joints = set(local["joints"])
    out = {s: {} for s in ITEM_SECTIONS}
    old = {}

    def link(v):
        return prefix + v if isinstance(v, str) and v in links else v

    for n, item in local["links"].items():
        out["links"][prefix + n] = item
        old[("links", prefix + n)] = n
    for n, j in local["joints"].items():
        if isinstance(j, dict):
            for key in ("parent", "child"):
                if key in j:
                    j[key] = link(j[key])
            mimic = j.get("mimic")
            if isinstance(mimic, dict) and mimic.get("joint") in joints:
                mimic["joint"] = prefix + mimic["joint"]
        out["joints"][prefix + n] = j
        old[("joints", prefix + n)] = n
    for n, s in local["sensors"].items():
        if isinstance(s, dict):
            if "parent" in s:
                s["parent"] = link(s["parent"])
            if isinstance(s.get("frame"), str):
                s["frame"] = prefix + s["frame"]
        out["sensors"][prefix + n] = s
        old[("sensors", prefix + n)] = n
    for n, a in local["actuators"].items():
        new = prefix + n if n in joints else n
        out["actuators"][new] = a
        old[("actuators", new)] = n
    out["_old"] = old
    return out


# ---------------------------------------------------------------- poses


def _compose(pose, origin):
    """The instance pose (xyz, rpy) followed by a joint's own origin: exact when either is a pure translation."""
    xyz0, rpy0 = pose
    if not isinstance(origin, dict):
        origin = {}
    xyz1, rpy1 = origin.get("xyz", [0, 0, 0]), origin.get("rpy", [0, 0, 0])
    values = [xyz0, rpy0, xyz1, rpy1]
    if not all(isinstance(v, (list, tuple)) and len(v) == 3 and all(_is_num(x) and math.isfinite(x) for x in v)
               for v in values):
        return origin  # the schema reports it
    if not any(rpy0):
        return {"xyz": [a + b for a, b in zip(xyz0, xyz1)], "rpy": list(rpy1)}
    R0 = rpy_rows(rpy0)
    xyz = [xyz0[i] + sum(R0[i][k] * xyz1[k] for k in range(3)) for i in range(3)]
    if not any(rpy1):
        return {"xyz": xyz, "rpy": list(rpy0)}
    R1 = rpy_rows(rpy1)
    R = [[sum(R0[i][k] * R1[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return {"xyz": xyz, "rpy": list(matrix_rpy(R))}


def _neg(x):
    return -x if x else x  # no -0.0


def _mirror_pose(origin, k):
    if not isinstance(origin, dict):
        return origin
    out = dict(origin)
    xyz, rpy = origin.get("xyz"), origin.get("rpy")
    if isinstance(xyz, list) and len(xyz) == 3 and all(_is_num(v) for v in xyz):
        out["xyz"] = [_neg(v) if i == k else v for i, v in enumerate(xyz)]
    if isinstance(rpy, list) and len(rpy) == 3 and all(_is_num(v) for v in rpy):
        out["rpy"] = [v if i == k else _neg(v) for i, v in enumerate(rpy)]
    return out


def _mirror_geoms(value, k, default_units):
    if isinstance(value, list):
        return [_mirror_geoms(g, k, default_units) for g in value]
    if not isinstance(value, dict):
        return value
    g = dict(value)
    if "origin" in g:
        g["origin"] = _mirror_pose(g["origin"], k)
    if isinstance(g.get("mesh"), str):
        scale = g.get("scale")
        if scale is None:
            f = UNIT_FACTORS.get(g.pop("units", None) or default_units, 1.0)
            scale = [f, f, f]
        elif _is_num(scale):
            scale = [scale] * 3
        if isinstance(scale, list) and len(scale) == 3 and all(_is_num(v) for v in scale):
            g["scale"] = [_neg(v) if i == k else v for i, v in enumerate(scale)]
    return g


def _mirror(parts: dict, k: int, default_units: str, local_joints: set):
    sign = [-1 if i == k else 1 for i in range(3)]
    for link in parts["links"].values():
        if not isinstance(link, dict):
            continue
        if "visual" in link:
            link["visual"] = _mirror_geoms(link["visual"], k, default_units)
        coll = link.get("collision")
        if isinstance(coll, (list, dict)):
            if isinstance(coll, dict) and "strategy" in coll:
                if "source" in coll:
                    coll["source"] = _mirror_geoms(coll["source"], k, default_units)
            else:
                link["collision"] = _mirror_geoms(coll, k, default_units)
        inertial = link.get("inertial")
        if isinstance(inertial, dict):
            com = inertial.get("com")
            if isinstance(com, list) and len(com) == 3 and all(_is_num(v) for v in com):
                inertial["com"] = [_neg(v) if i == k else v for i, v in enumerate(com)]
            inertia = inertial.get("inertia")
            if isinstance(inertia, dict):  # I' = M I M: products with one flipped axis change sign
                for key, (a, b) in (("ixy", (0, 1)), ("ixz", (0, 2)), ("iyz", (1, 2))):
                    if _is_num(inertia.get(key)) and sign[a] * sign[b] < 0:
                        inertia[key] = _neg(inertia[key])
    flipped = set()
    for n, j in parts["joints"].items():
        if not isinstance(j, dict):
            continue
        j["origin"] = _mirror_pose(j.get("origin", {}), k)
        axis = j.get("axis", [1, 0, 0])
        if not (isinstance(axis, list) and len(axis) == 3 and all(_is_num(v) for v in axis)):
            continue
        Ma = [_neg(v) if i == k else v for i, v in enumerate(axis)]
        new = Ma if j.get("type") in ("prismatic", "planar") else [_neg(v) for v in Ma]
        if j.get("type") in ("revolute", "continuous", "prismatic") and sum(a * b for a, b in zip(new, axis)) < 0:
            new = [_neg(v) for v in new]
            flipped.add(n)
            lim = j.get("limit")
            if isinstance(lim, dict) and _is_num(lim.get("lower")) and _is_num(lim.get("upper")):
                lim["lower"], lim["upper"] = _neg(lim["upper"]), _neg(lim["lower"])
        if "axis" in j or new != [1, 0, 0]:
            j["axis"] = new
    for n, j in parts["joints"].items():
        mimic = j.get("mimic") if isinstance(j, dict) else None
        if not isinstance(mimic, dict):
            continue
        s_f = -1 if n in flipped else 1
        s_l = -1 if mimic.get("joint") in flipped else 1
        if s_f * s_l < 0 and _is_num(mimic.get("multiplier", 1.0)):
            mimic["multiplier"] = _neg(mimic.get("multiplier", 1.0))
        if s_f < 0 and _is_num(mimic.get("offset", 0.0)) and mimic.get("offset"):
            mimic["offset"] = _neg(mimic["offset"])
    for s in parts["sensors"].values():
        if isinstance(s, dict) and "origin" in s:
            s["origin"] = _mirror_pose(s["origin"], k)
