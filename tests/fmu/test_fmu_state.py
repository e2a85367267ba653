"""FMU state (get/set/serialise), variable communication steps, and the
estimator's fixed-sample-period rule, through fmpy's FMU2Slave."""
from __future__ import annotations

import ctypes

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters

from conftest import (ESTIMATOR, ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS, FMU_NAMES, JOINT, JOINT_INPUTS,
                      JOINT_OUTPUTS, joint_test_inputs)

TS = 1e-3
IO = {ESTIMATOR: (ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS), JOINT: (JOINT_INPUTS, JOINT_OUTPUTS)}


def inputs_for(name, recording, n, offset=0):
    if name == ESTIMATOR:
        r = recording
        return np.column_stack([r.i_m, r.theta_m, r.theta_l])[offset:offset + n]
    return joint_test_inputs(offset + n)[offset:]


def start_inputs(name, u0):
    return dict(zip(IO[name][0], u0))


def assert_moves(out):
    # Every comparison below is only worth something if the outputs change.
    assert np.all(np.ptp(out, axis=0)[:3] > 0), np.ptp(out, axis=0)


# ---------------------------------------------------------------- get/set state


@pytest.mark.parametrize("name", FMU_NAMES)
def test_restoring_a_saved_state_repeats_the_continuation_bit_for_bit(name, make_slave, recording):
    ins, outs = IO[name]
    n0, n1 = 150, 250
    u = inputs_for(name, recording, n0 + n1)
    s = make_slave(name)
    s.start(inputs=start_inputs(name, u[0]))
    s.run(0.0, [TS] * n0, u[:n0], ins, outs)
    t_save = n0 * TS
    outputs_at_save = s.get(outs)
    state = s.slave.getFMUstate()

    first = s.run(t_save, [TS] * n1, u[n0:], ins, outs)
    assert_moves(first)
    s.slave.setFMUstate(state)
    assert np.array_equal(s.get(outs), outputs_at_save)
    second = s.run(t_save, [TS] * n1, u[n0:], ins, outs)
    assert np.array_equal(first, second)

    # The state can be restored again, and the restored time is the saved one.
    s.slave.setFMUstate(state)
    third = s.run(t_save, [TS] * 20, u[n0:n0 + 20], ins, outs)
    assert np.array_equal(first[:20], third)
    s.slave.freeFMUstate(state)
    assert not s.errors()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_restored_state_carries_the_communication_time(name, make_slave, recording):
    ins, outs = IO[name]
    u = inputs_for(name, recording, 100)
    s = make_slave(name)
    s.start(inputs=start_inputs(name, u[0]))
    s.run(0.0, [TS] * 50, u[:50], ins, outs)
    state = s.slave.getFMUstate()
    s.run(50 * TS, [TS] * 50, u[50:], ins, outs)
    s.slave.setFMUstate(state)
    # Back at t = 0.05 s: a step from 0.1 s is a jump and must be refused.
    with pytest.raises(Exception):
        s.slave.doStep(100 * TS, TS)
    message = s.errors()[-1]
    assert "fmi2DoStep" in message and "expected communication point 0.0500000" in message, message


@pytest.mark.parametrize("name", FMU_NAMES)
def test_get_state_into_an_existing_state_overwrites_it(name, make_slave, recording):
    ins, outs = IO[name]
    u = inputs_for(name, recording, 200)
    s = make_slave(name)
    s.start(inputs=start_inputs(name, u[0]))
    state = s.slave.getFMUstate()  # at t = 0
    s.run(0.0, [TS] * 100, u[:100], ins, outs)
    # FMI 2.0: when *FMUstate != NULL on entry, the state is overwritten in place.
    s.slave.fmi2GetFMUstate(s.slave.component, ctypes.byref(state))
    first = s.run(100 * TS, [TS] * 100, u[100:], ins, outs)
    s.slave.setFMUstate(state)
    second = s.run(100 * TS, [TS] * 100, u[100:], ins, outs)
    assert np.array_equal(first, second)
    s.slave.freeFMUstate(state)


