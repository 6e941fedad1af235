"""The links of a body's joint chain carry mass taken from the body, placed where it changes nothing.

A body moved by several joints is a chain of links (robotkit.importer.mjcf.tree): link k moves
with the body's first k joints.  A link needs a mass (MuJoCo refuses a moving body without one)
of more than 1e-6 kg (libsdformat's URDF reader, Gazebo's, drops a lighter link with everything
below it): each gets :data:`CHAIN_POINT_MASS` as a point mass (with the least tensor MuJoCo takes,
:data:`CHAIN_MOMENT`) taken from the body, at a point that every later joint of the chain leaves
fixed: a point on the axes of all the later hinges (a ball joint's centre, where its three
hinges meet).  Such a point moves with link k exactly as with the body, so the multibody's mass
matrix and forces are the original's (but for the point's tensor, 1e-12 kg m^2, turning with
the link rather than the body).  The body keeps the rest: its mass less the point's, its centre
of mass and inertia tensor moved so that the two together are the original body
(:func:`take_point_mass`).

A link after which a joint slides (no point stays fixed), after hinges whose axes do not meet,
or of a body too light to give the mass (what is left would not be a physical body) keeps a
millionth of the lightest body's mass (not below the least mass a recipe takes: a fruit fly's
bodies weigh micrograms), added (robotkit.importer.mjcf.tree.CHAIN_MASS): stated on the ledger."""

from __future__ import annotations

import numpy as np

from robotkit.importer.inertials import POINT_MASS_FLOOR
from robotkit.importer.mjcf.frames import clean
from robotkit.model.inertia_policy import MIN_MOMENT, defects, mujoco_ready
from robotkit.recipe.schema import MIN_MASS

CHAIN_POINT_MASS = POINT_MASS_FLOOR
"""kg: the point mass a chain link takes from its body (libsdformat keeps a link above 1e-6 kg)."""
CHAIN_MOMENT = 10 * MIN_MOMENT
"""kg m^2: the principal moments of a chain link's point mass: ten times the least the build
writes into an MJCF (robotkit.model.inertia_policy.MIN_MOMENT), MuJoCo's eigen-decomposition's margin."""
MEET = 1e-10
"""m: hinge axes meet when one point is within this of every one."""
BALL, HINGE = 1, 3


def _steiner(mass: float, d) -> np.ndarray:
    """The inertia of a point mass at ``d`` about the origin."""
    d = np.asarray(d, float)
    return mass * (float(d @ d) * np.eye(3) - np.outer(d, d))


def take_point_mass(mass: float, com, inertia, m: float, p, moment: float):
    """A body (``mass``, centre ``com``, ``inertia`` about it, all in one frame) less a point mass
    ``m`` at ``p`` with principal moments ``moment``: (mass, centre, inertia about it) of the rest,
    which with the point is the body exactly; None when the rest is not a physical body (its mass
    not positive, its tensor not positive definite or breaking the triangle inequality, or too
    close to either for MuJoCo)."""
    rest = mass - m
    if not rest > 0:
        return None
    com, p = np.asarray(com, float), np.asarray(p, float)
    c = (mass * com - m * p) / rest
    I = np.asarray(inertia, float) + _steiner(mass, com - c) - _steiner(m, p - c) - moment * np.eye(3)
    I = 0.5 * (I + I.T)
    if defects(rest, I):
        return None
    ready = mujoco_ready(I)
    if ready is None or not np.array_equal(ready, I):
        return None
    return rest, c, I


def fixed_point(lines, near) -> np.ndarray | None:
    """The point on every line (anchor, unit direction) nearest ``near``; None when they do not meet."""
    near = np.asarray(near, float)
    P = [np.eye(3) - np.outer(u, u) for _, u in lines]
    d = np.linalg.pinv(sum(P)) @ sum(Pi @ (np.asarray(a, float) - near) for Pi, (a, _) in zip(P, lines))
    x = near + d
    if max(float(np.linalg.norm(Pi @ (x - a))) for Pi, (a, _) in zip(P, lines)) > MEET:
        return None
    return x


