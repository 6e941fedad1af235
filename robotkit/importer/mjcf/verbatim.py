"""What the recipe has no key for but MuJoCo needs, kept verbatim for the MJCF: the recipe's
``mjcf_extras`` (:mod:`robotkit.emit.mjcf` appends them to the rebuilt MJCF's sections).

Written from the compiled model (every default class, ``childclass`` and computed value
resolved as MuJoCo resolved them), in the rebuilt model's names: bodies are their links
(``tree.link_of``), joints the recipe's (``tree.joint_map``), sites their frame links
(``tree.sites``: the rebuilt MJCF gives every frame link a site of its name), actuators the
rebuilt ones (``<joint>_<interface>``) or the verbatim ones.  Points in a body's frame move to its
link's frame (``tree.offset``).  Active connect and weld constraints between two links are the
recipe's ``loops`` instead, softness and all (:func:`_loops`).  Kept: tendons (fixed, and spatial
through sites and pulleys), the other equality constraints but the mimic joints (connect, weld,
joint, tendon), actuators the
recipe's actuators do not hold (``tree.refused``), sensors other than the IMUs', custom numerics
and texts.  Each is on the ledger for the URDF and SDF; what cannot be written (a wrap around a
geom, a flex, a ball joint's sensor...) is dropped for all formats, saying why.  ``tree.verbatim``:
{kind: {MuJoCo id: rebuilt name}} for the verification."""

from __future__ import annotations

import numpy as np

from robotkit import mj
from robotkit.importer.mjcf.extras import EQ_KINDS, SOLIMP, SOLREF
from robotkit.importer.mjcf.frames import origin, quat_matrix
from robotkit.importer.mjcf.sites import free_name
from robotkit.importer.names import valid_frame_name, valid_name
from robotkit.importer.recipe_writer import fmt

KEPT = "dropped: {why} (kept verbatim in mjcf_extras for the MJCF)"
OTHERS = "urdf, sdf"
HINGE_SLIDE = (2, 3)


class Dropped(Exception):
    """Why an element cannot be written verbatim in the rebuilt model's names."""


def _numbers(values, least: int = 1) -> str:
    """Space-separated numbers, trailing zeros left out (at least ``least`` kept: MuJoCo pads with zeros)."""
    values = [float(v) for v in values]
    while len(values) > least and values[-1] == 0:
        values.pop()
    return " ".join(fmt(v) for v in values)


def _xml(tag: str, attrs: dict, children: list[str] = ()) -> str:
    from xml.sax.saxutils import quoteattr

    head = f"<{tag}" + "".join(f" {k}={quoteattr(str(v))}" for k, v in attrs.items())
    return head + (">" + "".join(children) + f"</{tag}>" if children else "/>")


