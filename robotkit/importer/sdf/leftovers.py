"""What a link's visuals and collisions, and a joint, set away from SDF's defaults that the recipe
has no place for: named on the ledger (one line per link or joint), so that nothing the rebuild
lacks is missing from it."""

from __future__ import annotations

from robotkit.importer.sdf.model import children

VISUAL = {"transparency": "0", "cast_shadows": "true", "laser_retro": "0", "visibility_flags": "4294967295"}
VISUAL_KEPT = {"geometry", "pose", "material"}
MATERIAL_KEPT = {"diffuse", "ambient", "script"}
MATERIAL = {"specular": "0 0 0 1", "emissive": "0 0 0 1", "lighting": "true", "render_order": "0",
            "double_sided": "false", "shader": None}
COLLISION_KEPT = {"geometry", "pose", "surface", "laser_retro", "max_contacts"}
STANDARD_SCRIPTS = "file://media/materials/scripts/gazebo.material"
JOINT_KEPT = {"parent", "child", "pose", "axis", "axis2", "thread_pitch", "screw_thread_pitch",
              "gearbox_ratio", "gearbox_reference_body", "sensor"}
AXIS = {"initial_position": "0", "use_parent_model_frame": None}
LIMIT = {"stiffness": "100000000", "dissipation": "1"}
DYNAMICS = {"spring_reference": "0", "spring_stiffness": "0"}


def same(text: str | None, default: str | None) -> bool:
    """Whether an element's text is SDF's default (numbers compared as numbers)."""
    if default is None:
        return True
    t, d = (text or "").split(), default.split()
    try:
        return [float(v) for v in t] == [float(v) for v in d]
    except ValueError:
        return [v.lower() for v in t] in ([v.lower() for v in d], ["1"] if d == ["true"] else [], ["0"] if d ==
                                          ["false"] else [])


def shape_leftovers(link_el) -> list[str]:
    out = []
    for v in children(link_el, "visual"):
        out += [f"visual '{v.get('name')}' <{c.tag}>" for c in v if isinstance(c.tag, str)
                and c.tag not in VISUAL_KEPT and not same(c.text, VISUAL.get(c.tag, ""))]
        mat = v.find("material")
        if mat is None:
            continue
        out += [f"visual '{v.get('name')}' material <{c.tag}>" for c in mat if isinstance(c.tag, str)
                and c.tag not in MATERIAL_KEPT and not same(c.text, MATERIAL.get(c.tag, ""))]
    for c in children(link_el, "collision"):
        out += [f"collision '{c.get('name')}' <{x.tag}>" for x in c if isinstance(x.tag, str)
                and x.tag not in COLLISION_KEPT]
    return out


def script_uris(link_el) -> list[tuple[str, tuple[str, ...]]]:
    """(visual name, its material script's <uri>s) of each visual of the link whose script is not
    Gazebo's standard materials (which the import reads: robotkit.importer.sdf.shapes)."""
    out = []
    for v in children(link_el, "visual"):
        uris = tuple((u.text or "").strip() for u in v.findall("material/script/uri"))
        if any(u not in (STANDARD_SCRIPTS, "__default__") for u in uris):  # __default__: libsdformat's, for none
            out.append((v.get("name"), uris))
    return out


def joint_leftovers(el) -> list[str]:
    out = [f"<{c.tag}>" for c in el if isinstance(c.tag, str) and c.tag not in JOINT_KEPT]
    for tag in ("axis", "axis2"):
        axis = el.find(tag)
        if axis is None:
            continue
        out += [f"<{tag}><{c.tag}>" for c in axis if isinstance(c.tag, str)
                and c.tag not in ("xyz", "limit", "dynamics") and not same(c.text, AXIS.get(c.tag, ""))]
        for part, defaults, kept in (("limit", LIMIT, {"lower", "upper", "effort", "velocity"}),
                                     ("dynamics", DYNAMICS, {"damping", "friction"})):
            node = axis.find(part)
            out += [f"<{tag}><{part}><{c.tag}> {' '.join((c.text or '').split())}" for c in
                    (node if node is not None else []) if isinstance(c.tag, str) and c.tag not in kept
                    and not same(c.text, defaults.get(c.tag, ""))]
    return out
