"""Sequence-gap detection over uint16 frame numbers: gaps, the wrap, duplicates, reordering, restarts."""

from __future__ import annotations

import pytest

from robowrangler.recorder.gaps import SeqGapDetector, find_gaps


def test_consecutive_frames_have_no_gap_even_across_the_wrap() -> None:
    assert find_gaps([65533, 65534, 65535, 0, 1, 2]) == []


def test_a_gap_names_the_missing_range_and_count_and_times() -> None:
    gaps = find_gaps([10, 11, 15, 16], host_s=[0.0, 0.02, 0.10, 0.12], time_s=[1.0, 1.02, 1.10, 1.12])
    assert len(gaps) == 1
    g = gaps[0]
    assert (g.from_seq, g.to_seq, g.missing) == (12, 14, 3)
    assert (g.last_time_s, g.resume_time_s) == (1.02, 1.10)
    assert g.silent_s == pytest.approx(0.08)


def test_a_gap_across_the_uint16_wrap() -> None:
    (g,) = find_gaps([65533, 65534, 2, 3])
    assert (g.from_seq, g.to_seq, g.missing) == (65535, 1, 3)  # 65535, 0, 1


def test_duplicates_and_late_frames_are_not_gaps_and_the_baseline_stays() -> None:
    d = SeqGapDetector()
    for seq in (100, 101, 101, 103, 102, 104):  # 101 twice; 102 arrives after 103
        d.feed(seq, host_s=0.0)
    assert (d.duplicates, d.reordered) == (1, 1)
    assert d.gaps == 1 and d.missing == 1  # 102 was counted missing when 103 came, as a live recorder must


def test_a_restart_of_the_numbering_is_a_gap_of_unknown_extent() -> None:
    d = SeqGapDetector()
    gaps = [d.feed(seq, host_s=float(i), time_s=t) for i, (seq, t) in enumerate([(5000, 9.0), (5001, 9.02),
                                                                                    (0, 0.0), (1, 0.02)])]
    restart = gaps[2]
    assert restart is not None and restart.to_seq is None and restart.missing is None
    assert restart.from_seq == 5002 and restart.resume_time_s == 0.0
    assert d.restarts == 1 and gaps[3] is None  # the new numbering is the baseline


def test_open_gap_at_the_end_of_a_silent_link() -> None:
    d = SeqGapDetector()
    assert d.open_gap(host_s=5.0) is None
    d.feed(7, host_s=1.0, time_s=3.0)
    g = d.open_gap(host_s=5.0)
    assert (g.from_seq, g.to_seq, g.resume_time_s, g.silent_s) == (8, None, None, 4.0)
    assert g.to_record()["stream"] == "device"


def test_bad_seq_is_refused_with_the_value() -> None:
    with pytest.raises(ValueError, match=r"seq: expected an integer in \[0, 65535\], got 65536"):
        SeqGapDetector().feed(65536, host_s=0.0)
