"""Quantities with units: ``5 cm``, ``90 deg``, ``300 g`` -> SI numbers.

Which unit a number may carry is read from the schema: fields annotated with
:class:`robotkit.recipe.schema.Dim` are lengths, angles, masses or joint
positions (a length for prismatic joints, an angle for revolute and continuous
ones).  Bare numbers are SI, as before.
"""

from __future__ import annotations

import math
import re
import types
import typing

from pydantic import BaseModel

from robotkit.recipe.schema import Dim, Position, Recipe

# unit -> (dimension, convert to SI); division by powers of ten keeps 5 cm == 0.05 exactly
UNITS = {
    "m": ("length", lambda x: float(x)), "cm": ("length", lambda x: x / 100), "mm": ("length", lambda x: x / 1000),
    "um": ("length", lambda x: x / 1e6), "km": ("length", lambda x: x * 1000.0),
    "in": ("length", lambda x: x * 0.0254), "ft": ("length", lambda x: x * 0.3048),
    "rad": ("angle", lambda x: float(x)), "deg": ("angle", math.radians),
    "kg": ("mass", lambda x: float(x)), "g": ("mass", lambda x: x / 1000), "mg": ("mass", lambda x: x / 1e6),
    "lb": ("mass", lambda x: x * 0.45359237),
}
ARTICLE = {"length": "a length", "angle": "an angle", "mass": "a mass"}
QUANTITY_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z]+)\s*$")
KNOWN = "lengths: m, cm, mm, um, km, in, ft; angles: rad, deg; masses: kg, g, mg, lb"


def parse(text: str):
    """(SI value, dimension) of a quantity like '5 cm'; None when ``text`` is not one.

    Raises ValueError for a number with an unknown unit."""
    m = QUANTITY_RE.match(text)
    if not m:
        return None
    number, unit = m.groups()
    if unit not in UNITS:
        raise ValueError(f"unknown unit '{unit}' in '{text.strip()}' ({KNOWN})")
    dim, to_si = UNITS[unit]
    x = float(number) if any(c in number for c in ".eE") else int(number)
    return to_si(x), dim


def convert(data: dict, problem) -> dict:
    """Replace every quantity in the flat recipe ``data`` by its SI number (in place).

    ``problem(path, message)`` records a problem at a key path."""
    convert_poses(data, problem)
    poses = data.pop("poses", None)  # converted above, by their joints' types
    convert_tree(data, Recipe, (), None, problem)
    if poses is not None:
        data["poses"] = poses
    return data


def convert_poses(data: dict, problem) -> None:
    """The quantities of ``poses`` (in place), each in the unit of its joint's type (a joint
    the recipe lacks takes either: resolution names it)."""
    poses, joints = data.get("poses"), data.get("joints")
    if not isinstance(poses, dict):
        return
    types_ = {k: j.get("type") for k, j in joints.items() if isinstance(j, dict)} if isinstance(joints, dict) else {}
    for name, pose in poses.items():
        if not isinstance(pose, dict):
            continue
        for joint, value in pose.items():
            if not isinstance(value, str):
                continue
            path = ("poses", name, joint)
            if joint in types_:
                pose[joint] = convert_tree(value, Position, path, types_[joint], problem)
                continue
            try:
                q = parse(value)
            except ValueError as exc:
                problem(path, str(exc))
                continue
            if q is not None:
                pose[joint] = q[0]


def _dims_and_kinds(tp, dims: list, kinds: list):
    """Flatten Annotated/Union: the Dim markers and the bare types (models, list, dict, scalars)."""
    origin = typing.get_origin(tp)
    if origin is typing.Annotated:
        args = typing.get_args(tp)
        dims.extend(m for m in args[1:] if isinstance(m, Dim))
        _dims_and_kinds(args[0], dims, kinds)
    elif origin in (typing.Union, types.UnionType):
        for a in typing.get_args(tp):
            _dims_and_kinds(a, dims, kinds)
    else:
        kinds.append(tp)


_CACHE: dict = {}


def _split(tp):
    key = id(tp)
    if key not in _CACHE:
        dims, kinds = [], []
        _dims_and_kinds(tp, dims, kinds)
        _CACHE[key] = (tp, dims, kinds)
    return _CACHE[key][1], _CACHE[key][2]


def _fields(model):
    key = ("fields", model)
    if key not in _CACHE:
        # pydantic keeps a field's own Annotated metadata (e.g. a Dim) apart from its annotation
        _CACHE[key] = {(f.alias or name): (typing.Annotated[(f.annotation, *f.metadata)] if f.metadata
                                           else f.annotation) for name, f in model.model_fields.items()}
    return _CACHE[key]


def convert_tree(value, tp, path, joint_type, problem):
    """``value`` (read as schema type ``tp``, at key ``path``) with its quantities replaced by SI
    numbers (mappings and lists changed in place); ``problem(path, message)`` records what
    cannot be converted."""
    dims, kinds = _split(tp)
    if isinstance(value, dict):
        for k in kinds:
            if isinstance(k, type) and issubclass(k, BaseModel):
                fields = _fields(k)
                jt = value.get("type") if k.__name__ == "Joint" else joint_type
                for key, v in value.items():
                    if key in fields:
                        new = convert_tree(v, fields[key], path + (key,), jt, problem)
                        if new is not v:
                            value[key] = new
                return value
            if typing.get_origin(k) is dict:
                sub = typing.get_args(k)[1] if typing.get_args(k) else None
                if sub is not None:
                    for key, v in value.items():
                        new = convert_tree(v, sub, path + (key,), joint_type, problem)
                        if new is not v:
                            value[key] = new
                return value
        return value
    if isinstance(value, list):
        for k in kinds:
            if typing.get_origin(k) is list:
                sub = typing.get_args(k)[0]
                for i, v in enumerate(value):
                    new = convert_tree(v, sub, path + (i,), joint_type, problem)
                    if new is not v:
                        value[i] = new
                return value
        return value
    if not isinstance(value, str) or not any(k in (float, int) for k in kinds):
        return value
    try:
        q = parse(value)
    except ValueError as exc:
        problem(path, str(exc))
        return value
    if q is None:
        return value
    si, dim = q
    want = dims[0].kind if dims else None
    if want == "position":
        want = {"revolute": "angle", "continuous": "angle", "prismatic": "length"}.get(
            joint_type if isinstance(joint_type, str) else None)
        if want is None:
            kind = joint_type if isinstance(joint_type, str) and joint_type else "untyped"
            problem(path, f"takes a plain number for a {kind} joint (got '{value.strip()}')")
            return value
    if want is None:
        problem(path, f"takes a plain number, not a quantity with units (got '{value.strip()}')")
        return value
    if dim != want:
        problem(path, f"expects {ARTICLE[want]}, got {ARTICLE[dim]} ('{value.strip()}')")
        return value
    return si
