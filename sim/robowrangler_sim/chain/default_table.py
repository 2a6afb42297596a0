"""Where the chain model's default shape table comes from, and the fallback when it is missing.

The default is ``robowrangler_sim/data/shape_table_default.json`` (made from first-principles physics of
the air-lifted loop; its ``source`` field says how). A user replaces it by passing their own table,
identified from their photos, to ChainPlant(table=ShapeTable.load(path)).
"""

from __future__ import annotations

import warnings
from pathlib import Path

from robowrangler_sim.shape_table import ShapeTable

DEFAULT_TABLE_PATH = Path(__file__).resolve().parents[1] / "data" / "shape_table_default.json"


class DefaultShapeTableMissing(FileNotFoundError):
    """The shipped default shape table file does not exist."""


def load_default_shape_table(*, path: Path | None = None) -> ShapeTable:
    """Load the shipped default table; raises DefaultShapeTableMissing (naming the path) if absent."""
    p = DEFAULT_TABLE_PATH if path is None else Path(path)
    if not p.exists():
        raise DefaultShapeTableMissing(
            f"default shape table: expected the file {p}, which does not exist; pass table=... "
            "(ShapeTable.load of your own table) or use synthetic_ellipse_table()")
    return ShapeTable.load(p)


def default_or_synthetic_table() -> ShapeTable:
    """The shipped default table, or (with a warning naming the missing file) the synthetic one."""
    try:
        return load_default_shape_table()
    except DefaultShapeTableMissing as exc:
        from robowrangler_sim.chain.synthetic_table import synthetic_ellipse_table

        warnings.warn(f"{exc}; falling back to the synthetic ellipse table", stacklevel=2)
        return synthetic_ellipse_table()
