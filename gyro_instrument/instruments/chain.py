"""Generic hinge chain about a fixed point on the rotating Earth (Kane's method).

Every fixed-point rigid instrument here is a chain of bodies, each turning about one hinge
carried by its parent, all sharing the fixed point: the directing-plane gyroscope (a hinge
about the plane normal, then the rotor's spin hinge; Quet sec. 4 §1), its cone variant, the
two-ring gimbal gyroscope (outer ring about PP', inner ring about NN', rotor about oQ;
sec. 4 §III) and the compound pendulum (sec. 3 §VI).

Relative kinematics (with respect to the Earth) are built recursively in body axes::

    w_k = R_kᵀ w_{k−1} + q̇_k e_k
    α_k = R_kᵀ α_{k−1} + q̈_k e_k + q̇_k (R_kᵀ w_{k−1}) × e_k

with R_k = R0_k Rot(e_k, q_k). The absolute angular velocity is w_k + Ω_k and the absolute
angular acceleration α_k + Ω_k × w_k (Ω constant in Earth axes), so the inertia torque
I α_abs + ω_abs × I ω_abs = [I α + w × I w] + [terms linear in Ω] + [Ω × I Ω]. The last two
come from the ``earth_rotation`` and ``centrifugal`` effects and are evaluated only when the
scene lists them. Kane's equations Σ_k P_kjᵀ τ*_k = Q_j (P_kj = e_j in body-k axes, the
partial angular velocity) give M(q) q̈ = Q − bias(q, q̇), solved at every step.

Gravity acts through each body's centre-of-mass offset ``com_m`` and ``mass_kg``; hinge
torques (damping, bearing friction) are callables of (q, q̇, w).
"""

from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.effects.centrifugal import rigid_body_inertia_torque_quadratic
from gyro_instrument.core.vector import cross3
from gyro_instrument.effects.earth_rotation import rigid_body_inertia_torque_linear