class Names:
    """The rebuilt model's name of each element an extra names."""

    def __init__(self, src, tree, recipe: dict):
        self.m, self.tree, self._zero = src.model, tree, None
        self.looped: set[int] = set()  # equalities that are the recipe's loops
        self.actuators = {a: f"{joint}_{recipe['actuators'][joint]['interface']}" for a, joint in tree.actuated.items()}
        self.taken = {"actuator": set(self.actuators.values()),
                      "sensor": {f"{n}_{s}" for n in recipe.get("sensors", {}) for s in ("gyro", "accel")},
                      "equality": {f"{child}_mimic" for child, _ in tree.mimics.values()}}

    def own(self, kind: str, i: int) -> str:
        """A verbatim element's name: its own, else ``<kind><id>``; never one the rebuild has."""
        name = getattr(self.m, {"equality": "eq"}.get(kind, kind))(i).name
        taken = self.taken.setdefault(kind, set())
        if not name or name in taken:
            name = f"{kind}{i}"
        taken.add(name)
        self.tree.verbatim.setdefault(kind, {})[i] = name
        return name

    def body(self, b: int) -> str:
        if b == 0:
            return "world"
        if b not in self.tree.link_of:
            raise Dropped(f"body '{self.m.body(b).name}' is not imported")
        return self.tree.link_of[b]

    def offset(self, b: int) -> np.ndarray:
        return np.zeros(3) if b == 0 else np.asarray(self.tree.offset[b], float)

    def same_at_zero(self, e: int) -> bool:
        """Whether a body connect's point in body2 (where MuJoCo found body1's point at the
        original's ``qpos0``) is where the rebuild finds it, at its zero configuration (hinges and
        slides at 0: not at a ``ref`` of theirs)."""
        m = self.m
        d, a, b, data = self.zero(), int(m.eq_obj1id[e]), int(m.eq_obj2id[e]), m.eq_data[e]
        point = d.xpos[a] + d.xmat[a].reshape(3, 3) @ data[:3]
        there = d.xmat[b].reshape(3, 3).T @ (point - d.xpos[b])
        return bool(np.abs(there - data[3:6]).max() <= 1e-12)

    def zero(self):
        """The original at the rebuild's zero configuration (hinges and slides at 0, the others at
        ``qpos0``): its MjData, positions and tendon lengths computed."""
        if self._zero is None:
            m, mujoco = self.m, mj.load()
            self._zero = mujoco.MjData(m)
            q = np.array(m.qpos0)
            for j in range(m.njnt):
                if int(m.jnt_type[j]) in HINGE_SLIDE:
                    q[int(m.jnt_qposadr[j])] = 0.0
            self._zero.qpos[:] = q
            mujoco.mj_fwdPosition(m, self._zero)
        return self._zero

    def coupling(self, kind: str, a: int, b: int, coef) -> str:
        """A joint or tendon coupling's ``polycoef`` for the rebuild: MuJoCo couples the values'
        changes from ``qpos0`` (``y - y0 = p(x - x0)``), and the rebuild's zero configuration is not
        the original's ``qpos0`` where a joint has a ``ref``."""
        from numpy.polynomial import Polynomial

        m, d = self.m, self.zero()
        coef = np.asarray(coef, float) if b >= 0 else np.array([float(coef[0]), 0.0])  # alone: fixed
        if kind == "joint":
            (y0, x0), (y1, x1) = ([float(m.qpos0[m.jnt_qposadr[j]]) if j >= 0 else 0.0 for j in (a, b)],
                                  [0.0, 0.0])
        else:
            (y0, x0), (y1, x1) = ([float(m.tendon_length0[t]) if t >= 0 else 0.0 for t in (a, b)],
                                  [float(d.ten_length[t]) if t >= 0 else 0.0 for t in (a, b)])
        # the rebuild's: y - y1 = p'(x - x1), with p'(z) = y0 - y1 + p(z + x1 - x0)
        p = Polynomial(np.asarray(coef, float))(Polynomial([x1 - x0, 1.0])) + (y0 - y1)
        return _numbers(np.pad(p.coef, (0, 5))[:5], 5)

    def anchor(self, e: int, b: int, point, k: int) -> str:
        """A frame link at a connect constraint's ``point`` in body ``b``'s frame (a site of the
        rebuilt MJCF), the ``k``-th of its two."""
        if b not in self.tree.link_of:
            raise Dropped("an anchor on the world, and the robot has no world link")
        eq = self.m.eq(e).name
        base = f"{eq if valid_frame_name(eq) else f'loop{e}'}_anchor{k}"
        name = free_name(self.tree, base)
        joint = free_name(self.tree, f"{name}_fixed", self.tree.joints)
        self.tree.links[name] = {}
        self.tree.joints[joint] = {"type": "fixed", "parent": self.tree.link_of[b], "child": name}
        o = origin(np.asarray(point, float) - self.offset(b), np.eye(3))
        if o:
            self.tree.joints[joint]["origin"] = o
        self.tree.notes[joint] = (f"an anchor of MJCF connect constraint {f'{eq!r}' if eq else f'#{e}'} (a site of the "
                                  "rebuilt MJCF, which mjcf_extras constrains)")
        return name

    def joint(self, j: int) -> str:
        if int(self.m.jnt_type[j]) not in HINGE_SLIDE:
            raise Dropped(f"joint '{self.m.joint(j).name}' is a ball or free joint (three joints in the rebuild)")
        return self.tree.joint_map[j][0]

    def site(self, s: int) -> str:
        if s not in self.tree.sites:
            raise Dropped(f"site '{self.m.site(s).name}' is not imported")
        return self.tree.sites[s]

    def tendon(self, t: int) -> str:
        if t not in self.tree.verbatim.get("tendon", {}):
            raise Dropped(f"tendon '{self.m.tendon(t).name}' is not kept")
        return self.tree.verbatim["tendon"][t]

    def actuator(self, a: int) -> str:
        if a in self.actuators:
            if float(self.m.actuator_gear[a][0]) != 1:
                raise Dropped(f"actuator '{self.m.actuator(a).name}' has its gear in the recipe's control")
            return self.actuators[a]
        if a not in self.tree.verbatim.get("actuator", {}):
            raise Dropped(f"actuator '{self.m.actuator(a).name}' is not kept")
        return self.tree.verbatim["actuator"][a]

    def object(self, objtype: int, i: int, oriented: bool) -> tuple[str, str]:
        """(MJCF object type, name) of a frame sensor's object or reference (``oriented``: its axes are read)."""
        kind = mj.load().mjtObj(objtype).name.removeprefix("mjOBJ_").lower()
        if kind == "site":
            return kind, self.site(i)
        if kind == "body" and oriented:
            raise Dropped(f"it reads the axes of body '{self.m.body(i).name}''s inertial frame, which MuJoCo "
                          "chooses anew from the rebuilt inertia tensor")
        if kind == "body":
            return kind, self.body(i)
        if kind == "xbody":
            if np.any(self.offset(i)):
                raise Dropped(f"the frame of body '{self.m.body(i).name}' is on its hinge's axis in the rebuild")
            return kind, self.body(i)
        raise Dropped(f"it reads a {kind}")


