"""Golden results: a fixed small campaign and the scenario, identical to the bit.

The files in ``tests/golden/`` were written by ``scripts/maintenance/make_golden.py`` (see
``tests/golden_cases.py`` for what runs).  A refactor or speed-up keeps every
value, dtype and column order; only a deliberate change of behaviour regenerates
them, in its own commit.
"""

import numpy as np
import pandas as pd
import pytest

from golden_cases import CAMPAIGNS, SCENARIOS, campaign_frames, golden_path, read, \
    scenario_frames


def _same(df: pd.DataFrame, path) -> None:
    want = read(path)
    assert list(df.columns) == list(want.columns)
    # exact: NaN equals NaN, every other float must match to the last bit
    pd.testing.assert_frame_equal(df.reset_index(drop=True), want, check_exact=True)
    for col in want.columns:
        a = df[col].to_numpy()
        b = want[col].to_numpy()
        if a.dtype.kind == "f":  # to the bit: -0.0 is not 0.0 here
            assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), col


@pytest.mark.parametrize("name", list(CAMPAIGNS))
def test_campaign_is_golden(name):
    for table, df in campaign_frames(name).items():
        _same(df, golden_path("campaign", name, table))


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_scenario_is_golden(name):
    for table, df in scenario_frames(name).items():
        _same(df, golden_path("scenario", name, table))
