"""The recorder's per-contact records (engine.observers.Recorder), property-tested on random chunk sequences.

A spring-driven row keeps a record per chunk until ``record_cap`` and merges them pairwise past it; the
physics tests (tests/physics/test_checkpoint.py) check a real run against the per-chunk records. Here the
invariants on any sequence of chunk lengths and caps: each record is the sum of the chunks it covers, starts
at one of them and counts them; every record but the last holds ``width`` chunks; the cap holds; and records
written to a checkpoint mid-way and restored continue to the uninterrupted records bit for bit.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from slipchain.engine import scheme as S
from slipchain.engine.backends.base import ChunkOutput
from slipchain.engine.observers import Recorder, record_cap

NC = 3


def _feed(rec: Recorder, chunks: list[np.ndarray]) -> None:
    for cacc in chunks:
        ns = 1 + int(cacc[0, 0] * 4) % 3  # 1-3 samples: lengths follow the data, as chunks of any length
        rec.chunk(None, ChunkOutput(out=np.zeros((1, ns, S.N_OUT)), acc=np.zeros((1, S.N_ACC)),
                                    cacc=np.ascontiguousarray(cacc.T)[None]), [0], ns)


def _chunks(seed: int, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.random((NC, S.N_CACC)) for _ in range(n)]


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31), st.integers(0, 70), st.integers(2, 9), st.integers(0, 70))
def test_records_sum_their_chunks_hold_the_cap_and_restore_bit_for_bit(seed, n, cap, cut):
    chunks = _chunks(seed, n)
    rec = Recorder([NC], budget=cap * NC * S.N_CACC * 8)
    assert rec.cap == [cap] and record_cap(NC, cap * NC * S.N_CACC * 8) == cap
    _feed(rec, chunks)
    r = rec.recording(0)
    assert len(r.contact_sums) <= cap and sum(rec.chunk_counts[0]) == n
    assert all(c == rec.width(0) for c in rec.chunk_counts[0][:-1]) and (not n or rec.chunk_counts[0][-1] <= rec.width(0))
    assert rec.width(0) == 1 or len(r.contact_sums) > cap // 2  # merged only when needed
    assert r.chunk_starts == list(np.cumsum([0] + r.chunk_samples[:-1]))[: len(r.chunk_starts)]  # tiled in order
    first = 0
    for k, cs in zip(rec.chunk_counts[0], r.contact_sums):
        np.testing.assert_allclose(cs, np.sum(chunks[first:first + k], axis=0), rtol=1e-13)
        first += k
    assert sum(r.chunk_samples) == rec.n[0]

    # stopped after ``cut`` chunks, written out as a checkpoint holds them, restored, continued
    cut = min(cut, n)
    part = Recorder([NC], budget=cap * NC * S.N_CACC * 8)
    _feed(part, chunks[:cut])
    resumed = Recorder([NC], budget=cap * NC * S.N_CACC * 8)
    resumed.restore(0, np.asarray(part.chunk_starts[0]), np.asarray(part.chunk_samples[0]),
                    list(np.stack(part.contact_sums[0])) if cut else [], np.asarray(part.chunk_counts[0]))
    resumed.n[0] = part.n[0]
    _feed(resumed, chunks[cut:])
    assert resumed.chunk_counts[0] == rec.chunk_counts[0] and resumed.chunk_starts[0] == rec.chunk_starts[0]
    assert all((a == b).all() for a, b in zip(resumed.contact_sums[0], rec.contact_sums[0]))

    # a checkpoint of before (a record per chunk, no counts) is replayed into the same records
    old = Recorder([NC], budget=10**9)
    _feed(old, chunks[:cut])
    replayed = Recorder([NC], budget=cap * NC * S.N_CACC * 8)
    replayed.restore(0, old.chunk_starts[0], old.chunk_samples[0], old.contact_sums[0], None)
    replayed.n[0] = old.n[0]
    _feed(replayed, chunks[cut:])
    assert replayed.chunk_counts[0] == rec.chunk_counts[0]
    assert all((a == b).all() for a, b in zip(replayed.contact_sums[0], rec.contact_sums[0]))


def test_a_whole_run_row_keeps_one_running_record():
    chunks = _chunks(7, 25)
    rec = Recorder([NC], [True], budget=2 * NC * S.N_CACC * 8)
    _feed(rec, chunks)
    total = chunks[0].copy()
    for c in chunks[1:]:
        total += c
    assert len(rec.contact_sums[0]) == 1 and rec.chunk_counts[0] == [25] and (rec.contact_sums[0][0] == total).all()