def add_verbatim(src, tree, recipe: dict, ledger) -> None:
    """``recipe['mjcf_extras']`` and the ledger lines of what it keeps and drops."""
    names = Names(src, tree, recipe)
    loops = _loops(src, tree, names, ledger)
    if loops:
        recipe["loops"] = loops
    sections = {}
    for tag, items in (("tendon", _tendons), ("actuator", _actuators), ("equality", _equalities),
                       ("sensor", _sensors)):
        children = []
        for where, label, why, text in items(src, tree, names):
            if text is None:
                ledger.add(where, label, "all", f"dropped: {why}")
            else:
                ledger.add(where, label, OTHERS, KEPT.format(why=why))
                children.append(text)
        if children:
            sections[tag] = children
    custom = _custom(src.model)
    if custom:
        for kind in ("numeric", "text"):
            for e in getattr(src.spec, kind + "s", []):
                ledger.add(src.where(e), f"custom {kind} '{e.name}'", OTHERS,
                           KEPT.format(why=f"the recipe has no custom {kind}s"))
        sections["custom"] = custom
    if sections:
        recipe["mjcf_extras"] = [_section(tag, children) for tag, children in sections.items()]


def _section(tag: str, children: list[str]) -> str:
    """A section element, indented as a person writes one."""
    import xml.etree.ElementTree as ET

    section = ET.fromstring(f"<{tag}>{''.join(children)}</{tag}>")
    ET.indent(section, "  ")
    return ET.tostring(section, encoding="unicode").replace(" />", "/>")


