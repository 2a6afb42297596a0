"""Fixtures of the chain-model tests: the synthetic shape table (the shipped default when it exists)."""

from __future__ import annotations

import pytest

from robowrangler_sim.chain.default_table import load_default_shape_table
from robowrangler_sim.chain.synthetic_table import synthetic_ellipse_table


@pytest.fixture(scope="session")
def table():
    """Synthetic ellipse-like table (-30..40 deg, loop elongated at negative phi), 2 m loop."""
    return synthetic_ellipse_table()


@pytest.fixture(scope="session")
def default_table(table):
    """The shipped default table (from the first-principles simulator), or the synthetic one if it is missing."""
    try:
        return load_default_shape_table()
    except FileNotFoundError:
        return table
