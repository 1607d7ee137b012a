"""Behaviour unchanged: the fixed sweep of :mod:`tests.golden_sweep` gives the stored records."""

import json

from tests.golden_sweep import GOLDEN, sweep_digests


def test_fixed_sweep_records_are_bit_identical():
    want = json.loads(GOLDEN.read_text())
    got = sweep_digests(jobs=2)
    assert set(got) == set(want)
    changed = sorted(k for k in want if got[k] != want[k])
    assert not changed, f"records changed (see tests/golden_sweep.py): {changed}"
