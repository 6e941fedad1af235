"""Inertia decisions of the importer, on the shared policy (robotkit.model.inertia_policy):
what a URDF <inertial> says, which given tensors are kept and which repaired, which links the
build would refuse for having no mass and what they get instead (each change recorded, with
the reason, for the recipe's comments), and the report of ``--recompute-inertials``."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from robotkit.importer.parsing import Problems, read_float, read_origin
from robotkit.importer.recipe_writer import fmt
from robotkit.mesh.inertia import mesh_mass_properties
from robotkit.mesh.io import load_mesh, volume_mesh
from robotkit.model import inertia_policy
from robotkit.model.load import load_robots
from robotkit.model.resolve import finalize_link_inertial
from robotkit.geometry import rpy_matrix
from robotkit.recipe.schema import Link


def no_inertial_form():
    """The recipe value that says "this link has no inertial", if the schema has one."""
    for value in ("none",):
        try:
            Link.model_validate({"visual": {"box": {"size": [1, 1, 1]}}, "inertial": value})
            return value
        except ValidationError:
            continue
    return None


def read_inertial(el, link: str, problems: Problems) -> dict | None:
    what = f"link '{link}' inertial"
    mass_el = el.find("mass")
    mass = read_float(mass_el.get("value") if mass_el is not None else None, f"{what} mass", problems, 0.0)
    xyz, rpy = read_origin(el.find("origin"), what, problems)
    t = el.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    values = {k: 0.0 for k in keys}
    if t is not None:
        for k in keys:
            v = read_float(t.get(k), f"{what} {k}", problems, 0.0)
            values[k] = v if v is not None else 0.0
    if any(rpy):
        I = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                      [values["ixy"], values["iyy"], values["iyz"]],
                      [values["ixz"], values["iyz"], values["izz"]]])
        R = rpy_matrix(rpy)
        I = R @ I @ R.T
        I = 0.5 * (I + I.T)
        scale = float(np.abs(I).max())
        I[np.abs(I) < 1e-14 * scale] = 0.0
        values = {"ixx": I[0, 0], "ixy": I[0, 1], "ixz": I[0, 2], "iyy": I[1, 1], "iyz": I[1, 2], "izz": I[2, 2]}
        values = {k: float(v) + 0.0 for k, v in values.items()}
    return {"mass": mass if mass is not None else 0.0, "com": xyz, "inertia": values, "rpy": rpy}


def _explicit_dict(given: dict) -> dict:
    out: dict = {"mass": given["mass"]}
    if any(given["com"]):
        out["com"] = list(given["com"])
    t = given["inertia"]
    inertia = {k: t[k] for k in ("ixx", "iyy", "izz")}
    for k in ("ixy", "ixz", "iyz"):
        if t[k] != 0.0:
            inertia[k] = t[k]
    out["inertia"] = inertia
    return out


POLICIES = ("keep", "repair", "recompute", "estimate")
"""``robotkit import --inertia-policy``: what a link whose given tensor no real body has gets."""


def chosen_inertial(name: str, given: dict, source: str | None, policy: str, repairs: dict[str, str],
                    why: str = "") -> dict | None:
    """The recipe's inertial for link ``name`` whose original gives a positive mass: as given when
    it is physical, else by ``policy`` (``source``: the geometry a recompute or an estimate reads,
    None when the link has none, which gets the repair), with what was wrong and what was done in
    ``repairs[name]`` (the comment above the link; ``why``: why not the repair, or why a physical
    tensor is replaced, when the import's fit (robotkit.importer.fit) gives the policy; ``density``:
    no inertial, the geometry's at the recipe's density, None for the visual geometry).  ``keep``
    writes the tensor as given: the import then stops on a defect, as the build would."""
    wrong = inertia_policy.defects(given["mass"], _tensor(given["inertia"]))
    if policy == "keep" or not (wrong or why):  # ``why``: the import's fit overrides a physical one too
        return _explicit_dict(given)
    what = "; ".join(filter(None, (f"the original's {'; '.join(wrong)}" if wrong else "", why)))
    if policy == "density" and source is not None:  # a mass no solid part of its volume has
        repairs[name] = (f"{what}: mass and inertia computed from its {source} geometry at the recipe's density "
                         "(the given ones are unused)")
        return {"source": source} if source != "visual" else None
    if policy in ("recompute", "estimate") and source is not None:
        spec = {**_explicit_dict(given), "policy": policy}  # the given values stay, for the record
        if source != "visual":
            spec["source"] = source
        how = ("recomputed from its {} geometry" if policy == "recompute" else
               "estimated as the bounding primitive of its {} geometry").format(source)
        repairs[name] = f"{what}: {how}, keeping the mass (policy: {policy}; the given com and inertia are unused)"
        return spec
    fixed = inertia_policy.repair(given["mass"], _tensor(given["inertia"]), given["mass"])
    t = fixed.inertia
    given = dict(given, inertia={k: float(v) + 0.0 for k, v in {
        "ixx": t[0, 0], "ixy": t[0, 1], "ixz": t[0, 2], "iyy": t[1, 1], "iyz": t[1, 2], "izz": t[2, 2]}.items()})
    alone = f"; it has no geometry to {'recompute it from' if policy == 'recompute' else 'estimate it from'}" \
        if policy != "repair" else ""
    repairs[name] = f"{what}{alone}: repaired ({'; '.join(fixed.changes)})"
    return _explicit_dict(given)


def _has_mass(link: dict) -> bool:
    spec = link.get("inertial")
    return isinstance(spec, dict) or (spec is None and bool(link.get("visual")))


def _welded_below(name: str, children: dict[str, list[dict]]) -> list[str]:
    """``name`` and the links welded below it by fixed joints, breadth first (a cycle is walked once)."""
    welded, todo = [], [name]
    while todo:
        welded += todo
        todo = list(dict.fromkeys(j["child"] for n in todo for j in children.get(n, [])
                                  if j["type"] == "fixed" and j["child"] not in welded))
    return welded


POINT_MASS_FLOOR = 1e-5
"""kg: the least point mass import gives a link without one (libsdformat drops a link of 1e-6 kg)."""


MOVING = frozenset({"revolute", "continuous", "prismatic", "planar", "floating"})


def give_moving_links_mass(links: dict[str, dict], joints: dict[str, dict], out) -> None:
    """A link the build refuses or SDF misreads for having no mass (it moves, it is a root
    with moving joints below it and no mass welded to it, or it has moving joints or mass below
    it: libsdformat drops such a link with its subtree) gets one: computed from its geometry at the
    recipe's density, or a point mass when it has none.  Each is recorded in ``out.repairs``."""
    tree = _Tree(links, joints)
    refused: dict[str, str] = {}  # link -> why it needs a mass
    _moving_without_mass(tree, refused)
    _massless_roots(tree, refused)
    _massless_inside(tree, refused)
    _give_mass(links, refused, out, tree)


