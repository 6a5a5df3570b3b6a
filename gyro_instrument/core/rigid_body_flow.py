"""Exact flow of the torque-free symmetric top, and splitting compositions with torque kicks.

A body of revolution (transverse moment A, axial moment C = μA about its fixed point) turns
freely. Its attitude is the unit quaternion q (body → inertial, scalar first; body z is the
figure axis) and ω = (ω1, ω2, ω3) its angular velocity in body axes. The torque-free motion is
solved exactly from ANY state (Euler 1758; e.g. Landau & Lifshitz, Mechanics §33):

* ω3 is constant; (ω1, ω2) turn about the body z axis at σ = (1 − μ) ω3:
  ω⊥(h) = Rot(e3, −σ h) ω⊥(0);
* the angular momentum L = A R Λ_b, Λ_b = (ω1, ω2, μ ω3), is constant in the inertial frame and
  the body turns about it at λ = |Λ_b| = |L|/A, then about its own axis at σ:
  R(h) = Rot(L̂, λ h) R(0) Rot(e3, σ h), i.e. q(h) = q(0) ⊗ Rot(Λ̂_b, λ h) ⊗ Rot(e3, σ h)
  (the rotation about the inertial L̂ written in body axes, where L̂ ↦ Λ̂_b).

Splitting (Celledoni, Fassò, Säfström & Zanna, "The exact computation of the free rigid body
motion and its use in splitting methods", SIAM J. Sci. Comput. 30(4), 2008, 2084–2112): for
ω̇ = free(ω) + torque/I, a Strang step is K(h/2) F(h) K(h/2), F the exact free flow above and K the
exact flow of the torque with the attitude (and the time) frozen — an angular-momentum kick. The
free flow carries the fast spin and nutation exactly, so the step is set by the slow time scales
(the torque's, the Earth rate's) only. Higher orders by symmetric composition of Strang steps
(:data:`COMPOSITIONS`): Yoshida's triple jump (order 4) and his 7-stage solution A (order 6)
(H. Yoshida, Phys. Lett. A 150, 262–268, 1990). Local error O(h^(p+1)) per step, global O(h^p).

The torques composed here are those of a heavy symmetric top on the turning Earth (the free
gyroscope under torques): a torque γ A (up × k) across the figure axis k (a mass unbalance m g d,
γ = m g d / A), ``up`` turning about Earth's axis ê at n in the inertial frame, and a relaxation of
the spin relative to the Earth, ρ = ω3 − n k·ê, at the rate 1/τ (bearing friction). With k and t
frozen both have exact flows (the kicks :func:`kick`). The step loop :func:`splitting_run` is a
compiled kernel (:mod:`gyro_instrument.core.jit`, on float arrays; uncompiled with
``GYRO_INSTRUMENT_JIT=0``). The same free flow from the release state, vectorised over the sample
times, is the free gyroscope's closed form
(:meth:`~gyro_instrument.instruments.free_gyroscope.FreeGyroscope.analytic_state`).
"""

import functools
import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

#: Weights of symmetric compositions of Strang steps, by order: 2 Strang itself; 4 Yoshida's triple
#: jump w1 = 1/(2 − 2^(1/3)), w0 = 1 − 2 w1; 6 Yoshida (1990) solution A, w1..w3 and w0 = 1 − 2 Σ.
_TJ = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_Y6 = (0.784513610477557263819, 0.235573213359358133684, -1.17767998417887100695)
COMPOSITIONS = {
    2: (1.0,),
    4: (_TJ, 1.0 - 2.0 * _TJ, _TJ),
    6: _Y6 + (1.0 - 2.0 * sum(_Y6),) + _Y6[::-1],
}


def stages(order) -> tuple:
    """The composition of ``order`` (2, 4 or 6; :data:`COMPOSITIONS`) as (kick fractions, flow
    fractions) of one step h: K(a0 h) F(b0 h) K(a1 h) … F(b_{s−1} h) K(a_s h), consecutive half-kicks
    merged (a has one more entry than b; Σa = Σb = 1). Raises ValueError for another order."""
    if order not in COMPOSITIONS:
        raise ValueError(f"splitting order {order!r} must be one of {sorted(COMPOSITIONS)}")
    w = COMPOSITIONS[order]
    a = [0.5 * w[0]] + [0.5 * (w[i] + w[i + 1]) for i in range(len(w) - 1)] + [0.5 * w[-1]]
    return tuple(a), tuple(w)


