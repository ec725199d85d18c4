"""Fast paths change no result: the numbers recorded before the performance work."""

import numpy as np

from tests.golden import GOLDEN, record


def test_results_match_the_recorded_reference():
    now = record()
    with np.load(GOLDEN) as reference:
        assert set(reference.files) == set(now)
        for key in reference.files:
            if key.endswith("_action"):
                np.testing.assert_array_equal(now[key], reference[key], err_msg=key)
            else:
                np.testing.assert_allclose(now[key], reference[key], rtol=1e-9, atol=1e-9, err_msg=key)
