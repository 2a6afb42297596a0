"""Building wire messages in tests: every field not named is 0, so a test stays valid when the schema grows."""

from __future__ import annotations

from robowrangler.protocol import generated as gen


def make(cls: type[gen.Message], **fields: float) -> gen.Message:
    """A message with the given fields and every other field 0."""
    unknown = set(fields) - {f.name for f in cls.FIELDS}
    if unknown:
        raise TypeError(f"{cls.NAME} has no field(s) {sorted(unknown)}")
    return cls(**{f.name: fields.get(f.name, 0) for f in cls.FIELDS})
