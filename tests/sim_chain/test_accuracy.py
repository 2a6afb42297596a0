"""Steady-state accuracy (the paper's Fig. 5a) on the synthetic table, and the default-table loader."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.chain.accuracy import plot_accuracy, point_to_polyline_m, steady_state_accuracy
from robowrangler_sim.chain.default_table import DefaultShapeTableMissing, load_default_shape_table


def test_point_to_polyline_distance():
    line = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    d = point_to_polyline_m(np.array([[0.5, 0.2], [2.0, 0.5], [-1.0, 0.0]]), line)
    np.testing.assert_allclose(d, [0.2, 1.0, 1.0])


def test_settled_chain_is_within_the_papers_error_at_every_phi(table, tmp_path):
    report = steady_state_accuracy(table, settle_s=3.0)
    assert report.phi_deg.tolist() == table.phi_deg.tolist()
    # paper: max 4 cm over all angles on a 2 m loop (2 %); ours on this table: about 2 %
    assert report.worst_max_m < 0.025 * report.loop_length_m
    assert np.all(report.mean_m < report.max_m) and np.all(report.mean_m < 0.015)
    assert np.all(report.closure_gap_m < 0.005)
    plot_accuracy(report, tmp_path / "acc.png")
    assert (tmp_path / "acc.png").stat().st_size > 10_000


def test_default_table_loader_names_the_missing_file(tmp_path):
    missing = tmp_path / "nope.json"
    with pytest.raises(DefaultShapeTableMissing, match="nope.json"):
        load_default_shape_table(path=missing)


def test_default_table_when_it_ships_drives_the_chain(skip_unless_ci):
    try:
        table = load_default_shape_table()
    except DefaultShapeTableMissing as exc:
        skip_unless_ci(f"no default table: {exc}")
    report = steady_state_accuracy(table, settle_s=3.0, phi_deg=table.phi_deg[[0, -1]])
    assert np.all(np.isfinite(report.max_m))
    assert report.worst_max_m < 0.05 * report.loop_length_m
