"""Fast paths change no result: the numbers recorded before the performance work."""

import numpy as np
import pytest

from tests.golden import GOLDEN, GOLDEN_V1, record, record_v1


@pytest.mark.parametrize(("path", "recorder"), [(GOLDEN, record), (GOLDEN_V1, record_v1)], ids=["v0", "v1"])
def test_results_match_the_recorded_reference(path, recorder):
    now = recorder()
    with np.load(path) as reference:
        assert set(reference.files) == set(now)
        for key in reference.files:
            if key.endswith("_action"):
                np.testing.assert_array_equal(now[key], reference[key], err_msg=key)
            else:
                np.testing.assert_allclose(now[key], reference[key], rtol=1e-9, atol=1e-9, err_msg=key)
