"""A validator for the subset of JSON Schema (draft 2020-12) the recording schemas use.

No third-party validator is a dependency of the host package, so this module checks exactly the
keywords below and refuses a schema that uses any other (SchemaKeywordError), so that a schema can
never be silently under-checked. Annotations ($schema, $id, $comment, title, description) are ignored.

    errors = first_error(instance, schema)   # None if valid, else "path: reason"
"""

from __future__ import annotations

import math
import re
from typing import Any

ANNOTATIONS = frozenset({"$schema", "$id", "$comment", "title", "description"})
KEYWORDS = frozenset({"type", "properties", "required", "additionalProperties", "patternProperties", "enum",
                      "const", "minimum", "maximum", "items", "minItems", "maxItems", "uniqueItems", "anyOf",
                      "pattern", "minLength"})


class SchemaKeywordError(ValueError):
    """The schema uses a keyword this validator does not implement."""


def _is_type(value: Any, name: str) -> bool:
    if name == "null":
        return value is None
    if name == "boolean":
        return isinstance(value, bool)
    if name == "integer":
        return (isinstance(value, int) and not isinstance(value, bool)) or (
            isinstance(value, float) and math.isfinite(value) and value.is_integer())
    if name == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if name == "string":
        return isinstance(value, str)
    if name == "array":
        return isinstance(value, list)
    if name == "object":
        return isinstance(value, dict)
    raise SchemaKeywordError(f"type: unknown JSON type {name!r}")


def check_keywords(schema: Any, where: str = "#") -> None:
    """Raise SchemaKeywordError if the schema (recursively) uses a keyword outside KEYWORDS."""
    if not isinstance(schema, dict):
        raise SchemaKeywordError(f"{where}: a schema must be an object, got {type(schema).__name__}")
    for key, sub in schema.items():
        if key in ANNOTATIONS:
            continue
        if key not in KEYWORDS:
            raise SchemaKeywordError(f"{where}: keyword {key!r} is not supported (supported: {sorted(KEYWORDS)})")
        if key in ("properties", "patternProperties"):
            for name, s in sub.items():
                check_keywords(s, f"{where}/{key}/{name}")
        elif key in ("items",) or (key == "additionalProperties" and isinstance(sub, dict)):
            check_keywords(sub, f"{where}/{key}")
        elif key == "anyOf":
            for i, s in enumerate(sub):
                check_keywords(s, f"{where}/anyOf/{i}")


def first_error(instance: Any, schema: dict, path: str = "") -> str | None:
    """The first violation as "path: reason" (path like /fields/rope_speed_mps), or None if valid."""
    here = path or "/"
    types = schema.get("type")
    if types is not None:
        names = [types] if isinstance(types, str) else list(types)
        if not any(_is_type(instance, t) for t in names):
            return f"{here}: expected {' or '.join(names)}, got {_show(instance)}"
    if "const" in schema and not _equal(instance, schema["const"]):
        return f"{here}: expected {schema['const']!r}, got {_show(instance)}"
    if "enum" in schema and not any(_equal(instance, v) for v in schema["enum"]):
        return f"{here}: expected one of {schema['enum']}, got {_show(instance)}"
    if _is_type(instance, "number"):
        if isinstance(instance, float) and not math.isfinite(instance):
            return f"{here}: expected a finite number, got {instance!r}"
        if "minimum" in schema and instance < schema["minimum"]:
            return f"{here}: expected >= {schema['minimum']}, got {instance!r}"
        if "maximum" in schema and instance > schema["maximum"]:
            return f"{here}: expected <= {schema['maximum']}, got {instance!r}"
    if isinstance(instance, str):
        if "minLength" in schema and len(instance) < schema["minLength"]:
            return f"{here}: expected at least {schema['minLength']} characters, got {instance!r}"
        if "pattern" in schema and re.search(schema["pattern"], instance) is None:
            return f"{here}: expected a string matching {schema['pattern']}, got {instance!r}"
    if isinstance(instance, list):
        if "minItems" in schema and len(instance) < schema["minItems"]:
            return f"{here}: expected at least {schema['minItems']} items, got {len(instance)}"
        if "maxItems" in schema and len(instance) > schema["maxItems"]:
            return f"{here}: expected at most {schema['maxItems']} items, got {len(instance)}"
        if schema.get("uniqueItems"):
            seen = []
            for item in instance:
                if any(_equal(item, s) for s in seen):
                    return f"{here}: expected unique items, {_show(item)} repeats"
                seen.append(item)
        if "items" in schema:
            for i, item in enumerate(instance):
                err = first_error(item, schema["items"], f"{path}/{i}")
                if err:
                    return err
    if isinstance(instance, dict):
        for name in schema.get("required", ()):
            if name not in instance:
                return f"{here}: missing required field {name!r}"
        props = schema.get("properties", {})
        patterns = schema.get("patternProperties", {})
        for name, value in instance.items():
            matched = False
            if name in props:
                matched = True
                err = first_error(value, props[name], f"{path}/{name}")
                if err:
                    return err
            for pattern, sub in patterns.items():
                if re.search(pattern, name):
                    matched = True
                    err = first_error(value, sub, f"{path}/{name}")
                    if err:
                        return err
            if not matched:
                extra = schema.get("additionalProperties", True)
                if extra is False:
                    allowed = sorted(props) + [f"/{p}/" for p in patterns]
                    return f"{here}: unexpected field {name!r} (allowed: {', '.join(allowed)})"
                if isinstance(extra, dict):
                    err = first_error(value, extra, f"{path}/{name}")
                    if err:
                        return err
    if "anyOf" in schema:
        errors = [first_error(instance, sub, path) for sub in schema["anyOf"]]
        if all(errors):
            return f"{here}: matches none of the allowed forms ({'; '.join(errors)})"
    return None


def _equal(a: Any, b: Any) -> bool:
    if isinstance(a, bool) != isinstance(b, bool):
        return False
    return a == b


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