def _each(src, kind: str, count: int, label_kind: str, write):
    """(where, label, why, text or None) for each element ``write(i)`` writes (Dropped: why not)."""
    specs = list(getattr(src.spec, "equalities" if kind == "equality" else kind + "s"))
    for i in range(count):
        name = getattr(src.model, {"equality": "eq"}.get(kind, kind))(i).name
        where = src.where(specs[i]) if i < len(specs) else src.where()
        label = f"{label_kind(i) if callable(label_kind) else label_kind}" + (f" '{name}'" if name else f" #{i}")
        try:
            result = write(i)
        except Dropped as why:
            yield where, label, str(why), None
            continue
        if result is not None:
            yield (where, label) + result


def _tendons(src, tree, names: Names):
    m = src.model
    wraps = mj.load().mjtWrap

    def write(t: int):
        children = []
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        for w in range(adr, adr + num):
            kind, obj, prm = int(m.wrap_type[w]), int(m.wrap_objid[w]), float(m.wrap_prm[w])
            if kind == wraps.mjWRAP_JOINT:
                children.append(_xml("joint", {"joint": names.joint(obj), "coef": fmt(prm)}))
            elif kind == wraps.mjWRAP_SITE:
                children.append(_xml("site", {"site": names.site(obj)}))
            elif kind == wraps.mjWRAP_PULLEY:
                children.append(_xml("pulley", {"divisor": fmt(prm)}))
            else:
                raise Dropped(f"it wraps around geom '{m.geom(obj).name}', which the rebuild names otherwise")
        fixed = int(m.wrap_type[adr]) == wraps.mjWRAP_JOINT if num else True
        name = names.own("tendon", t)
        return ("the recipe has no tendons", _xml("fixed" if fixed else "spatial", {"name": name, **_tendon_attrs(m, t)},
                                                  children))

    yield from _each(src, "tendon", m.ntendon, "tendon", write)


def _tendon_attrs(m, t: int) -> dict:
    out = {}
    if m.tendon_limited[t]:
        out["range"] = _numbers(m.tendon_range[t], 2)
        out.update(_softness("limit", m.tendon_solref_lim[t], m.tendon_solimp_lim[t]))
    if m.tendon_actfrclimited[t]:
        out["actuatorfrcrange"] = _numbers(m.tendon_actfrcrange[t], 2)
    for attr, field in (("stiffness", "tendon_stiffness"), ("damping", "tendon_damping"),
                        ("frictionloss", "tendon_frictionloss"), ("armature", "tendon_armature"),
                        ("margin", "tendon_margin")):
        if float(getattr(m, field)[t]):
            out[attr] = fmt(getattr(m, field)[t])
    if float(m.tendon_stiffness[t]):
        out["springlength"] = _numbers(m.tendon_lengthspring[t], 2)
    if float(m.tendon_frictionloss[t]):
        out.update(_softness("friction", m.tendon_solref_fri[t], m.tendon_solimp_fri[t]))
    return out


def _softness(what: str, solref, solimp) -> dict:
    out = {}
    if not np.allclose(solref, SOLREF):
        out[f"solref{what}"] = _numbers(solref, 2)
    if not np.allclose(solimp, SOLIMP):
        out[f"solimp{what}"] = _numbers(solimp, 5)
    return out


def _actuators(src, tree, names: Names):
    m, enums = src.model, mj.load()

    def write(a: int):
        if a not in tree.refused:
            return None
        try:
            return tree.refused[a], _xml("general", _actuator(m, a, names, enums))
        except Dropped as why:
            raise Dropped(f"{tree.refused[a]} ({why})") from None

    yield from _each(src, "actuator", m.nu, "actuator", write)