class _Tree:
    """The joints of an imported robot as a tree: which links carry mass, and where."""

    def __init__(self, links: dict[str, dict], joints: dict[str, dict]):
        self.links, self.joints = links, joints
        self.children: dict[str, list[dict]] = {}
        for j in joints.values():
            self.children.setdefault(j["parent"], []).append(j)
        self.parent_joint = {j["child"]: j for j in joints.values()}
        self.named = {id(j): n for n, j in joints.items()}

    def body_mass(self, name: str) -> bool:
        """Whether ``name`` or a link welded below it has mass."""
        todo, seen = [name], set()
        while todo:
            n = todo.pop()
            if n in seen or n not in self.links:
                continue
            seen.add(n)
            if _has_mass(self.links[n]):
                return True
            todo += [j["child"] for j in self.children.get(n, []) if j["type"] == "fixed"]
        return False

    def welded_below(self, name: str) -> list[str]:
        return _welded_below(name, self.children)

    def bearer(self, name: str) -> str:
        """The first link with geometry welded below ``name`` (or ``name``): where its mass goes."""
        return next((n for n in self.welded_below(name)
                     if self.links[n].get("visual") or isinstance(self.links[n].get("collision"), (dict, list))),
                    name)

    def carries(self, name: str, seen: frozenset = frozenset()) -> str | None:
        """The first joint below ``name`` that moves or holds mass (libsdformat drops it)."""
        for j in self.children.get(name, []):
            if j["child"] in seen or j["child"] not in self.links:
                continue
            if j["type"] in MOVING or _has_mass(self.links[j["child"]]) or self.carries(j["child"], seen | {name}):
                return self.named[id(j)]
        return None


