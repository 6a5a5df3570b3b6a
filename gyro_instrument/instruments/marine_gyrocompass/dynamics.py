"""The marine gyrocompass's equations of motion and their integration (issue 39 item 1).

The sensitive element: a rotor of angular momentum H along the unit vector s (its north end), at
azimuth α east of true north and tilt θ (north end up), s = (sin α cos θ, cos α cos θ, sin θ) in the
local-level frame ENU at the ship. The element is free in azimuth and in tilt (its follow-up keeps the
ship's rotation off it) and swings as a pendulum by β about its spin axis (the case's up axis
u = cos β u0 + sin β e, u0 = e × s, e = (cos α, −sin α, 0) the horizontal axis across s). Gyroscopic
approximation (the spin momentum only; nutation left out): in the local-level frame, which turns at
Ω + ρ (the Earth rate Ω (0, cos φ, sin φ) and the transport rate ρ = (−V_N, V_E, V_E tan φ)/R of a ship
sailing on the sphere),

    ds/dt = τ⊥ / H − (Ω + ρ) × s

with τ⊥ the torques' part across s; the part along s swings β:
β'' = ω_β² (τ_c · s)/P_c − 2 ζ_β ω_β β'. The torques (per H):

- control (pendulous, bottom-heavy; or ballistic, a top-heavy liquid with the rotor spinning the other
  way, the same equations for the north end in the limit of instantaneous flow): the pendulous mass
  P_c/g at −u in the apparent gravity f = g − a, τ_c = −(P_c/g) u × f, a = dv/dt + (2Ω + ρ) × v the
  kinematic acceleration of the point of support (its horizontal part: the ship's speed and course
  changes, the Coriolis term of its velocity, the sway of roll and pitch; the vertical part is left out);
- damping in tilt (Sperry): a torque about the vertical k_d (τ_c · e) ẑ, k_d = P_d/P_c (the control's
  offset: it reduces the tilt and settles the axis east of north by sin δ = k_d tan φ);
- damping in azimuth (Anschütz): an oil ballistic lagging the control torque, τ_o = k_o (c − q) e,
  dq/dt = (c − q)/τ_lag, c = τ_c · e; at rest q = c and no torque: no settle error; for τ_lag ≪ T
  it is −k_o τ_lag dc/dt, a torque across s ∝ the tilt rate, ζ ≈ k_o τ_lag ω0 / 2.

The speed error, the ballistic deflection and its Schuler cancellation, and the intercardinal rolling
error (the element's swing β under the athwartships sway times the north–south sway: a mean torque
about the vertical at intercardinal headings) all follow from these equations; the closed forms
they are checked against are in :mod:`.theory`. The state: (α, θ, β, β', q, φ, V_f), φ the ship's
latitude (dφ/dt = V_N/R) and V_f the speed log's reading through its first-order filter.

Integration: DOP853 (``core.integrate.integration``, ``DOP853-scalar``: the method on Python floats)
piece by piece of the ship's schedule (:class:`~gyro_instrument.core.motion.Motion`: the speed's and
course's rates jump at the pieces' ends; each piece starts a new run from the last state, so no step
straddles a jump).
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.integrate import SCALAR_DOP853, Trajectory, integration
from gyro_instrument.core.motion import EARTH_RADIUS_M, Piece

#: The state's components.
STATE = ("azimuth", "tilt", "element_roll", "element_roll_rate", "oil", "latitude", "log_speed")


@dataclass(frozen=True)
class Coefficients:
    """The constants of the right-hand side (SI): Earth rate Ω, gravity g, P_c/H, k_d (tilt damping),
    k_o and τ_lag (oil damping), ω_β and ζ_β (the element's swing), τ_f (speed filter, 0: none), and the
    sway: forward and starboard acceleration amplitudes (m/s²), their angular rates and the pitch's phase."""

    earth_rate: float
    gravity: float
    control: float
    tilt_damping: float
    oil_damping: float
    oil_lag_s: float
    swing_rate: float
    swing_damping: float
    filter_s: float
    fwd_m_s2: float = 0.0
    fwd_rate: float = 0.0
    fwd_phase: float = 0.0
    stbd_m_s2: float = 0.0
    stbd_rate: float = 0.0


def right_hand_side(co, piece: Piece) -> Callable:
    """``f(t, *state) -> tuple`` of the derivatives over one piece of the schedule (module docstring)."""
    Om, g, k, kd, ko = co.earth_rate, co.gravity, co.control, co.tilt_damping, co.oil_damping
    inv_lag = 1.0 / co.oil_lag_s if ko else 0.0
    wb2, zb2 = co.swing_rate ** 2, 2.0 * co.swing_damping * co.swing_rate
    inv_f = 1.0 / co.filter_s if co.filter_s > 0 else 0.0
    t0, v0, acc, c0, r = piece.t0, piece.v0, piece.a, piece.c0, piece.r
    Af, wf, pf, As, ws = co.fwd_m_s2, co.fwd_rate, co.fwd_phase, co.stbd_m_s2, co.stbd_rate
    R, sin, cos, m = EARTH_RADIUS_M, math.sin, math.cos, -k / g

    def f(t, al, th, be, bd, q, lat, vf):
        tau = t - t0
        V, C = v0 + acc * tau, c0 + r * tau
        sC, cC = sin(C), cos(C)
        vE, vN = V * sC, V * cC
        af = Af * sin(wf * t + pf) if Af else 0.0
        ast = -As * sin(ws * t) if As else 0.0
        sl, cl = sin(lat), cos(lat)
        rz = vE * sl / (cl * R)
        wx, wy, wz = -vN / R, Om * cl + vE / R, Om * sl + rz
        cz = 2.0 * Om * sl + rz                                   # (2Ω + ρ)_up: the Coriolis term of v
        aE = acc * sC + V * r * cC + af * sC + ast * cC - cz * vN
        aN = acc * cC - V * r * sC + af * cC - ast * sC + cz * vE
        sa, ca, st, ct, sb, cb = sin(al), cos(al), sin(th), cos(th), sin(be), cos(be)
        sx, sy, sz = sa * ct, ca * ct, st
        ux, uy, uz = -cb * sa * st + sb * ca, -cb * ca * st - sb * sa, cb * ct
        # τ_c / H = −(P_c/(g H)) u × f, f = (−aE, −aN, −g)
        Tx, Ty, Tz = m * (-uy * g + uz * aN), m * (-uz * aE + ux * g), m * (-ux * aN + uy * aE)
        Tcs = Tx * sx + Ty * sy + Tz * sz                          # along s: swings the element
        c = Tx * ca - Ty * sa                                      # across s, horizontal: the control
        Tz += kd * c
        d = ko * (c - q)
        Tx, Ty = Tx + d * ca, Ty - d * sa
        Ts = Tx * sx + Ty * sy + Tz * sz
        dx = Tx - Ts * sx - (wy * sz - wz * sy)
        dy = Ty - Ts * sy - (wz * sx - wx * sz)
        dz = Tz - Ts * sz - (wx * sy - wy * sx)
        return ((dx * ca - dy * sa) / ct, dz / ct, bd, wb2 * Tcs / k - zb2 * bd, (c - q) * inv_lag,
                vN / R, (V - vf) * inv_f)
    return f


def integrate_pieces(co, motion, pieces, y0, t, rtol=1e-9, atol=1e-12) -> Trajectory:
    """Integrate from ``y0`` at ``t[0]`` and sample at ``t`` (s), one DOP853 run per piece of the
    schedule (``pieces``: :class:`~gyro_instrument.core.motion.Piece` tuple covering the run).

    Returns a :class:`Trajectory` (states (7, len(t)); nfev, wall and CPU time summed over the pieces)."""
    t = np.asarray(t, dtype=float)
    y = tuple(float(v) for v in y0)
    out = np.empty((len(y), t.size))
    nfev, wall, cpu, t_now, i = 0, 0.0, 0.0, float(t[0]), 0
    for p in pieces:
        if t_now >= t[-1] and i >= t.size:
            break
        end = min(p.t1, float(t[-1]))
        if end < t_now:
            continue
        j = int(np.searchsorted(t, end, side="left")) if end < t[-1] else t.size
        samples = t[i:j]
        if end > t_now:
            run = integration(right_hand_side(co, p), y, t_now, end, method=SCALAR_DOP853, rtol=rtol, atol=atol)
            tr = run.advance(np.append(samples, end))
            out[:, i:j] = tr.y[:, :-1]
            y = tuple(float(v) for v in tr.y[:, -1])
            nfev, wall, cpu = nfev + tr.nfev, wall + tr.wall_time_s, cpu + tr.cpu_time_s
        else:
            out[:, i:j] = np.array(y)[:, None]
        i, t_now = j, end
        if i >= t.size:
            break
    return Trajectory(t=t, y=out, nfev=nfev, wall_time_s=wall, cpu_time_s=cpu, method="DOP853 (scalar, by pieces)")
