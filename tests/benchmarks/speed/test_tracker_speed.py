"""The tracker benchmark: the two trackers it times take the same recorded inputs, and its speed-up
is the quotient of their channel-cycle rates."""

import pytest

from benchmarks.speed import tracker_speed


def test_the_speedup_is_the_quotient_of_the_rates_over_the_same_inputs(monkeypatch):
    seen = {}

    def spy(name, run):
        def wrapped(model, inputs, trials):
            seen[name] = (trials, len(inputs), inputs[0][2].shape)
            return run(model, inputs, trials)

        return wrapped

    monkeypatch.setattr(tracker_speed, "run_batched", spy("batched", tracker_speed.run_batched))
    monkeypatch.setattr(tracker_speed, "run_filterpy", spy("filterpy", tracker_speed.run_filterpy))
    r = tracker_speed.measure(trials=6, steps=3, reference_trials=2)
    # the reference runs the first trials of the same recorded steps
    assert seen["batched"][:2] == (6, 3) and seen["filterpy"][:2] == (2, 3)
    assert seen["batched"][2][1:] == seen["filterpy"][2][1:]
    assert r["tracker_speedup_vs_filterpy"] == pytest.approx(
        r["batched_channel_cycles_per_s"] / r["filterpy_channel_cycles_per_s"], rel=1e-12
    )