def _moving_without_mass(tree: _Tree, refused: dict[str, str]) -> None:
    """A moving link with no mass (nor any welded to it), or with mass only welded to it."""
    for jname, j in tree.joints.items():
        if j["type"] in MOVING and j["child"] in tree.links and not tree.body_mass(j["child"]):
            refused.setdefault(j["child"], f"no mass in the original, and it moves (joint '{jname}'): MuJoCo "
                                           "refuses a moving body without mass and Gazebo drops it")
        elif j["type"] in MOVING and j["child"] in tree.links and not _has_mass(tree.links[j["child"]]):
            refused.setdefault(j["child"], f"no mass in the original, and it moves (joint '{jname}'): SDF keeps "
                                           "it a link, which Gazebo and Drake give 1 kg without an inertial")


def _massless_roots(tree: _Tree, refused: dict[str, str]) -> None:
    """A massless root with joints below it, and a massless welded link with a moving joint below."""
    for name in tree.links:
        if name != "world" and name not in tree.parent_joint and tree.children.get(name) and not tree.body_mass(name):
            refused.setdefault(tree.bearer(name), "no mass in the original (nor on the links welded to it), and it is "
                                                  "(or is welded to) the root with moving joints below it: Gazebo's "
                                                  "URDF conversion drops it and everything below it")
    for name in tree.links:  # libsdformat weighs a welded link with the links welded below it only
        jname = next((n for n, j in tree.joints.items() if j["parent"] == name and j["type"] in MOVING), None)
        if (jname is not None and name in tree.parent_joint and tree.parent_joint[name]["type"] == "fixed"
                and not tree.body_mass(name) and not any(n in refused for n in tree.welded_below(name))):
            refused.setdefault(tree.bearer(name), f"no mass in the original (nor on the links welded below it), and "
                                                  f"joint '{jname}' moves below it: Gazebo's URDF conversion drops "
                                                  "everything that moves below it, though it is welded to a link "
                                                  "with mass")


def _massless_inside(tree: _Tree, refused: dict[str, str]) -> None:
    """A massless link inside the tree with a joint below it that moves or holds mass: iCub's l_hip_3."""
    for name in sorted(set(tree.parent_joint) & set(tree.links)):
        if tree.body_mass(name) or any(n in refused for n in tree.welded_below(name)):
            continue
        below = tree.carries(name)
        if below:
            refused.setdefault(name, f"no mass in the original, with joint '{below}' below it: Gazebo's URDF "
                                     "conversion drops it and everything below it, even welded to a link with mass")


GIMBAL_SHARE = 1e-2
"""A link between two moving joints with neither mass nor geometry (one of the frames a ball joint
is split into: the 36-DoF human's ``left_upperarm_virtual``) gets this share of the least principal
moment of the links it carries: near the hinges' gimbal lock, the joint-space inertia of the
hinges above and below it is that link's own, and the smallest a repair leaves (6e-11 kg m^2 on
the human) lets MuJoCo's simulation explode (5.8e3 rad/s after 2 s; stable from about 1e-7)."""


def _least_moment_below(tree: _Tree, name: str, explicit: dict) -> float | None:
    """The least principal moment of the given tensors of the links below ``name`` (None: none)."""
    least, todo, seen = None, [j["child"] for j in tree.children.get(name, [])], {name}
    while todo:
        n = todo.pop()
        if n in seen:
            continue
        seen.add(n)
        todo += [j["child"] for j in tree.children.get(n, [])]
        if n in explicit and explicit[n]["mass"] > 0:
            moment = float(np.linalg.eigvalsh(_tensor(explicit[n]["inertia"])).min())
            least = moment if moment > 0 and (least is None or moment < least) else least
    return least


def _gimbal_moment(tree: _Tree, name: str, explicit: dict) -> float | None:
    """GIMBAL_SHARE of the least moment below ``name`` when a moving joint moves it and another
    moves below it, else None."""
    above = tree.parent_joint.get(name)
    if above is None or above["type"] not in MOVING or not any(j["type"] in MOVING for j in tree.children.get(name, [])):
        return None
    least = _least_moment_below(tree, name, explicit)
    return float(f"{GIMBAL_SHARE * least:.3g}") if least is not None else None


