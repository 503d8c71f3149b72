"""RowControl.next_samples: the one rule for a chunk's length, shared by the driver and the replay."""

from slipchain.engine.control import DeadWeightRamp, RowControl


def test_next_samples_follows_ramp_remaining_and_chunk():
    row = RowControl(limit=50, ramp=DeadWeightRamp(1.0, n_ramp=3))
    lengths = []
    while row.n < row.limit:
        k = row.next_samples(20)
        lengths.append(k)
        row.n += k
    # a sample at a time while the weight rises, then whole chunks, the last cut to what is left
    assert lengths == [1, 1, 1, 20, 20, 7]


def test_next_samples_without_ramp_is_chunk_or_remaining():
    row = RowControl(limit=5)
    assert row.next_samples(20) == 5
    row.n = 2
    assert row.next_samples(2) == 2
    assert row.next_samples(20) == 3
