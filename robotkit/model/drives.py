"""The recipe's drives, named poses and self-collision settings, resolved: actuators on joints that can carry them (the
motor's reflected inertia folded into the joint's armature) and poses within the joints' limits.

The gains of ``gains: auto`` are not known here (they need the robot's inertials): the tuner
(:mod:`robotkit.model.gains`) fills them in once the build has the inertials."""

from __future__ import annotations

import difflib
from dataclasses import replace
from typing import Callable

from robotkit.errors import short_number
from robotkit.model.robot import Actuator, Dynamics, Joint, NamedPose
from robotkit.model.selfcollision import Settings

Report = Callable[[tuple, str], None]
ACTUATED = ("revolute", "continuous", "prismatic")


def unknown_name(kind: str, value: str, known) -> str:
    """``no joint named 'x' (did you mean 'y'?)``."""
    msg = f"no {kind} named '{value}'"
    close = difflib.get_close_matches(value, list(known), n=1)
    return msg + (f" (did you mean '{close[0]}'?)" if close else "")


def _refusal(name: str, a, j: Joint | None, known) -> tuple[tuple, str] | None:
    """Why the actuator ``a`` cannot drive joint ``j`` (key below the actuator, message), or None."""
    if j is None:
        return (), unknown_name("joint", name, known)
    if j.type not in ACTUATED:
        return (), f"joint '{name}' is {j.type}: only revolute, continuous and prismatic joints can be actuated"
    if j.mimic is not None:
        return (), f"joint '{name}' mimics '{j.mimic.joint}'; actuate the joint it follows"
    if a.interface == "effort" and (j.limit is None or not j.limit.effort):
        return (), f"an effort actuator needs joint '{name}' to have an effort limit"
    if a.gains == "auto" and a.interface == "position" and j.type == "continuous":
        return ("gains",), (f"gains: auto on a position drive needs joint '{name}' to have limits; "
                            "a continuous joint takes a velocity interface")
    if a.gains == "auto" and (j.limit is None or not j.limit.effort):
        return ("gains",), f"gains: auto needs joint '{name}' to have an effort limit (the saturation check)"
    return None


def resolve_actuators(report: Report, actuators: dict, joints: list[Joint]) -> tuple[list[Actuator], list[Joint]]:
    """(the recipe's actuators, the joints with each motor's armature added to their dynamics)."""
    out = []
    by_name = {j.name: j for j in joints}
    armature: dict[str, float] = {}
    for name, a in actuators.items():
        why = _refusal(name, a, by_name.get(name), by_name)
        if why is not None:
            report(("actuators", name) + why[0], why[1])
            continue
        arm = a.motor.rotor_inertia * a.motor.gear ** 2 if a.motor is not None else float(a.armature or 0.0)
        if arm > 1e6:
            report(("actuators", name, "motor"), f"gives an armature of {short_number(arm)} kg m^2 (over 1e6)")
            continue
        armature[name] = arm
        out.append(Actuator(name, a.interface, float(a.p), float(a.i), float(a.d), auto=a.gains == "auto",
                            bandwidth=a.bandwidth, damping_ratio=float(a.damping_ratio), armature=arm))
    return out, [_with_armature(j, armature.get(j.name, 0.0)) for j in joints]


def _with_armature(j: Joint, arm: float) -> Joint:
    if not arm:
        return j
    dyn = j.dynamics or Dynamics()
    return replace(j, dynamics=replace(dyn, armature=dyn.armature + arm))


def resolve_poses(report: Report, poses: dict, joints: list[Joint]) -> list[NamedPose]:
    """Each named pose, its joints checked: they exist, move on their own, and stay in their limits."""
    by_name = {j.name: j for j in joints}
    out = []
    for pose_name, values in poses.items():
        kept = []
        for joint, value in values.items():
            path = ("poses", pose_name, joint)
            j = by_name.get(joint)
            if j is None:
                report(path, unknown_name("joint", joint, by_name))
            elif j.type not in ACTUATED:
                report(path, f"joint '{joint}' is {j.type}: a pose sets revolute, continuous and prismatic joints")
            elif j.mimic is not None:
                report(path, f"joint '{joint}' mimics '{j.mimic.joint}'; set the joint it follows")
            elif j.limit is not None and j.limit.lower is not None and not (
                    j.limit.lower - 1e-12 <= value <= j.limit.upper + 1e-12):
                report(path, f"{short_number(value)} is outside the limits of joint '{joint}' "
                             f"[{short_number(j.limit.lower)}, {short_number(j.limit.upper)}]")
            else:
                kept.append((joint, float(value)))
        out.append(NamedPose(pose_name, tuple(kept)))
    return out


def resolve_settings(report, spec, link_names: list[str]) -> Settings:
    """The recipe's ``self_collision`` checked: pairs name two different existing links, and no
    pair is both allowed and checked.  ``report(path, message)`` collects the problems."""
    pairs: dict[str, list[tuple]] = {"allow": [], "check": []}
    for kind in ("allow", "check"):
        for i, entry in enumerate(getattr(spec, kind)):
            a, b = entry[0], entry[1]
            bad = [n for n in (a, b) if n not in link_names]
            for n in bad:
                report(("self_collision", kind, i), unknown_name("link", n, link_names))
            if not bad and a == b:
                report(("self_collision", kind, i), f"a pair names two links; '{a}' is named twice")
            elif not bad:
                pairs[kind].append((*sorted((a, b)), entry[2] if len(entry) > 2 else ""))
    allowed = {p[:2] for p in pairs["allow"]}
    for i, p in enumerate(pairs["check"]):
        if p[:2] in allowed:
            report(("self_collision", "check", i), f"pair '{p[0]}', '{p[1]}' is also in self_collision.allow")
    return Settings(spec.samples, spec.seed, tuple(pairs["allow"]), tuple(p[:2] for p in pairs["check"]))