def qmul(a, b) -> tuple:
    """Hamilton product of two quaternions given as 4-tuples of floats (scalar first)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def to_body(q, v) -> tuple:
    """R(q)ᵀ v: the inertial vector ``v`` (3 floats) in body axes, for the unit quaternion ``q`` (4
    floats, scalar first): v + w t + r' × t, t = 2 r' × v, r' = −(x, y, z) (as inside :func:`kick`)."""
    w, x, y, z = q
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (z * vy - y * vz), 2.0 * (x * vz - z * vx), 2.0 * (y * vx - x * vy)
    return vx + w * tx + (z * ty - y * tz), vy + w * ty + (x * tz - z * tx), vz + w * tz + (y * tx - x * ty)


def free_flow(y, mu, h) -> None:
    """Exact torque-free flow of the symmetric top over ``h`` seconds, in place on ``y`` = [q (4, unit,
    body → inertial, scalar first), ω (3, body, rad/s)], μ = C/A: q ← q ⊗ Rot(Λ̂_b, λh) ⊗ Rot(e3, σh),
    (ω1, ω2) ← Rot(e3, −σh)(ω1, ω2) (the module docstring; |q| kept to round-off)."""
    w1, w2, w3 = y[4], y[5], y[6]
    l3 = mu * w3
    lam = math.sqrt(w1 * w1 + w2 * w2 + l3 * l3)
    pw, px, py, pz = 1.0, 0.0, 0.0, 0.0
    if lam > 0.0:
        sl = math.sin(0.5 * lam * h) / lam
        pw, px, py, pz = math.cos(0.5 * lam * h), sl * w1, sl * w2, sl * l3
    sig = (1.0 - mu) * w3 * h
    cs, ss = math.cos(0.5 * sig), math.sin(0.5 * sig)
    pw, px, py, pz = pw * cs - pz * ss, px * cs + py * ss, py * cs - px * ss, pz * cs + pw * ss
    aw, ax, ay, az = y[0], y[1], y[2], y[3]
    y[0] = aw * pw - ax * px - ay * py - az * pz
    y[1] = aw * px + ax * pw + ay * pz - az * py
    y[2] = aw * py - ax * pz + ay * pw + az * px
    y[3] = aw * pz + ax * py - ay * px + az * pw
    c, s = math.cos(sig), math.sin(sig)
    y[4] = c * w1 + s * w2
    y[5] = -s * w1 + c * w2


def kick(y, t, dt, torque) -> None:
    """Exact flow over ``dt`` (s, may be negative) of the torques with the attitude and the time ``t``
    frozen, in place on ``y`` (as :func:`free_flow`). ``torque`` = [γ (rad/s²), n (rad/s), 1/τ (1/s),
    ê (3), up_par (3), up_perp (3), up_cross (3)]: up(t) = up_par + cos(nt) up_perp + sin(nt) up_cross
    (inertial); (ω1, ω2) += dt γ (u_y, −u_x), u = R(q)ᵀ up(t); ρ = ω3 − n (R(q)ᵀ ê)_z → ρ e^(−dt/τ)."""
    gam, n, rate = torque[0], torque[1], torque[2]
    w, x, yy, z = y[0], y[1], y[2], y[3]
    c, s = math.cos(n * t), math.sin(n * t)
    vx = torque[6] + c * torque[9] + s * torque[12]
    vy = torque[7] + c * torque[10] + s * torque[13]
    vz = torque[8] + c * torque[11] + s * torque[14]
    tx, ty, tz = 2.0 * (z * vy - yy * vz), 2.0 * (x * vz - z * vx), 2.0 * (yy * vx - x * vy)
    ux = vx + w * tx + (z * ty - yy * tz)             # R(q)ᵀ v = v + 2 r' × (r' × v + w v), r' = −r
    uy = vy + w * ty + (x * tz - z * tx)
    y[4] += dt * gam * uy
    y[5] -= dt * gam * ux
    if rate != 0.0:
        ex, ey, ez = torque[3], torque[4], torque[5]
        tx, ty = 2.0 * (z * ey - yy * ez), 2.0 * (x * ez - z * ex)
        kz = ez + w * 2.0 * (yy * ex - x * ey) + (yy * tx - x * ty)
        rest = n * kz
        y[6] = rest + (y[6] - rest) * math.exp(-dt * rate)