NON_DEFAULT = {ESTIMATOR: {"Kf": 9000.0, "ukf_q_tau": 0.05}, JOINT: {"Jl": 0.2, "Df": 2.0, "max_step": 5e-5}}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_serialized_state_continues_identically_in_a_new_instance(name, make_slave, recording):
    ins, outs = IO[name]
    n0, n1 = 120, 200
    u = inputs_for(name, recording, n0 + n1)
    a = make_slave(name, "a")
    a.start(params=NON_DEFAULT[name], inputs=start_inputs(name, u[0]))
    a.run(0.0, [TS] * n0, u[:n0], ins, outs)
    state = a.slave.getFMUstate()
    blob = a.slave.serializeFMUstate(state)
    a.slave.freeFMUstate(state)
    assert isinstance(blob, bytes) and len(blob) > 0
    expected = a.run(n0 * TS, [TS] * n1, u[n0:], ins, outs)
    assert_moves(expected)

    # A fresh instance, never initialised, with default parameters.
    b = make_slave(name, "b")
    restored = b.slave.deSerializeFMUstate(blob)
    b.slave.setFMUstate(restored)
    b.slave.freeFMUstate(restored)
    # The parameters travelled with the state.
    assert list(b.get(list(NON_DEFAULT[name]))) == list(NON_DEFAULT[name].values())
    got = b.run(n0 * TS, [TS] * n1, u[n0:], ins, outs)
    assert np.array_equal(expected, got)

    # A default-parameter run differs, so the comparison above could fail.
    c = make_slave(name, "c")
    c.start(inputs=start_inputs(name, u[0]))
    default_run = c.run(0.0, [TS] * (n0 + n1), u, ins, outs)[n0:]
    assert not np.array_equal(default_run, expected)
    assert not (a.errors() or b.errors() or c.errors())


@pytest.mark.parametrize("name", FMU_NAMES)
def test_serialized_state_is_stable(name, make_slave, recording):
    """Serialise, deserialise, serialise again: the same bytes."""
    ins, outs = IO[name]
    u = inputs_for(name, recording, 50)
    s = make_slave(name)
    s.start(inputs=start_inputs(name, u[0]))
    s.run(0.0, [TS] * 50, u, ins, outs)
    st = s.slave.getFMUstate()
    blob = s.slave.serializeFMUstate(st)
    st2 = s.slave.deSerializeFMUstate(blob)
    assert s.slave.serializeFMUstate(st2) == blob
    s.slave.freeFMUstate(st)
    s.slave.freeFMUstate(st2)


# ---------------------------------------------------------------- the estimator's sample rule


def rule_reference(make_slave, points, steps, inputs):
    """What the documented rule says the estimator outputs after each communication step, as if
    every sample were read.

    Samples fall at k*Ts (start 0); the step [t_j, t_j + h_j) processes the
    samples inside it with the inputs set at t_j. Reference: an instance
    stepped at h = Ts, each sample fed the input of the communication point
    whose interval holds it. That is the rule for the compliance model
    (MEMORYLESS); the filters read the inputs at a step's first sample only
    and predict over the others (held_rule_reference).
    """
    points = np.asarray(points)
    ends = points + np.asarray(steps)
    n_samples = int(np.sum(np.arange(int(ends[-1] / TS) + 2) * TS < ends[-1] - 1e-9))
    sample_times = np.arange(n_samples) * TS
    owner = np.searchsorted(points, sample_times + 1e-9, side="right") - 1
    assert owner.min() == 0
    fine_inputs = inputs[owner]
    fine = make_slave(ESTIMATOR, "fine")
    fine.start(inputs=start_inputs(ESTIMATOR, inputs[0]))
    initial = fine.get(ESTIMATOR_OUTPUTS)
    fine_out = np.vstack([initial, fine.run(0.0, [TS] * n_samples, fine_inputs, ESTIMATOR_INPUTS,
                                            ESTIMATOR_OUTPUTS)])
    # After step j: the outputs after the last sample before t_j + h_j (row 0: none yet).
    processed = np.array([np.sum(sample_times < e - 1e-9) for e in ends])
    return fine_out[processed], processed


MEMORYLESS = [ESTIMATOR_OUTPUTS.index(n) for n in ("tau_compliance", "dtheta_f")]
FILTERED = [k for k in range(len(ESTIMATOR_OUTPUTS)) if k not in MEMORYLESS]


def held_rule_reference(points, steps, inputs):
    """The filters' rule: the batch path with the communication points as rows (each row steps to the
    next point, the last by its own step), which reads each row at its step's first sample only."""
    stream = _core.EstimatorStream(parameters.for_estimator(parameters.defaults()), 0.0, False)
    out = stream.run(np.asarray(points, float), *(np.ascontiguousarray(inputs[:, k]) for k in range(3)),
                     float(points[-1] + steps[-1]))
    return np.column_stack([out[n] for n in ESTIMATOR_OUTPUTS])