def axis_rotation(axis, angle):
    """Rotation matrix about a unit ``axis`` by ``angle`` (right-hand rule), Rodrigues' formula."""
    a = np.asarray(axis, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    x, y, z = a
    C = 1.0 - c
    return np.array([[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]])


@dataclass
class Link:
    """One body of the chain.

    Parameters
    ----------
    name : str
    axis : array (3,)
        Unit hinge axis in this body's axes (also fixed in the parent's pre-hinge axes).
    inertia : array (3, 3)
        Inertia tensor about the fixed point, in this body's axes, kg m².
    pre_rotation : array (3, 3)
        Constant rotation from the parent's axes to this body's axes at q = 0.
    locked : bool
        A locked hinge keeps q = ``locked_angle`` and q̇ = 0 (reaction torques absorb the rest).
    mass_kg, com_m : float, array (3,)
        Mass and centre-of-mass offset from the fixed point (body axes), for gravity.
    """

    name: str
    axis: np.ndarray
    inertia: np.ndarray
    pre_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    locked: bool = False
    locked_angle: float = 0.0
    mass_kg: float = 0.0
    com_m: np.ndarray = field(default_factory=lambda: np.zeros(3))


class HingeChain:
    """Equations of motion of a hinge chain in the Earth frame.

    Parameters
    ----------
    links : list of Link
    base_rotation : array (3, 3)
        Columns: the base axes expressed in ENU.
    omega_enu : array (3,)
        Earth-rate vector in ENU (rad/s).
    gravity_enu : array (3,)
        Gravity vector in ENU (m/s²), e.g. (0, 0, −g).
    linear, quadratic : bool
        Evaluate the O(Ω) (``earth_rotation``) and O(Ω²) (``centrifugal``) inertia torques.
    hinge_torques : callable, optional
        ``f(q, qd, w_rel_axis) -> array`` of applied hinge torques for all links (same length
        as ``links``), e.g. damping or bearing friction. ``w_rel_axis[k]`` is the relative
        angular velocity of body k along its own hinge axis.
    """

    def __init__(self, links, base_rotation, omega_enu, gravity_enu, linear=True, quadratic=True,
                 hinge_torques=None):
        self.links = list(links)
        self.nl = len(self.links)
        self.free = [k for k, L in enumerate(self.links) if not L.locked]
        self.nf = len(self.free)
        self.base = np.asarray(base_rotation, dtype=float)
        self.omega_base = self.base.T @ np.asarray(omega_enu, dtype=float)
        self.gravity_base = self.base.T @ np.asarray(gravity_enu, dtype=float)
        self.linear = linear and np.any(self.omega_base != 0.0)
        self.quadratic = quadratic and np.any(self.omega_base != 0.0)
        self.hinge_torques = hinge_torques
        self.axes = [np.asarray(L.axis, dtype=float) / np.linalg.norm(L.axis) for L in self.links]
        self.gravity_on = any(L.mass_kg != 0.0 and np.any(L.com_m) for L in self.links)

    def full_coordinates(self, qf, qdf):
        """Expand free coordinates to all links (locked ones at their locked angle)."""
        q = np.array([L.locked_angle for L in self.links], dtype=float)
        qd = np.zeros(self.nl)
        q[self.free] = qf
        qd[self.free] = qdf
        return q, qd

    def orientations(self, q):
        """Rotation matrices B_k (body k axes -> base axes) for all links."""
        B, out = np.eye(3), []
        for k, L in enumerate(self.links):
            B = B @ L.pre_rotation @ axis_rotation(self.axes[k], q[k])
            out.append(B)
        return out

    def kinematics(self, q, qd):
        """Relative angular velocities w_k, velocity-product accelerations a0_k (q̈ = 0),
        the rotation matrices R_k and the partial angular velocities P[k][j]."""
        nl = self.nl
        w, a0, R, B = [], [], [], []
        P = [[None] * nl for _ in range(nl)]
        w_prev = np.zeros(3)
        a_prev = np.zeros(3)
        B_prev = np.eye(3)
        for k, L in enumerate(self.links):
            Rk = L.pre_rotation @ axis_rotation(self.axes[k], q[k])
            Rt = Rk.T
            wp = Rt @ w_prev
            e = self.axes[k]
            wk = wp + qd[k] * e
            ak = Rt @ a_prev + qd[k] * cross3(wp, e)
            for j in range(k):
                P[k][j] = Rt @ P[k - 1][j]
            P[k][k] = e
            B_prev = B_prev @ Rk
            w.append(wk)
            a0.append(ak)
            R.append(Rk)
            B.append(B_prev)
            w_prev, a_prev = wk, ak
        return w, a0, B, P

    def accelerations(self, qf, qdf):
        """q̈ of the free coordinates."""
        q, qd = self.full_coordinates(qf, qdf)
        w, a0, B, P = self.kinematics(q, qd)
        nf = self.nf
        M = np.zeros((nf, nf))
        rhs = np.zeros(nf)
        if self.hinge_torques is not None:
            w_axis = np.array([np.dot(w[k], self.axes[k]) for k in range(self.nl)])
            Q = self.hinge_torques(q, qd, w_axis)
            rhs += Q[self.free]
        for k, L in enumerate(self.links):
            I = L.inertia
            tau = I @ a0[k] + cross3(w[k], I @ w[k])
            if self.linear or self.quadratic:
                om = B[k].T @ self.omega_base
                if self.linear:
                    tau = tau + rigid_body_inertia_torque_linear(I, w[k], om)
                if self.quadratic:
                    tau = tau + rigid_body_inertia_torque_quadratic(I, om)
            if L.mass_kg and self.gravity_on:
                g_b = B[k].T @ self.gravity_base
                tau = tau - cross3(L.com_m, L.mass_kg * g_b)
            for a, j in enumerate(self.free):
                if j > k:
                    break
                pj = P[k][j]
                rhs[a] -= np.dot(pj, tau)
                Ipj = I @ pj
                for b, i in enumerate(self.free):
                    if i > k:
                        break
                    M[a, b] += np.dot(P[k][i], Ipj)
        if nf == 1:
            return rhs / M[0, 0]
        return np.linalg.solve(M, rhs)

    def rhs(self, t, y):
        """State derivative for y = [q_free, q̇_free]."""
        nf = self.nf
        return np.concatenate([y[nf:], self.accelerations(y[:nf], y[nf:])])

    def energy_relative(self, qf, qdf):
        """Relative kinetic energy ½ Σ w_kᵀ I_k w_k plus gravity potential (J)."""
        q, qd = self.full_coordinates(qf, qdf)
        w, _, B, _ = self.kinematics(q, qd)
        e = 0.0
        for k, L in enumerate(self.links):
            e += 0.5 * w[k] @ L.inertia @ w[k]
            if L.mass_kg:
                e -= L.mass_kg * np.dot(B[k] @ L.com_m, self.gravity_base)
        return e

    def axis_in_enu(self, qf, link, axis_body):
        """Direction of a body-fixed vector of ``link`` in ENU for free coordinates qf."""
        q, _ = self.full_coordinates(qf, np.zeros(self.nf))
        B = self.orientations(q)[link]
        return self.base @ (B @ np.asarray(axis_body, dtype=float))


def hinge_friction(n_links, damping_rate=0.0, swing_inertias=None, spin_link=None, spin_inertia=0.0,
                   spin_time_constant_s=0.0):
    """Hinge torques for the ``pivot_damping`` and ``spin_decay`` effects, or None when neither acts.

    Swinging hinge k gets −(2/τ_d) J_k q̇_k (amplitude e-folding in τ_d); the rotor's bearing gets
    −C q̇_spin / τ_s — friction acts on the joint rate, the rotor's rate relative to its carrier.

    Parameters
    ----------
    swing_inertias : dict
        link index -> swinging inertia J (kg m²).
    """
    swing = dict(swing_inertias or {})
    if not (damping_rate and swing) and not (spin_time_constant_s and spin_link is not None):
        return None

    def torques(q, qd, w_axis):
        out = np.zeros(n_links)
        if damping_rate:
            for k, J in swing.items():
                out[k] = -damping_rate * J * qd[k]
        if spin_time_constant_s and spin_link is not None:
            out[spin_link] = -spin_inertia * qd[spin_link] / spin_time_constant_s
        return out
    return torques