def _actuator(m, a: int, names: Names, enums) -> dict:
    """The attributes of a ``<general>`` actuator as the original compiled it."""
    trn = enums.mjtTrn
    kind, target = int(m.actuator_trntype[a]), int(m.actuator_trnid[a][0])
    if kind in (trn.mjTRN_JOINT, trn.mjTRN_JOINTINPARENT):
        where = {"jointinparent" if kind == trn.mjTRN_JOINTINPARENT else "joint": names.joint(target)}
    elif kind == trn.mjTRN_TENDON:
        where = {"tendon": names.tendon(target)}
    elif kind == trn.mjTRN_SITE:
        ref = int(m.actuator_trnid[a][1])
        where = {"site": names.site(target), **({"refsite": names.site(ref)} if ref >= 0 else {})}
    elif kind == trn.mjTRN_BODY:
        where = {"body": names.body(target)}
    else:
        raise Dropped("its transmission is not kept")
    if float(m.actuator_damping[a]) or float(m.actuator_armature[a]):
        raise Dropped("its damping or armature is not kept")
    return {"name": names.own("actuator", a), **where, **_actuator_attrs(m, a, enums)}


def _actuator_attrs(m, a: int, enums) -> dict:
    out = {"dyntype": enums.mjtDyn(int(m.actuator_dyntype[a])).name.removeprefix("mjDYN_").lower(),
           "gaintype": enums.mjtGain(int(m.actuator_gaintype[a])).name.removeprefix("mjGAIN_").lower(),
           "biastype": enums.mjtBias(int(m.actuator_biastype[a])).name.removeprefix("mjBIAS_").lower(),
           "dynprm": _numbers(m.actuator_dynprm[a]), "gainprm": _numbers(m.actuator_gainprm[a]),
           "biasprm": _numbers(m.actuator_biasprm[a]), "gear": _numbers(m.actuator_gear[a])}
    for what in ("ctrl", "force", "act"):
        limited = int(getattr(m, f"actuator_{what}limited")[a])
        out[f"{what}limited"] = "true" if limited else "false"
        if limited:
            out[f"{what}range"] = _numbers(getattr(m, f"actuator_{what}range")[a], 2)
    if any(m.actuator_lengthrange[a]):
        out["lengthrange"] = _numbers(m.actuator_lengthrange[a], 2)
    if m.actuator_actearly[a]:
        out["actearly"] = "true"
    return out


def _equalities(src, tree, names: Names):
    m = src.model

    def write(e: int):
        if e in tree.mimics or e in names.looped:
            return None
        kind = EQ_KINDS.get(int(m.eq_type[e]))
        attrs = {"name": None, **_equality_target(m, e, kind, names)}
        attrs["name"] = names.own("equality", e)
        if not m.eq_active0[e]:
            attrs["active"] = "false"
        attrs.update({k: v for k, v in (("solref", _numbers(m.eq_solref[e], 2)), ("solimp", _numbers(m.eq_solimp[e], 5)))
                      if not np.allclose(m.eq_solref[e] if k == "solref" else m.eq_solimp[e],
                                         SOLREF if k == "solref" else SOLIMP)})
        return "the recipe has no loop closures or couplings of this kind", _xml(kind, attrs)

    yield from _each(src, "equality", m.neq, lambda e: f"equality {EQ_KINDS.get(int(m.eq_type[e]), m.eq_type[e])}",
                     write)


LOOP = "the recipe's loop '{name}': URDF and SDF are trees, which leave it open"


