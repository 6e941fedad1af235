"""MuJoCo actuators as recipe actuators (by joint): a position servo (gain kp, bias
``0 -kp -kv``) is ``interface: position`` with ``p: kp, d: kv``; a velocity servo (gain kv,
bias ``0 0 -kv``) is ``interface: velocity`` with ``p: kv``; a motor (gain 1, no bias) is
``interface: effort``.  The force limit (``forcerange``, the joint's ``actuatorfrcrange``, a
motor's ``ctrlrange`` times its gear) is the joint's effort limit; a velocity servo's
``ctrlrange`` its velocity limit.  Anything else (another transmission, dynamics, a gain or bias
of another form, a second actuator on a joint) is on the ledger."""

from __future__ import annotations

import numpy as np

from robotkit.importer.mjcf.tree import UNLIMITED

TRN_JOINT = 0
AFFINE = 1


def _kind(m, a: int) -> tuple[str, dict] | None:
    """(interface, gains) of an actuator the recipe expresses, else None."""
    gain, bias = [float(v) for v in m.actuator_gainprm[a][:3]], [float(v) for v in m.actuator_biasprm[a][:3]]
    if int(m.actuator_gaintype[a]) != 0 or int(m.actuator_dyntype[a]) != 0 or any(m.actuator_gainprm[a][1:]):
        return None
    btype = int(m.actuator_biastype[a])
    if btype == AFFINE and bias[0] == 0 and gain[0] > 0 and bias[1] == -gain[0] and bias[2] <= 0:
        return "position", {"p": gain[0], **({"d": -bias[2]} if bias[2] else {})}
    if btype == AFFINE and bias[0] == 0 and bias[1] == 0 and gain[0] > 0 and bias[2] == -gain[0]:
        return "velocity", {"p": gain[0]}
    if (btype == 0 or not any(bias)) and gain[0] == 1:
        return "effort", {}
    return None


def add_actuators(src, tree, recipe: dict, ledger) -> None:
    m = src.model
    out: dict[str, dict] = {}
    efforts: dict[str, float] = {}
    speeds: dict[str, float] = {}
    spec_acts = list(src.spec.actuators)
    for a in range(m.nu):
        name = m.actuator(a).name or f"actuator {a}"
        where = src.where(spec_acts[a]) if a < len(spec_acts) else src.where()
        why = _refusal(m, a, tree, out)
        if why:  # kept verbatim if it can be (robotkit.importer.mjcf.verbatim), on the ledger
            tree.refused[a] = why
            continue
        joint = tree.joint_map[int(m.actuator_trnid[a][0])][0]
        interface, gains = _kind(m, a)
        out[joint] = {"interface": interface, **gains}
        tree.actuated[a] = joint
        _limits(src, a, joint, interface, efforts, speeds, where, name, ledger)
    if out:
        recipe["actuators"] = out
    _fill_limits(src, tree, efforts, speeds, set(out))


def _refusal(m, a: int, tree, out: dict) -> str | None:
    if int(m.actuator_trntype[a]) != TRN_JOINT:
        kinds = {1: "a joint-in-parent", 2: "a slider-crank", 3: "a tendon", 4: "a site", 5: "a body"}
        return f"{kinds.get(int(m.actuator_trntype[a]), 'another')} transmission (the recipe's actuators drive joints)"
    j = int(m.actuator_trnid[a][0])
    if int(m.jnt_type[j]) not in (2, 3):
        return "it drives a free or ball joint"
    if _kind(m, a) is None:
        return "a gain, bias or dynamics other than a position or velocity servo or a motor"
    gear = float(m.actuator_gear[a][0])
    if gear != 1 and _kind(m, a)[0] != "effort":
        return f"gear {gear:g} on a servo (the recipe's servos act on the joint directly)"
    joint = tree.joint_map[j][0]
    if joint in out:
        return f"a second actuator on joint '{joint}' (the recipe has one per joint)"
    return None


def _limits(src, a: int, joint: str, interface: str, efforts, speeds, where, name, ledger) -> None:
    m = src.model
    gear = float(m.actuator_gear[a][0])
    lo, hi = (float(v) for v in m.actuator_ctrlrange[a])
    if m.actuator_forcelimited[a]:
        flo, fhi = (float(v) for v in m.actuator_forcerange[a])
        efforts[joint] = max(abs(flo), abs(fhi))
        if flo != -fhi:
            ledger.add(where, f"actuator '{name}'", "all", f"forcerange [{flo:g}, {fhi:g}] written as the symmetric "
                       f"effort limit {efforts[joint]:g}")
    elif interface == "effort" and m.actuator_ctrllimited[a]:
        efforts[joint] = max(abs(lo), abs(hi)) * abs(gear)
    if interface == "velocity" and m.actuator_ctrllimited[a]:
        speeds[joint] = max(abs(lo), abs(hi))
    if interface == "effort" and gear != 1:
        ledger.add(where, f"actuator '{name}'", "all", f"gear {gear:g}: the recipe's motor takes the joint's force "
                   f"(ctrl x {gear:g})")
    if interface == "position" and m.actuator_ctrllimited[a]:
        j = int(m.actuator_trnid[a][0])
        rng = [float(v) for v in m.jnt_range[j]] if m.jnt_limited[j] else None
        if rng is None or not np.allclose(rng, [lo, hi], rtol=0, atol=1e-12):
            ledger.add(where, f"actuator '{name}'", "all", f"ctrlrange [{lo:g}, {hi:g}] written as the joint's range "
                       + (f"[{rng[0]:g}, {rng[1]:g}]" if rng else "(none: a continuous joint)"))


def _fill_limits(src, tree, efforts: dict, speeds: dict, driven: set) -> None:
    """Every joint's effort (force limits, else the joint's ``actuatorfrcrange``) and velocity (a
    velocity servo's range: MuJoCo has no velocity limit); a limit the MJCF does not give is 0 on
    a joint nothing drives (passive), :data:`UNLIMITED` on a driven one (stated above the joint)."""
    m = src.model
    for j, recipe_names in tree.joint_map.items():
        for name in recipe_names:
            joint = tree.joints.get(name)
            if joint is None or joint["type"] in ("floating", "fixed"):
                continue
            effort = efforts.get(name)
            if effort is None and m.jnt_actfrclimited[j]:
                effort = float(max(abs(v) for v in m.jnt_actfrcrange[j]))
            limit = joint.setdefault("limit", {})
            free = UNLIMITED if name in driven else 0.0
            limit["effort"], limit["velocity"] = effort or free, speeds.get(name) or free
            unbounded = [k for k in ("effort", "velocity") if name in driven and limit[k] == UNLIMITED]
            if unbounded:
                said = f"driven, with no {' or '.join(unbounded)} limit in the MJCF (unlimited): {UNLIMITED:g}"
                tree.notes[name] = f"{tree.notes[name]}; {said}" if name in tree.notes else said