def _why_not(stages, k: int, com):
    """(the point link ``k`` of a chain with joint ``stages`` takes its mass at, in the body's
    frame, or None; why not)."""
    later = stages[k + 1:]
    slide = next((s for s in later if s[1] not in (BALL, HINGE)), None)
    if slide is not None:
        return None, f"joint '{slide[0]}' after it is not a hinge, so no point of the link stays fixed in the body"
    p = fixed_point([(anchor, axis) for _, _, axis, anchor, _ in later], com)
    if p is None:
        return None, "the axes of the hinges after it do not meet, so no point of the link stays fixed in the body"
    return p, ""


def carve(inertial, points) -> dict | None:
    """A link's explicit inertial (``mass``, ``com``, ``inertia`` as the recipe writes them) less
    a chain link's point mass at each of ``points`` (in the link's frame): the rest, as the recipe
    writes it; None when it is not explicit or the rest would not be a physical body."""
    if not isinstance(inertial, dict) or set(inertial) - {"mass", "com", "inertia"} or "inertia" not in inertial:
        return None
    t = inertial["inertia"]
    full = np.array([[t["ixx"], t.get("ixy", 0.0), t.get("ixz", 0.0)], [t.get("ixy", 0.0), t["iyy"], t.get("iyz", 0.0)],
                     [t.get("ixz", 0.0), t.get("iyz", 0.0), t["izz"]]], float)
    body = (float(inertial["mass"]), np.array(inertial.get("com", (0.0, 0.0, 0.0)), float), full)
    for p in points:
        body = take_point_mass(*body, CHAIN_POINT_MASS, p, CHAIN_MOMENT)
        if body is None:
            return None
    rest, c, I = body
    return {"mass": rest, "com": clean(c), "inertia": recipe_tensor(I)}


def recipe_tensor(full) -> dict:
    """A 3x3 inertia tensor as the recipe writes it (products of inertia that are rounding left out)."""
    out = {"ixx": full[0, 0], "iyy": full[1, 1], "izz": full[2, 2],
           "ixy": full[0, 1], "ixz": full[0, 2], "iyz": full[1, 2]}
    return {k: float(v) for k, v in out.items() if k[1] == k[2] or abs(v) > 1e-15 * abs(full).max()}


def point_inertial(at) -> dict:
    """A chain link's inertial: its point mass at ``at`` (in its frame)."""
    return {"mass": CHAIN_POINT_MASS, "com": clean(at),
            "inertia": {"ixx": CHAIN_MOMENT, "iyy": CHAIN_MOMENT, "izz": CHAIN_MOMENT}}


def place_chain_masses(src, tree, ledger) -> None:
    """Each chain link's mass taken from its body where it can be (see the module docstring)."""
    m = src.model
    for b, (links, stages) in tree.chains.items():
        com = np.array(m.body_ipos[b], float)
        child = tree.links[tree.link_of[b]]
        placed, light, why = {}, [], ""
        for k, link in enumerate(links):
            p, reason = _why_not(stages, k, com)
            rest = carve(child.get("inertial"), [q - tree.offset[b] for q in [*placed.values(), p]]) \
                if p is not None else None
            if rest is None:
                light.append(link)
                why = why or reason or ("the body is too light to give it (what would be left is not a physical body)"
                                        if isinstance(child.get("inertial"), dict) else "the body has no mass to give")
                continue
            placed[link] = p
        if placed:
            child["inertial"] = carve(child["inertial"], [p - tree.offset[b] for p in placed.values()])
        for k, link in enumerate(links):
            if link in placed:
                tree.links[link]["inertial"] = point_inertial(placed[link] - stages[k][3])
                tree.moved[link] = b
        if light:
            _ledger(src, tree, ledger, b, light, why)


def _ledger(src, tree, ledger, b: int, light: list[str], why: str) -> None:
    mass = float(tree.links[light[0]]["inertial"]["mass"])
    share = "a millionth of the lightest body" if mass > MIN_MASS else "the least mass a recipe takes"
    dropped = ("; Gazebo (libsdformat's URDF reader) drops a link of 1e-06 kg or less with everything below it"
               if mass <= 1e-6 else "")
    name = src.model.body(b).name
    links = ", ".join(f"'{n}'" for n in light)
    ledger.add(src.where_named("body", name), f"body '{tree.link_of[b]}' (joint chain)", "all",
               f"approximated: chain link{'s' if len(light) > 1 else ''} {links} carr{'y' if len(light) > 1 else 'ies'} "
               f"an added point mass of {mass:.3g} kg ({share}), not taken from the body: "
               f"{why}{dropped}")