def _loops(src, tree, names: Names, ledger) -> dict:
    """The recipe's ``loops``: the active connect and weld constraints between two imported
    bodies or sites, with their softness (solref, solimp, a weld's torque scale) where it is not
    MuJoCo's default (the others are verbatim), each end in its link's frame: a site's on its
    body's link, not on the site's frame link (massless: MuJoCo's constraint softness weighs the
    constrained bodies, and a soft loop on massless links moves otherwise)."""
    m, specs, out = src.model, list(src.spec.equalities), {}
    sites = int(mj.load().mjtObj.mjOBJ_SITE)
    for e in range(m.neq):
        kind = EQ_KINDS.get(int(m.eq_type[e]))
        data = np.asarray(m.eq_data[e], float)
        if kind not in ("connect", "weld") or not m.eq_active0[e]:
            continue
        a, b = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        try:
            if int(m.eq_objtype[e]) == sites:  # each site's frame on its body's link (MuJoCo weighs the bodies)
                ends = [(names.body(int(m.site_bodyid[s])),
                         origin(m.site_pos[s] - names.offset(int(m.site_bodyid[s])),
                                quat_matrix(m.site_quat[s]) if kind == "weld" else np.eye(3))) for s in (a, b)]
            elif kind == "connect":
                ends = [(names.body(a), origin(data[:3] - names.offset(a), np.eye(3))),
                        (names.body(b), origin(data[3:6] - names.offset(b), np.eye(3)))]
            else:  # body1's point and the relative orientation; body2's anchor
                ends = [(names.body(a), origin(data[3:6] - names.offset(a), quat_matrix(data[6:10]))),
                        (names.body(b), origin(data[:3] - names.offset(b), np.eye(3)))]
            if any(link == "world" and "world" not in tree.links for link, _ in ends):
                raise Dropped("the robot has no world link")
        except Dropped:
            continue  # kept verbatim, or dropped saying why (_equalities)
        eq = m.eq(e).name
        name = eq if valid_name(eq) and eq not in names.taken.get("equality", set()) else f"loop{e}"
        names.taken.setdefault("equality", set()).add(name)
        loop = {"type": kind} if kind == "weld" else {}
        for k, (link, o) in enumerate(ends, 1):
            loop[f"link{k}"] = link
            if o:
                loop[f"origin{k}"] = o
        out[name] = loop | _loop_softness(m, e, kind)
        names.looped.add(e)
        tree.verbatim.setdefault("equality", {})[e] = name
        ledger.add(src.where(specs[e]) if e < len(specs) else src.where(),
                   f"equality {kind}" + (f" '{eq}'" if eq else f" #{e}"), OTHERS, LOOP.format(name=name))
    return out


def _loop_softness(m, e: int, kind: str) -> dict:
    """A loop's softness where it is not MuJoCo's default: solref, solimp, a weld's torquescale."""
    out = {}
    if not np.allclose(m.eq_solref[e], SOLREF, rtol=0, atol=0):
        out["solref"] = [float(v) for v in m.eq_solref[e]]
    if not np.allclose(m.eq_solimp[e], SOLIMP, rtol=0, atol=0):
        out["solimp"] = [float(v) for v in m.eq_solimp[e]]
    if kind == "weld" and float(m.eq_data[e][10]) != 1:
        out["torquescale"] = float(m.eq_data[e][10])
    return out


def _equality_target(m, e: int, kind: str | None, names: Names) -> dict:
    """The constrained objects and the constraint's data, in the rebuilt model's frames."""
    a, b, data = int(m.eq_obj1id[e]), int(m.eq_obj2id[e]), np.asarray(m.eq_data[e], float)
    sites = int(m.eq_objtype[e]) == int(mj.load().mjtObj.mjOBJ_SITE)
    if kind in ("connect", "weld") and sites:
        out = {"site1": names.site(a), "site2": names.site(b)}
        return out if kind == "connect" else {**out, "torquescale": fmt(data[10])}
    if kind == "connect" and not names.same_at_zero(e):  # two frame links at its two points, as sites
        return {"site1": names.anchor(e, a, data[:3], 1), "site2": names.anchor(e, b, data[3:6], 2)}
    if kind == "connect":  # the anchor in body1's frame (MuJoCo finds it in body2's at the zero configuration)
        return {"body1": names.body(a), "body2": names.body(b), "anchor": _numbers(data[:3] - names.offset(a), 3)}
    if kind == "weld":  # the anchor in body2's frame; body2's pose in body1's
        pose = np.concatenate([data[3:6] - names.offset(a), data[6:10]])
        return {"body1": names.body(a), "body2": names.body(b), "anchor": _numbers(data[:3] - names.offset(b), 3),
                "relpose": _numbers(pose, 7), "torquescale": fmt(data[10])}
    if kind in ("joint", "tendon"):
        name = names.joint if kind == "joint" else names.tendon
        return {f"{kind}1": name(a), **({f"{kind}2": name(b)} if b >= 0 else {}),
                "polycoef": names.coupling(kind, a, b, data[:5])}
    raise Dropped(f"the recipe has no {kind} constraints")


