"""The DOP853 tableau held in core/dop853.py is scipy's, value for value."""

import numpy as np
from scipy.integrate import DOP853

from gyro_instrument.core import dop853


def test_tableau_equals_scipy_public_class():
    for name in ("A", "B", "C", "E3", "E5", "D", "A_EXTRA", "C_EXTRA"):
        ours, theirs = getattr(dop853, name), getattr(DOP853, name)
        assert ours.shape == theirs.shape, name
        assert ours.dtype == theirs.dtype, name
        assert np.array_equal(ours, theirs), name
    assert dop853.N_STAGES == DOP853.n_stages
    assert dop853.ORDER == DOP853.order
    assert dop853.ERROR_ESTIMATOR_ORDER == DOP853.error_estimator_order


def test_first_crossing_matches_solve_ivp_event():
    """The apocentre (at ~π) of a damped-rotating oscillator in the plane after t = 2, as solve_ivp's
    terminal event finds it."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        return np.array([y[2], y[3], -y[0] - 0.01 * y[3], -y[1] + 0.01 * y[2]])

    def g(y):
        return y[0] * y[2] + y[1] * y[3]
    y0 = [1.0, 0.0, 0.0, 0.05]
    t_event, y_event, sol, nfev = dop853.first_crossing(lambda t, *y: tuple(rhs(t, np.array(y))), y0, 4.0, g,
                                                        after=2.0, rtol=1e-12, atol=1e-14)

    def event(t, y):
        return g(y) if t > 2.0 else 1.0
    event.direction, event.terminal = -1, True
    ref = solve_ivp(rhs, (0.0, 4.0), y0, method="DOP853", rtol=1e-12, atol=1e-14, events=event, dense_output=True)
    assert abs(t_event - ref.t_events[0][0]) < 1e-12
    assert np.allclose(y_event, ref.y_events[0][0], rtol=0, atol=1e-12)
    assert abs(g(y_event)) < 1e-13
    tt = np.linspace(0.0, t_event, 50)
    assert np.allclose(sol(tt), ref.sol(tt), rtol=0, atol=1e-11)
    assert nfev > 0