def rhs_kernel(t, y, p, dy) -> None:
    """The heavy symmetric top's right-hand side for DOP853 (:mod:`gyro_instrument.core.dop853_jit`'s
    kernel ``f(t, y, p, dy)``), y = [q (4), ω (3, body, rad/s)] as in :func:`free_flow`, dy/dt into ``dy``:
    Euler's equations ω̇1 = (1 − μ) ω3 ω2 + τ1/A, ω̇2 = −(1 − μ) ω3 ω1 + τ2/A, ω̇3 = τ3/C and
    q̇ = ½ q ⊗ (0, ω) + κ (1 − |q|²) q (a Baumgarte term, κ in 1/s, holding |q| at 1). The torques are
    :func:`kick`'s at the time ``t`` and the attitude q (not renormalised): (τ1, τ2)/A = γ (u_y, −u_x),
    u = R(q)ᵀ up(t), and τ3/C = −(ω3 − n (R(q)ᵀ ê)_z)/τ. ``p`` (:func:`rhs_params`) = [1 − μ, κ, τ (s; 0:
    no spin relaxation), then :func:`kick`'s torque array (empty: torque-free)]. The arithmetic, term for
    term, of :meth:`~gyro_instrument.instruments.free_gyroscope.FreeGyroscope.rhs_scalar`."""
    a, kappa = p[0], p[1]
    qw, qx, qy, qz, w1, w2, w3 = y[0], y[1], y[2], y[3], y[4], y[5], y[6]
    corr = kappa * (1.0 - (qw * qw + qx * qx + qy * qy + qz * qz))
    d1, d2, d3 = 0.0, 0.0, 0.0
    if p.size > 3:
        gam, n = p[3], p[4]
        c, s = math.cos(n * t), math.sin(n * t)
        vx = p[9] + c * p[12] + s * p[15]
        vy = p[10] + c * p[13] + s * p[16]
        vz = p[11] + c * p[14] + s * p[17]
        tx, ty, tz = 2.0 * (qz * vy - qy * vz), 2.0 * (qx * vz - qz * vx), 2.0 * (qy * vx - qx * vy)
        ux = vx + qw * tx + (qz * ty - qy * tz)       # R(q)ᵀ v, as in to_body
        uy = vy + qw * ty + (qx * tz - qz * tx)
        d1, d2 = gam * uy, -gam * ux
        if p[2] != 0.0:
            ex, ey, ez = p[6], p[7], p[8]
            tx, ty, tz = 2.0 * (qz * ey - qy * ez), 2.0 * (qx * ez - qz * ex), 2.0 * (qy * ex - qx * ey)
            kz = ez + qw * tz + (qy * tx - qx * ty)
            d3 = -(w3 - n * kz) / p[2]
    dy[0] = 0.5 * (-qx * w1 - qy * w2 - qz * w3) + corr * qw
    dy[1] = 0.5 * (qw * w1 + qy * w3 - qz * w2) + corr * qx
    dy[2] = 0.5 * (qw * w2 - qx * w3 + qz * w1) + corr * qy
    dy[3] = 0.5 * (qw * w3 + qx * w2 - qy * w1) + corr * qz
    dy[4] = a * w2 * w3 + d1
    dy[5] = -a * w1 * w3 + d2
    dy[6] = d3


def rhs_params(mu, kappa, decay_time_s, torque) -> np.ndarray:
    """:func:`rhs_kernel`'s parameter array: μ = C/A, κ (1/s), the spin relaxation time τ (s; 0 for
    none) and :func:`kick`'s ``torque`` array (empty for the torque-free body)."""
    return np.concatenate([[1.0 - float(mu), float(kappa), float(decay_time_s)], np.asarray(torque, dtype=float)])


@functools.cache
def compiled_rhs_kernel() -> "Callable":
    """:func:`rhs_kernel` compiled with :func:`~gyro_instrument.core.dop853_jit.rhs_signature` (numba's
    cache), or the plain function when :func:`gyro_instrument.core.jit.enabled` is False."""
    from gyro_instrument.core import dop853_jit  # noqa: PLC0415 - its compile step only when asked for
    if not jit.enabled():
        return rhs_kernel
    return jit.compiled(rhs_kernel, signature_or_function=dop853_jit.rhs_signature())


def _splitting_loop(free, kick_fn):
    """The step loop over :func:`free_flow` and :func:`kick` (``free``, ``kick_fn``: those functions,
    compiled or not): ``run(y, t0, times, h_max, a, b, mu, torque, out)``."""
    def run(y, t0, times, h_max, a, b, mu, torque, out):
        t = t0
        for j in range(times.size):
            span = times[j] - t
            nstep = 1
            if torque.size > 0 and span > 0.0:
                nstep = max(1, int(math.ceil(span / h_max * (1.0 - 1e-12))))
            h = span / nstep
            for _ in range(nstep if span > 0.0 else 0):
                if torque.size == 0:
                    free(y, mu, h)
                    continue
                ts = t
                for i in range(b.size):
                    kick_fn(y, ts, a[i] * h, torque)
                    free(y, mu, b[i] * h)
                    ts += b[i] * h
                kick_fn(y, ts, a[b.size] * h, torque)
                t += h
            t = times[j]
            nq = 1.0 / math.sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3])
            for i in range(4):
                y[i] *= nq
            out[:, j] = y
    return run


