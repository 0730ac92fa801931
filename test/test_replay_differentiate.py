# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The replay's Savitzky-Golay derivatives: scipy's filter, and the one-column-at-a-time form.

:func:`savgol_many` computes several derivatives of every column on threads; the reference
here is the form it replaced (one ``np.convolve`` per column and derivative, one derivative
per call), and scipy's ``savgol_filter(mode='interp')`` is the independent oracle.
"""

import numpy as np
import pytest

from spatial_dynamics.recordings import differentiate
from spatial_dynamics.recordings.differentiate import (derivatives, savgol, savgol_many,
                                                       savgol_weights)

RNG = np.random.default_rng(5)


def savgol_one_by_one(y, dt, window, order, deriv):
    """One derivative, one column after the other (the replay's form before threads)."""
    N = y.shape[0]
    window = min(window, N - (1 - N % 2))
    h = window // 2
    out = np.empty(y.shape)
    flat, res = y.reshape(N, -1), out.reshape(N, -1)
    w = savgol_weights(window, order, deriv, dt)
    for j in range(flat.shape[1]):
        res[h:N - h, j] = np.convolve(flat[:, j], w[::-1], mode='valid')
    for k in range(h):
        res[k] = savgol_weights(window, order, deriv, dt, at=k) @ flat[:window]
        res[N - 1 - k] = savgol_weights(window, order, deriv, dt, at=window - 1 - k) @ \
            flat[N - window:]
    return out


def derivatives_one_by_one(t, y, window_s, order, deriv, spans):
    """:func:`derivatives` of one derivative through :func:`savgol_one_by_one`."""
    out = np.full(y.shape, np.nan)
    for a, b in spans:
        ts, ys = t[a:b], y[a:b]
        dt = np.diff(ts)
        period = float(np.median(dt))
        window = differentiate.window_samples(window_s, period)
        if np.max(np.abs(dt - period)) <= differentiate.JITTER * period:
            out[a:b] = savgol_one_by_one(ys, period, window, order, deriv)
            continue
        grid = ts[0] + period * np.arange(int(np.floor((ts[-1] - ts[0]) / period)) + 1)
        yg = np.column_stack([np.interp(grid, ts, ys[:, j]) for j in range(ys.shape[1])])
        dg = savgol_one_by_one(yg, period, window, order, deriv)
        out[a:b] = np.column_stack([np.interp(ts, grid, dg[:, j]) for j in range(ys.shape[1])])
    return out


@pytest.mark.parametrize('threads', [1, 2, 3])
@pytest.mark.parametrize('shape', [(2001, 7), (400, 1), (37, 3), (1000,)])
def test_savgol_many_equals_one_by_one_and_scipy(monkeypatch, threads, shape):
    signal = pytest.importorskip('scipy.signal')
    monkeypatch.setattr(differentiate.compiled, 'THREADS', threads)
    dt, window, order = 1e-3, 51, 3
    y = np.cumsum(RNG.standard_normal(shape), axis=0) * 1e-2
    many = savgol_many(y, dt, window, order, (0, 1, 2))
    for deriv, got in zip((0, 1, 2), many):
        ref = savgol_one_by_one(y, dt, window, order, deriv)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.max(np.abs(ref)))
        np.testing.assert_allclose(savgol(y, dt, window, order, deriv), ref, rtol=1e-12,
                                   atol=1e-12 * np.max(np.abs(ref)))
        w = min(window, shape[0] - (1 - shape[0] % 2))
        oracle = signal.savgol_filter(y, w, order, deriv=deriv, delta=dt, axis=0,
                                      mode='interp')
        np.testing.assert_allclose(got, oracle, rtol=1e-8, atol=1e-8 * np.max(np.abs(oracle)))


def test_savgol_many_writes_into_the_given_arrays():
    y = RNG.standard_normal((300, 4))
    outs = [np.full((500, 4), -1.0) for _ in range(2)]
    views = [o[100:400] for o in outs]
    got = savgol_many(y, 0.01, 21, 2, (0, 1), views)
    for o, g, deriv in zip(outs, got, (0, 1)):
        assert np.shares_memory(g, o)
        np.testing.assert_array_equal(o[100:400], savgol_one_by_one(y, 0.01, 21, 2, deriv))
        assert (o[:100] == -1.0).all() and (o[400:] == -1.0).all()