def check_sample_rule(got, expected, processed, points, steps, inputs):
    """The compliance model follows the sample rule exactly; the filters predict over the samples of
    a step after its first (they differ from an instance that read every sample there)."""
    assert np.array_equal(got[:, MEMORYLESS], expected[:, MEMORYLESS])
    assert np.array_equal(got[:, FILTERED], held_rule_reference(points, steps, inputs)[:, FILTERED])
    counts = np.diff(np.concatenate([[0], processed]))
    first_held = np.argmax(counts > 1)
    assert counts[first_held] > 1
    assert np.array_equal(got[:first_held, FILTERED], expected[:first_held, FILTERED])
    assert not np.array_equal(got[first_held, FILTERED], expected[first_held, FILTERED])


def coarse_run(make_slave, points, steps, inputs):
    s = make_slave(ESTIMATOR, "coarse")
    s.start(inputs=start_inputs(ESTIMATOR, inputs[0]))
    out = np.empty((len(steps), len(ESTIMATOR_OUTPUTS)))
    vin, vout = s.vr(ESTIMATOR_INPUTS), s.vr(ESTIMATOR_OUTPUTS)
    for j, (t, h) in enumerate(zip(points, steps)):
        s.slave.setReal(vin, list(inputs[j]))
        s.slave.doStep(float(t), float(h))
        out[j] = s.slave.getReal(vout)
    assert not s.errors()
    return out


def recording_inputs_at(recording, points):
    rows = np.minimum(np.round(np.asarray(points) / TS).astype(int), len(recording) - 1)
    r = recording
    return np.column_stack([r.i_m, r.theta_m, r.theta_l])[rows]


def test_step_not_a_multiple_of_ts_follows_the_sample_rule(make_slave, recording):
    h = 2.5e-3
    n = 200
    points = np.arange(n) * h
    steps = np.full(n, h)
    inputs = recording_inputs_at(recording, points)
    expected, processed = rule_reference(make_slave, points, steps, inputs)
    # The rule in numbers: steps alternately hold 3 and 2 samples (0,1,2 | 3,4 | 5,6,7 | ...).
    assert list(np.diff(np.concatenate([[0], processed]))[:4]) == [3, 2, 3, 2]
    got = coarse_run(make_slave, points, steps, inputs)
    check_sample_rule(got, expected, processed, points, steps, inputs)
    # A one-sample shift of the rule would be visible.
    assert not np.array_equal(got[1:, MEMORYLESS], expected[:-1, MEMORYLESS])


def test_random_step_sizes_follow_the_sample_rule(make_slave, recording):
    rng = np.random.default_rng(11)
    steps = rng.uniform(0.3e-3, 7e-3, size=150)
    points = np.concatenate([[0.0], np.cumsum(steps)[:-1]])
    inputs = recording_inputs_at(recording, points)
    expected, processed = rule_reference(make_slave, points, steps, inputs)
    # Some steps hold no sample at all, some several.
    counts = np.diff(np.concatenate([[0], processed]))
    assert counts.min() == 0 and counts.max() >= 6
    got = coarse_run(make_slave, points, steps, inputs)
    check_sample_rule(got, expected, processed, points, steps, inputs)


@pytest.mark.parametrize("h", [0.0009999999999976694, 0.0010000000000023306])
def test_floating_noise_steps_equal_exact_ts_steps(h, make_slave, recording):
    n = 3000
    u = inputs_for(ESTIMATOR, recording, n)
    exact = make_slave(ESTIMATOR, "exact")
    exact.start(inputs=start_inputs(ESTIMATOR, u[0]))
    vin, vout = exact.vr(ESTIMATOR_INPUTS), exact.vr(ESTIMATOR_OUTPUTS)
    ref = np.empty((n, len(vout)))
    for k in range(n):
        exact.slave.setReal(vin, list(u[k]))
        exact.slave.doStep(k * TS, TS)
        ref[k] = exact.slave.getReal(vout)

    noisy = make_slave(ESTIMATOR, "noisy")
    noisy.start(inputs=start_inputs(ESTIMATOR, u[0]))
    got = np.empty_like(ref)
    t = 0.0
    for k in range(n):  # a master accumulating its communication points
        noisy.slave.setReal(vin, list(u[k]))
        noisy.slave.doStep(t, h)
        got[k] = noisy.slave.getReal(vout)
        t += h
    assert abs(t - n * TS) > 1e-12  # the noise really accumulated
    assert np.array_equal(got, ref)
    assert not (exact.errors() or noisy.errors())