def _give_mass(links: dict[str, dict], refused: dict[str, str], out, tree: _Tree) -> None:
    """Each refused link's mass: from its geometry at the recipe's density, else a point mass."""
    given = [g["mass"] for g in out.explicit.values() if g["mass"] > 0]
    point = 1e-3 * min(given) if given else 1e-3
    # libsdformat reads a mass up to 1e-6 kg as none and drops the link (iCub weighs a link 1e-6 kg)
    why_point = "a thousandth of the lightest link" if point >= POINT_MASS_FLOOR else \
        "ten times the 1e-06 kg up to which libsdformat drops a link"
    point = max(point, POINT_MASS_FLOOR)
    for name, why in refused.items():
        link = links[name]
        if link.get("visual"):
            link.pop("inertial", None)
            out.repairs[name] = f"{why}; computed from its visual geometry at the recipe's density"
        elif isinstance(link.get("collision"), (dict, list)):
            link["inertial"] = {"source": "collision"}
            out.repairs[name] = f"{why}; computed from its collision geometry at the recipe's density"
        else:
            floor = inertia_policy.moment_floor(point)
            gimbal = _gimbal_moment(tree, name, out.explicit)
            moment = max(floor, gimbal or 0.0)
            link["inertial"] = {"mass": point, "inertia": {"ixx": moment, "iyy": moment, "izz": moment}}
            inertia = ("with the smallest inertia a repair leaves" if moment == floor else
                       f"with moments of {moment:.3g} kg m^2, a hundredth of the least of the links it carries "
                       "(the joints above and below it are a gimbal, which a smaller inertia leaves ill-conditioned)")
            out.repairs[name] = f"{why}; it has no geometry: a point mass of {fmt(point)} kg ({why_point}) {inertia}"


def _tensor(t: dict):
    return np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])



def geometry_facts(mesh) -> dict:
    """Unit-density mass properties of one mesh, as robotkit's mesh task records them."""
    m = load_mesh(mesh.source, mesh.scale)
    bbox_min, bbox_max = m.bounds
    vol, _, _, _ = volume_mesh(m, mesh.open_mesh, os.path.basename(mesh.source))
    props = mesh_mass_properties(vol.vertices, vol.faces)
    return {"volume": props.volume, "com": [float(v) for v in props.com],
            "inertia": [[float(v) for v in row] for row in np.asarray(props.inertia)],
            "bbox_min": [float(v) for v in bbox_min], "bbox_max": [float(v) for v in bbox_max]}


def report_recomputed(recipe_file: Path, conv, result) -> None:
    (_, robot), = load_robots([recipe_file])
    facts: dict[str, dict] = {}
    for link in robot.links:
        if link.inertial_spec.mode not in ("mass", "density") or link.name not in conv.explicit:
            continue
        for g in link.source_geoms():
            if g.shape.mesh is not None and g.shape.mesh.key not in facts:
                facts[g.shape.mesh.key] = geometry_facts(g.shape.mesh)
        new = finalize_link_inertial(link, facts)
        given = conv.explicit[link.name]
        t = given["inertia"]
        I0 = np.array([[t["ixx"], t["ixy"], t["ixz"]], [t["ixy"], t["iyy"], t["iyz"]], [t["ixz"], t["iyz"], t["izz"]]])
        I1 = new.tensor()
        com_shift = float(np.linalg.norm(np.asarray(new.com) - np.asarray(given["com"])))
        rel = float(np.linalg.norm(I1 - I0) / max(np.linalg.norm(I0), 1e-300))
        result.inertials[link.name] = {
            "given": {"mass": given["mass"], "com": list(given["com"]), "inertia": I0.tolist()},
            "computed": {"mass": new.mass, "com": list(new.com), "inertia": I1.tolist()},
            "com_shift": com_shift, "inertia_rel_diff": rel,
        }
        mass = (f"mass {new.mass:.6g} kg (given {given['mass']:.6g})" if link.inertial_spec.mode == "density"
                else f"mass {new.mass:.6g} kg kept")
        d0 = ", ".join(f"{v:.4g}" for v in np.diag(I0))
        d1 = ", ".join(f"{v:.4g}" for v in np.diag(I1))
        result.warnings.append(
            f"link '{link.name}': recomputed inertial from its {link.inertial_spec.source} geometry: {mass}; "
            f"centre of mass moved {com_shift * 1000:.3g} mm; inertia tensor differs by {rel * 100:.3g}% "
            f"(diagonal given {d0}, now {d1} kg m^2)")
