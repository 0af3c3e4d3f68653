"""The JSON objects of plans and motions (rollplan.io): every number of a time series is a Python float equal,
bit for bit, to the sampled value it records."""

import numpy as np

import rollplan
from rollplan.execution.actuation import actuate, motion_samples
from rollplan.io import motion_to_dict


def test_motion_lists_are_the_samples_as_python_floats(asym_plan):
    motion = actuate(asym_plan, rollplan.Robot(), duration=4.0)
    d, m = motion_to_dict(motion), motion_samples(motion)
    assert type(d["time"]) is list and all(type(t) is float for t in d["time"])
    assert np.array_equal(np.array(d["time"]), np.asarray(m.time, float))
    for key in ("omega", "rotor_rates", "rotor_angles", "rotor_torques", "state"):
        want = np.asarray(getattr(m, key), float)
        rows = d[key]
        assert len(rows) == len(want) and all(type(r) is list and len(r) == want.shape[1] for r in rows), key
        assert all(type(v) is float for r in rows for v in r), key
        got = np.array(rows)
        assert np.array_equal(got.view(np.int64), want.view(np.int64)), key   # bit for bit, -0.0 included
    assert all(type(s) is int for s in d["segment"])
    assert d["torque_breaks"] == [float(t) for t in m.repeated_times()]