def test_estimator_with_ts_2ms_samples_every_other_step(make_slave, recording):
    """Ts = 2 ms and communication steps of 1 ms: a sample every other step, inputs of the even points."""
    n = 400
    r = recording
    u = np.column_stack([r.i_m, r.theta_m, r.theta_l])[:n]
    s = make_slave(ESTIMATOR, "ts2")
    s.start(params={"Ts": 2e-3}, inputs=start_inputs(ESTIMATOR, u[0]))
    got = s.run(0.0, [TS] * n, u, ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS)
    ref = _core.run_estimator({**parameters.for_estimator(parameters.defaults()), "Ts": 2e-3},
                              r.time[0:n:2], r.i_m[0:n:2], r.theta_m[0:n:2], r.theta_l[0:n:2])
    for k, name in enumerate(ESTIMATOR_OUTPUTS):
        np.testing.assert_array_equal(got[0::2, k], ref[name])  # sample at each even step
        np.testing.assert_array_equal(got[1::2, k], ref[name])  # odd steps hold no sample


# ---------------------------------------------------------------- the joint: variable steps


def test_joint_variable_steps_equal_batch_path_on_the_same_grid(make_slave):
    rng = np.random.default_rng(5)
    steps = rng.uniform(0.3e-3, 7e-3, size=150)
    time = np.concatenate([[0.0], np.cumsum(steps)])
    u = joint_test_inputs(len(time))
    s = make_slave(JOINT)
    s.start(inputs={"i_m": u[0, 0], "tau_ext": u[0, 1]})
    got = s.run(0.0, np.diff(time), u[:-1], JOINT_INPUTS, JOINT_OUTPUTS)
    # (Run passes t as a running sum; re-synchronisation to the master's time is the FMU's job.)
    batch = _core.simulate_joint(parameters.for_plant(parameters.defaults()), time, u[:, 0], u[:, 1])
    for k, name in enumerate(JOINT_OUTPUTS):
        np.testing.assert_allclose(got[:, k], batch[name][1:], rtol=1e-12, atol=1e-12, err_msg=name)
    assert_moves(got)


def test_joint_variable_steps_match_uniform_fine_steps(make_slave):
    """Constant inputs, random steps on a 0.1 ms grid: the same trajectory as 0.1 ms steps."""
    rng = np.random.default_rng(8)
    ticks = rng.integers(3, 70, size=60)  # 0.3 ms .. 7 ms
    inputs = {"i_m": 0.7, "tau_ext": -0.2}
    dt = 1e-4
    coarse = make_slave(JOINT, "coarse")
    coarse.start()
    vin, vout = coarse.vr(JOINT_INPUTS), coarse.vr(JOINT_OUTPUTS)
    got, t = [], 0.0
    for k in ticks:
        coarse.slave.setReal(vin, list(inputs.values()))
        coarse.slave.doStep(t, k * dt)
        t += k * dt
        got.append(coarse.slave.getReal(vout))
    fine = make_slave(JOINT, "fine")
    fine.start()
    total = int(ticks.sum())
    trajectory = fine.run(0.0, [dt] * total, np.tile(list(inputs.values()), (total, 1)), JOINT_INPUTS,
                          JOINT_OUTPUTS)
    expected = trajectory[np.cumsum(ticks) - 1]
    got = np.array(got)
    k = JOINT_OUTPUTS.index("tau_joint")
    assert np.ptp(expected[:, k]) > 0.1
    np.testing.assert_allclose(got[:, k], expected[:, k], rtol=0, atol=1e-9 * np.abs(expected[:, k]).max())
    for name in ("omega_m", "omega_link"):
        k = JOINT_OUTPUTS.index(name)
        np.testing.assert_allclose(got[:, k], expected[:, k], rtol=1e-9, atol=1e-9)


def _torsional_response(make_slave, h, duration=0.3, params=None):
    """Current step at t = 0 held constant: tau_joint at every 10 ms."""
    s = make_slave(JOINT, f"h{h}")
    s.start(params=params)
    n = int(round(duration / h))
    out = s.run(0.0, [h] * n, np.tile([0.8, 0.0], (n, 1)), JOINT_INPUTS, ("tau_joint",))[:, 0]
    every = int(round(10e-3 / h))
    return out[every - 1::every]


def test_joint_coarse_communication_step_substeps_internally(make_slave):
    fine = _torsional_response(make_slave, 1e-3)
    coarse = _torsional_response(make_slave, 10e-3)
    assert len(fine) == len(coarse) == 30
    # A torsional oscillation is there to be resolved (tens of Hz, lightly damped).
    assert np.ptp(fine) > 1.0 and np.any(np.diff(np.sign(np.diff(fine))) != 0)
    scale = np.abs(fine).max()
    assert np.max(np.abs(coarse - fine)) <= 1e-6 * scale
    # Without substeps (max_step = 10 ms: one ROS2 step per communication step)
    # the answer is visibly different: the comparison above tests the substepping.
    one_step = _torsional_response(make_slave, 10e-3, params={"max_step": 1e-2})
    assert np.max(np.abs(one_step - fine)) > 1e-2 * scale
