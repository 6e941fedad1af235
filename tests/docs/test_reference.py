"""docs/recipe.md, the full recipe reference, documents every key of the JSON Schema: one
section per schema model (anchored by the model's name), one table row per property.
(That the file is the generator's output is tests/recipe/test_recipe.py's
test_reference_docs_are_current.)"""

import json
import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"


def documented() -> dict[str, set[str]]:
    """{section anchor: the keys its table documents} of docs/recipe.md."""
    out, current = {}, None
    for line in (DOCS / "recipe.md").read_text(encoding="utf-8").splitlines():
        if m := re.fullmatch(r'<a id="([a-z0-9]+)"></a>', line):
            current = out.setdefault(m.group(1), set())
        elif current is not None and (m := re.match(r"\| `([^`]+)` \|", line)):
            current.add(m.group(1))
    return out


def test_every_schema_key_is_documented():
    docs = documented()
    for name in ("recipe.schema.json", "part.schema.json"):
        schema = json.loads((DOCS / name).read_text(encoding="utf-8"))
        models = dict(schema["$defs"])
        if "properties" in schema:  # the recipe's top level (the part schema refers to its Part)
            models["Recipe"] = schema
        for model, definition in models.items():
            assert model.lower() in docs, f"docs/recipe.md has no section for {model}"
            assert set(definition["properties"]) == docs[model.lower()], model


def test_the_sections_asked_for_are_there():
    """The sections the reference once lacked (issue 31), with keys of each."""
    docs = documented()
    for model, key in [("sensor", "update_rate"), ("cameraparams", "hfov"), ("lidarparams", "max_range"),
                       ("actuator", "gains"), ("contact", "mu1"), ("collision", "strategy"), ("proxy", "max_vertices"),
                       ("meshdefaults", "collision"), ("world", "unknown_as_wall")]:
        assert key in docs[model], model


def test_types_link_to_their_sections_and_say_the_dimension():
    text = (DOCS / "recipe.md").read_text(encoding="utf-8")
    assert "| `sensors` | mapping of name to [Sensor](#sensor) | {} |" in text
    assert "| `radius` | length | required | Radius in metres. |" in text
    assert "| `hfov` | angle | 1.047 | Horizontal field of view in radians. |" in text
    assert "| `lower` | joint position |  |" in text
    for target in set(re.findall(r"\]\(#([a-z0-9]+)\)", text)):
        assert f'<a id="{target}"></a>' in text, target