def test_savgol_many_refuses_outs_it_cannot_write_into():
    y = RNG.standard_normal((50, 2, 3))
    strided = np.empty((50, 4, 3))[:, ::2]         # (50, 2, 3) that cannot be (50, 6)
    with pytest.raises(ValueError, match='C-contiguous'):
        savgol_many(y, 0.01, 11, 2, (0,), [strided])


def test_derivatives_equal_one_derivative_per_call():
    """Spans with a gap between, an uneven segment (resampled) and samples outside."""
    t = np.concatenate([np.arange(3000) * 1e-3,                      # uniform
                        5.0 + np.cumsum(RNG.uniform(0.8e-3, 1.2e-3, 2000)),   # uneven
                        9.0 + np.arange(30) * 1e-3])                  # too short: outside
    y = np.column_stack([np.sin(3 * t + k) for k in range(3)]) + 1e-4 * RNG.standard_normal(
        (len(t), 3))
    spans = [(0, 3000), (3000, 5000)]
    for derivs in ((0, 1), (1, 2)):
        got, resampled = derivatives(t, y, 0.05, 3, derivs, spans)
        assert resampled == 1
        for deriv, g in zip(derivs, got):
            ref = derivatives_one_by_one(t, y, 0.05, 3, deriv, spans)
            assert np.isnan(g[5000:]).all()
            np.testing.assert_allclose(g[:5000], ref[:5000], rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(ref[:5000])))


# --------------------------------------------------------------------------------------------
# What divides by a difference of stamps is bounded by what the thing can do (issue 34)

def joint_states(t, q):
    from spatial_dynamics.recordings.cdr import JointStates
    n = q.shape[1]
    return JointStates(tuple(f'j{k}' for k in range(n)), t, q, np.full(q.shape, np.nan),
                       np.ones(q.shape))


@pytest.mark.parametrize('period', [1e-6, 1e-9])
def test_joint_states_stamped_closer_than_any_sensor_are_refused(period):
    from spatial_dynamics.recordings.errors import Refused
    from spatial_dynamics.recordings.recording import clean
    t = 100.0 + period * np.arange(200)
    q = 1e-3 * np.sin(np.arange(200))[:, None] * np.ones((1, 2))   # within every bound
    with pytest.raises(Refused, match='stamped .* apart .*less than 1e-05 s'):
        clean(joint_states(t, q), 0.05)


def test_differentiated_accelerations_no_joint_reaches_are_refused():
    """A 1 kHz recording whose positions jump by 1 rad: q̈ ~1e6 rad/s², refused, named."""
    from spatial_dynamics.recordings.errors import Refused
    from spatial_dynamics.recordings.recording import clean, rates
    t = 1e-3 * np.arange(400)
    q = np.zeros((400, 1))
    q[200:] = 10.0
    s = clean(joint_states(t, q), 0.005)
    with pytest.raises(Refused, match='differentiated (velocity|acceleration) of joint 0'):
        rates(s, 0.005, 3)
    q[200:] = 0.0
    q[:, 0] = np.sin(t)                                             # a real motion passes
    s = clean(joint_states(t, q), 0.005)
    qd, qdd, _ = rates(s, 0.005, 3)
    np.testing.assert_allclose(qdd[10:-10, 0], -np.sin(t[10:-10]), atol=1e-3)


def test_a_base_topic_stamped_closer_than_any_sensor_or_accelerating_beyond_a_base_is_refused():
    from spatial_dynamics.recordings import base_topics
    from spatial_dynamics.recordings.errors import Refused
    from spatial_dynamics.recordings.cdr import IMU, Stamped
    t = 1e-6 * np.arange(20)
    found = Stamped(IMU, t, np.zeros((20, 10)), ('imu',))
    with pytest.raises(Refused, match='--base-imu /imu: .*stamped 1e-06 s apart'):
        base_topics.covering(found, [np.zeros((20, 3))], t, '--base-imu /imu')
    tj = 1e-3 * np.arange(10)
    a = np.zeros((10, 6))
    a[4, 3] = 2e3                                                   # 200 g
    with pytest.raises(Refused, match='linear acceleration at 0.004000 s is 2e\\+03 m/s'):
        base_topics.check_base_acceleration('--base-odometry /odom', tj, a)
    a[4, 3], a[5, 0] = 30.0, 2e4
    with pytest.raises(Refused, match='angular acceleration at 0.005000 s is 2e\\+04'):
        base_topics.check_base_acceleration('--base-odometry /odom', tj, a)
    a[5, 0] = 200.0
    base_topics.check_base_acceleration('--base-odometry /odom', tj, a)      # a real base