@functools.cache
def _compiled_loop():
    return jit.compiled(_splitting_loop(jit.compiled(free_flow), jit.compiled(kick)))


def splitting_run(y, t0, times, h_max, order, mu, torque, compiled=True) -> np.ndarray:
    """Compose :func:`free_flow` with :func:`kick` from the state ``y`` (7 floats, updated in place) at
    ``t0`` to each of ``times`` (increasing, ≥ t0, s) in steps of at most ``h_max`` (s) that end on every
    sample time; the composition of ``order`` (:func:`stages`). ``torque``: :func:`kick`'s array, or an
    empty array for the torque-free body (one exact step per sample). ``compiled=False``: the plain
    Python loop (the compiled one must agree with it). Returns the states, shape (7, m)."""
    a, b = (np.asarray(v, dtype=float) for v in stages(order))
    times = np.ascontiguousarray(times, dtype=float)
    out = np.empty((7, times.size))
    run = _compiled_loop() if compiled else _splitting_loop(free_flow, kick)
    run(y, float(t0), times, float(h_max), a, b, float(mu), np.asarray(torque, dtype=float), out)
    return out


class SplittingRun(Solver):
    """The splitting (:func:`splitting_run`) resumed block by block, a
    :class:`~gyro_instrument.core.solver.Solver` with no end.

    The state (7 floats: q, ω in body axes) and time are carried across blocks; the steps end on every
    sample, so the samples depend on the sample times only, never on how they are cut into blocks.
    :meth:`step` takes one composition step of ``h_max`` (of :data:`FREE_STEP_S` for the torque-free
    body, whose exact flow takes any step); :meth:`dense_output` composes from the step's start to
    each time asked (the method's own value there). No right-hand side is evaluated: ``nfev`` is 0.

    Parameters
    ----------
    y0 : array_like (7,)
        State at ``t0``: q (body → inertial, scalar first), ω in body axes (rad/s).
    t0 : float
        Start, s.
    h_max : float
        Largest step, s (``math.inf``: one exact step per sample, torque-free).
    order : int
        The composition's order (:func:`stages`).
    mu : float
        C/A.
    torque : array
        :func:`kick`'s array (empty: torque-free).
    """

    method = "splitting"
    #: Step of :meth:`step` for the torque-free body (its exact flow takes any), s.
    FREE_STEP_S = 1.0

    def __init__(self, y0, t0, h_max, order, mu, torque) -> None:
        super().__init__(t0)
        self.y = np.array(y0, dtype=float)
        self.h_max, self.order, self.mu = float(h_max), int(order), float(mu)
        self.torque = np.asarray(torque, dtype=float)
        self._y_old = None
        self.meta = {"integrator": f"splitting order {order}", "step_s": h_max}

    @property
    def nfev(self) -> int:
        """0: the exact flows and kicks evaluate no right-hand side."""
        return 0

    def _compose(self, y, t0, times) -> np.ndarray:
        return splitting_run(y, t0, times, self.h_max, self.order, self.mu, self.torque)

    def _step_impl(self):
        h = self.h_max if math.isfinite(self.h_max) else self.FREE_STEP_S
        self._y_old, t_old = self.y.copy(), self.t
        self._compose(self.y, t_old, np.array([t_old + h]))
        self.t_old, self.t = t_old, t_old + h

    def _dense_output_impl(self):
        y_old, t_old = self._y_old, self.t_old

        def sol(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            return np.column_stack([self._compose(y_old.copy(), t_old, np.array([ti])) for ti in t]) \
                if t.size else np.empty((7, 0))
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """States (7, len(t)) at the times ``t`` (s, increasing, from the previous block's last on);
        ``progress(t_i)`` after the block."""
        t = np.asarray(t, dtype=float)
        with self.clock():
            y = self._compose(self.y, self.t, t)
            if t.size:
                self.t = float(t[-1])
            self.t_old = self._y_old = self._dense = None          # the samples are not steps
        if progress is not None and t.size:
            progress(self.t)
        return Trajectory(t, y, 0, self.wall_time_s, self.cpu_time_s, self.method, dict(self.meta))