def _sensors(src, tree, names: Names):
    m, enums = src.model, mj.load()

    def write(i: int):
        if i in tree.kept_sensors:
            return None
        tag = enums.mjtSensor(int(m.sensor_type[i])).name.removeprefix("mjSENS_").lower()
        tag = {"jointactfrc": "jointactuatorfrc", "tendonactfrc": "tendonactuatorfrc"}.get(tag, tag)
        target = _sensor_target(m, i, tag, names)
        attrs = {"name": names.own("sensor", i), **target}
        if float(m.sensor_noise[i]):
            attrs["noise"] = fmt(m.sensor_noise[i])
        if float(m.sensor_cutoff[i]):
            attrs["cutoff"] = fmt(m.sensor_cutoff[i])
        return f"the recipe has no {tag} sensors", _xml(tag, attrs)

    yield from _each(src, "sensor", m.nsensor, lambda i: "sensor", write)


SITE_SENSORS = ("touch", "accelerometer", "velocimeter", "gyro", "force", "torque", "magnetometer", "rangefinder")
BODY_SENSORS = ("touch", "force", "torque")
"""Site sensors that read the site's body (its contacts, the force from its parent), not the site's motion."""


def _sensor_target(m, i: int, tag: str, names: Names) -> dict:
    obj, ref = int(m.sensor_objid[i]), int(m.sensor_refid[i])
    if tag in BODY_SENSORS:  # the rebuild's site is on a frame link: a body of its own, massless, without geoms
        site = m.site(obj).name
        raise Dropped(f"it reads the contacts of site '{site}''s body, and the rebuild holds the site on a frame link "
                      "of its own (a body without geoms)" if tag == "touch" else
                      f"it reads the force between site '{site}''s body and its parent, and the rebuild holds the site "
                      "on a frame link of its own (a massless body)")
    if tag in SITE_SENSORS:
        return {"site": names.site(obj)}
    for prefix, attr, name in (("joint", "joint", names.joint), ("tendon", "tendon", names.tendon),
                               ("actuator", "actuator", names.actuator)):
        if tag.startswith(prefix):
            return {attr: name(obj)}
    if tag.startswith("frame"):
        oriented = tag in ("framequat", "framexaxis", "frameyaxis", "framezaxis")
        kind, name = names.object(int(m.sensor_objtype[i]), obj, oriented)
        out = {"objtype": kind, "objname": name}
        if ref >= 0:
            rkind, rname = names.object(int(m.sensor_reftype[i]), ref, True)
            out.update(reftype=rkind, refname=rname)
        return out
    if tag.startswith("subtree"):
        return {"body": names.body(obj)}
    raise Dropped(f"the recipe has no {tag} sensors")


def _custom(m) -> list[str]:
    mujoco = mj.load()
    out = []
    for i in range(m.nnumeric):
        adr, size = int(m.numeric_adr[i]), int(m.numeric_size[i])
        out.append(_xml("numeric", {"name": mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_NUMERIC, i),
                                    "data": " ".join(fmt(v) for v in m.numeric_data[adr:adr + size])}))
    for i in range(m.ntext):
        adr, size = int(m.text_adr[i]), int(m.text_size[i])
        text = bytes(m.text_data[adr:adr + size]).split(b"\0")[0].decode("utf-8", "replace")
        out.append(_xml("text", {"name": mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TEXT, i), "data": text}))
    return out
