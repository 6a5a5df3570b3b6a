"""Directing-plane gyroscope: Quet 1853 sec. 4 §1 (the gyrocompass), and its cone variant.

A body of revolution (moments A, C; μ = C/A) has its centre of mass fixed; its axis may turn
only in a plane fixed on the Earth (or on a cone of half-angle ε). Axes: ``oz`` the plane
normal, ``ox`` the projection of the north part of Earth's axis on the plane, ``oy = oz × ox``;
u is the angle of the rotor axis from ``ox``, counter-clockwise about ``oz``; ρ the relative
spin about the axis; ω the angle between the normal and Earth's axis.

Reduced model (``model: reduced``), exact for the rigid body when ``earth_rotation`` and
``centrifugal`` are both listed — the Lagrangian L = ½C(φ̇ + n sin ω cos u)² + ½A[(u̇ + r)² +
(n sin ω sin u)²] gives::

    u'' = −μ n sin ω ρ sin u − (μ − 1) n² sin² ω cos u sin u      (eq. 2 plus the dropped O(n²))
    d(ρ + n sin ω cos u) = 0                                       (eq. 3)

Quet's eq. (2) is the first term alone (``centrifugal`` absent). Small swings last
T = π / √(μ n ρ0 sin ω) (eq. 9: one swing, HALF the period); finite amplitude a multiplies
this by (2/π) K(sin(a/2)) (item 6: pendulum law). Hence n = π² / (μ ρ0 T² sin ω) (eq. 10;
item 8's printed π/(μρ0T²) is a misprint) and item 9: (T_m / T_h)² = cos γ.

Cone (``cone_half_angle_deg`` < 90): T = π √(sin ε / (μ n ρ0 sin ω)) (sec. 4 §1, end; the
printed second equation lacks a factor sin ε, the period is right). Integrated with the
generic :class:`~gyro_instrument.instruments.chain.HingeChain`; u is then the azimuth of
the axis about the cone axis, from the half-plane toward Earth's north axis.
"""

import math
import time

import numpy as np
from scipy.integrate import DOP853

from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.integrate import Trajectory, integrate
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import plane_frame
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.core.effect import DAMPING, RESTORING_LAW, RIGID_BODY, SPIN
from gyro_instrument.instruments.base import Column, DirectingModel, Instrument, Simulation, with_notes
from gyro_instrument.instruments.chain import HingeChain, Link, axis_rotation


def plane_normal_enu(plane, normal_enu, site):
    """Normal of the named directing plane in ENU.

    ``horizontal``: up (u counter-clockwise from north seen from above); ``meridian``: east;
    ``polar`` (normal along Earth's axis, Quet item 4: no restoring torque); ``custom``: given.
    """
    if plane == "horizontal":
        return np.array([0.0, 0.0, 1.0])
    if plane == "meridian":
        return np.array([1.0, 0.0, 0.0])
    if plane == "polar":
        return site.earth_axis_north_enu()
    return np.asarray(normal_enu, dtype=float)


def swing_duration_small_s(mu, earth_rate, spin, sin_omega, sin_eps=1.0):
    """One-swing duration of small oscillations, T = π √(sin ε / (μ n ρ0 sin ω)) (eq. 9 and
    the cone variant); ``inf`` when there is no restoring torque (items 1–4)."""
    k = mu * earth_rate * spin * sin_omega
    if k <= 0.0:
        return math.inf
    return math.pi * math.sqrt(sin_eps / k)


# ------------------------------------------------------------------ scalar DOP853 driver
# The reduced model has three state components and a right-hand side of a few sines: through
# ``solve_ivp`` nearly all of its cost is per-step overhead of numpy calls on length-3 arrays
# (~90 µs per step, 15 RHS calls per step through two wrappers). This driver runs the same
# method with plain floats (~18 µs per step):
# scipy's DOP853 tableau (Hairer's 8(5,3) pair, read from ``scipy.integrate.DOP853``), the same
# initial-step choice, error norm, step-size control and 7th-order dense output, so it takes
# the same steps and the same number of RHS evaluations and agrees with ``integrate(...,
# method="DOP853")`` to rounding (≤ 1e-13 rad in u over an hour of quet_paris, against the
# ~1e-10 rad integration error at rtol 1e-11). The stage arithmetic is
# generated once per state size with the coefficients as literals; the dense output is
# evaluated for all sample times at once after the run.

def _linear_combination(coeffs, terms):
    parts = [f"{float(c)!r} * {x}" for c, x in zip(coeffs, terms) if c != 0.0]
    return " + ".join(parts) if parts else "0.0"


def _dop853_source(n):
    """Source of ``attempt`` (one trial step: new state, new derivative, the 5th- and 3rd-order
    error estimates and the 13 stages) and ``dense`` (the three extra stages and the dense
    coefficients F3..F6 = h D K) for an ``n``-component state held in scalars."""
    A, B, C, E5, E3, D = DOP853.A, DOP853.B, DOP853.C, DOP853.E5, DOP853.E3, DOP853.D
    AX, CX, ns = DOP853.A_EXTRA, DOP853.C_EXTRA, DOP853.n_stages
    ys = ", ".join(f"y{i}" for i in range(n))

    def k(s):
        return ", ".join(f"k{s}_{i}" for i in range(n))

    def combo(coeffs, i, upto):
        return _linear_combination(coeffs[:upto], [f"k{j}_{i}" for j in range(upto)])

    allk = ", ".join(k(s) for s in range(ns + 1))
    src = [f"def attempt(f, t, h, {ys}, {k(0)}):"]
    for s in range(1, ns):
        args = ", ".join(f"y{i} + h * ({combo(A[s], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(C[s])!r} * h, {args})")
    for i in range(n):
        src.append(f"    z{i} = y{i} + h * ({combo(B, i, ns)})")
    zs = ", ".join(f"z{i}" for i in range(n))
    src.append(f"    {k(ns)}, = f(t + h, {zs})")
    e5 = ", ".join(combo(E5, i, ns + 1) for i in range(n))
    e3 = ", ".join(combo(E3, i, ns + 1) for i in range(n))
    src.append(f"    return ({zs},), ({k(ns)},), ({e5},), ({e3},), ({allk},)")
    src.append(f"def dense(f, t, h, {ys}, stages):")
    src.append(f"    {allk}, = stages")
    for r in range(AX.shape[0]):
        s = ns + 1 + r
        args = ", ".join(f"y{i} + h * ({combo(AX[r], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(CX[r])!r} * h, {args})")
    rows = ", ".join(f"h * ({combo(D[r], i, D.shape[1])})" for r in range(D.shape[0]) for i in range(n))
    src.append(f"    return ({rows},)")
    return "\n".join(src) + "\n"


_DOP853_KERNELS = {}


def _dop853_kernels(n):
    if n not in _DOP853_KERNELS:
        namespace = {}
        exec(compile(_dop853_source(n), f"<DOP853 scalar kernels, n = {n}>", "exec"), namespace)
        _DOP853_KERNELS[n] = (namespace["attempt"], namespace["dense"])
    return _DOP853_KERNELS[n]


def integrate_dop853_scalar(f, y0, t_eval, rtol=1e-10, atol=1e-12):
    """DOP853 on a small state held in Python floats; ``f(t, *y) -> tuple`` of the derivatives.

    Same method, step control and dense output as ``integrate(..., method="DOP853")`` (see the
    comment above); ``t_eval`` must increase. Returns a :class:`Trajectory` whose ``nfev``
    counts every RHS evaluation as ``integrate`` does (15 per accepted step, 12 per rejected,
    2 at the start).
    """
    t_eval = np.asarray(t_eval, dtype=float)
    y = tuple(float(v) for v in y0)
    n = len(y)
    if not all(math.isfinite(v) for v in y):
        raise IntegrationError(f"initial state is not finite: {y}")
    if t_eval.size == 1 or t_eval[-1] == t_eval[0]:
        return Trajectory(t_eval, np.array(y)[:, None].repeat(t_eval.size, axis=1), 0, 0.0, 0.0, "DOP853")
    attempt, dense = _dop853_kernels(n)
    rtol = max(float(rtol), 100 * np.finfo(float).eps)   # as scipy's validate_tol
    atol = float(atol)
    w0, c0 = time.perf_counter(), time.process_time()
    t, t_end = float(t_eval[0]), float(t_eval[-1])
    fy = tuple(f(t, *y))
    # Initial step: Hairer, Nørsett & Wanner II.4, as scipy's select_initial_step (order 7).
    sc = [atol + abs(v) * rtol for v in y]
    d0 = math.sqrt(sum((v / s) ** 2 for v, s in zip(y, sc)) / n)
    d1 = math.sqrt(sum((v / s) ** 2 for v, s in zip(fy, sc)) / n)
    h0 = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, t_end - t)
    f1 = f(t + h0, *[v + h0 * w for v, w in zip(y, fy)])
    d2 = math.sqrt(sum(((a - b) / s) ** 2 for a, b, s in zip(f1, fy, sc)) / n) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / 8)
    h_abs = min(100 * h0, h1, t_end - t)
    nfev, nrej = 2, 0
    t_old, t_new_all, h_all, y_old, coef = [], [], [], [], []
    expo = -1.0 / 8.0
    while t < t_end:
        min_step = 10 * abs(math.nextafter(t, math.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                raise IntegrationError(f"DOP853 failed at t = {t:.6g} s: required step size is less than "
                                       f"spacing between numbers")
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            h_abs = abs(h)
            z, fz, e5, e3, stages = attempt(f, t, h, *y, *fy)
            nfev += 12
            n5 = n3 = 0.0
            for a, b, e, g in zip(y, z, e5, e3):
                s = atol + max(abs(a), abs(b)) * rtol
                n5 += (e / s) ** 2
                n3 += (g / s) ** 2
            err = 0.0 if n5 == 0.0 and n3 == 0.0 else h_abs * n5 / math.sqrt((n5 + 0.01 * n3) * n)
            if err < 1.0:
                fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** expo)
                h_abs *= min(1.0, fac) if rejected else fac
                break
            h_abs *= max(0.2, 0.9 * err ** expo)   # also for a NaN error: the step shrinks
            rejected = True
            nrej += 1
        dy = [b - a for a, b in zip(y, z)]
        coef.append((*dy, *[h * a - d for a, d in zip(fy, dy)],
                     *[2 * d - h * (a + b) for a, b, d in zip(fy, fz, dy)], *dense(f, t, h, *y, stages)))
        nfev += 3
        t_old.append(t)
        t_new_all.append(t_new)
        h_all.append(h)
        y_old.append(y)
        t, y, fy = t_new, z, fz
    # Dense output at every sample time at once (scipy's Dop853DenseOutput, vectorised).
    idx = np.minimum(np.searchsorted(np.array(t_new_all), t_eval, side="left"), len(t_old) - 1)
    x = ((t_eval - np.array(t_old)[idx]) / np.array(h_all)[idx])[:, None]
    F = np.array(coef).reshape(len(coef), 7, n)[idx]
    out = np.zeros((t_eval.size, n))
    for i in range(6, -1, -1):
        out += F[:, i]
        out *= x if i % 2 == 0 else 1.0 - x
    out += np.array(y_old)[idx]
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    if not np.all(np.isfinite(out)):
        raise IntegrationError("DOP853 produced a non-finite state")
    return Trajectory(t_eval, out.T.copy(), nfev, wall, cpu, "DOP853",
                      {"rtol": rtol, "atol": atol, "nsteps": len(t_old), "nrejected": nrej,
                       "driver": "scalar"})


class PlaneGyroscope(Instrument):
    """Gyroscope whose axis turns in a directing plane (or on a cone) fixed on the Earth."""

    type_name = "plane_gyroscope"
    summary = "rotor axis held in a directing plane or cone (Quet sec. 4 §1)"
    PARAMS = (
        Param("plane", kind="str", default="horizontal", choices=("horizontal", "meridian", "polar", "custom"),
              doc="directing plane: horizontal, meridian, polar (normal along Earth's axis) or custom"),
        Param("normal_enu", kind="vec3", default=None, doc="plane normal in ENU when plane = custom"),
        Param("cone_half_angle_deg", default=90.0, low=0.0, high=90.0, open_low=True,
              doc="half-angle ε of the directing cone about the normal; 90 = plane"),
        Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True,
              doc="μ = C/A, axial over transverse moment (≤ 2 for a rigid body of revolution)"),
        Param("transverse_inertia_kg_m2", default=1.0e-3, low=0.0, open_low=True, doc="A, kg m^2"),
        Param("spin_rate_rad_s", default=2 * math.pi * 100.0, low=-1.0e6, high=1.0e6,
              doc="initial relative spin ρ0 about the axis, rad/s (positive: Earth's sense when u = 0)"),
        Param("initial_angle_deg", default=math.degrees(0.1), low=-180.0, high=180.0,
              doc="initial angle u0 of the axis from the equilibrium line, degrees"),
        Param("initial_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6, doc="initial u̇0, degrees/s"),
        Param("model", kind="str", default="reduced", choices=("reduced", "chain"),
              doc="reduced 1-DOF equation or the generic hinge chain (cone: always chain)"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
    )
    MECHANICS = frozenset({RIGID_BODY, DAMPING, SPIN, RESTORING_LAW})
    MEASURED_CHANNELS = ("angle",)
    JOINTS = ("axis", "rotor")
    SHOWS_AXIS = True
    SIMULATOR_NODE = "gyrocompass_sim"
    COLUMNS = (Column("angle", "rad", "u: axis angle from the north projection, counter-clockwise about the normal"),
               Column("angle_rate", "rad/s", "du/dt"),
               Column("spin_rate", "rad/s", "ρ: relative spin of the rotor about its axis"))

    @classmethod
    def check_params(cls, prefix, p):
        if p["plane"] == "custom" and p["normal_enu"] is None:
            raise SceneError(f"{prefix}.normal_enu", None, "is required when plane = custom (3 numbers, ENU)")

    def __init__(self, name, site, params, effects):
        super().__init__(name, site, params, effects)
        self.normal = plane_normal_enu(self.plane, self.normal_enu, site)
        self.frame, self.sin_omega = plane_frame(self.normal, site)
        self.eps = math.radians(self.cone_half_angle_deg)
        self.is_cone = self.cone_half_angle_deg < 90.0
        self.mu = self.inertia_ratio
        self.A = self.transverse_inertia_kg_m2
        self.C = self.mu * self.A
        self.u0 = math.radians(self.initial_angle_deg)
        self.ud0 = math.radians(self.initial_rate_deg_s)

    # ---------------------------------------------------------------- predictions
    def _swing_duration_small_s(self, n):
        """Eq. (9) (or the cone form) at Earth rate ``n``."""
        return swing_duration_small_s(self.mu, n, self.spin_rate_rad_s, self.sin_omega,
                                      math.sin(self.eps) if self.is_cone else 1.0)

    def predictions(self):
        """Eq. (9) (or the cone form), the finite-amplitude factor and eq. (10)'s ingredients, for
        the model as simulated: without ``earth_rotation`` n = 0, there is no directing torque
        μ n ρ0 sin ω and the durations are infinite (``null`` in JSON); without
        ``finite_amplitude`` the small-angle model swings in T0 at any amplitude."""
        n = self.model_earth_rate()
        T0 = self._swing_duration_small_s(n)
        factor = finite_amplitude_factor(self.u0) if self.has("finite_amplitude") else 1.0
        out = {"sin_omega": self.sin_omega,
               "swing_duration_small_s": T0,
               "swing_duration_s": T0 * factor if math.isfinite(T0) else math.inf,
               "period_s": 2.0 * T0,
               "conserved_spin_rad_s": self.spin_rate_rad_s + n * self.sin_omega * math.cos(self.u0)}
        T_site = self._swing_duration_small_s(self.site.earth_rate_rad_s)
        rest = " (only the O(n²) centrifugal term acts)" if self.has("centrifugal") else ""
        return with_notes(out, self.missing_effect_note(
            "earth_rotation", f"no directing torque μ n ρ0 sin ω (eq. 9): the axis stays where it is released{rest}, "
                              f"swing durations null (with it T0 = {T_site:.6g} s)"),
            self.missing_effect_note(
            "finite_amplitude", "small-angle model: swing_duration_s = swing_duration_small_s at any amplitude"))

    def axis_direction_enu(self, position):
        """Rotor axis in ENU, (m, 3): cos u · ox + sin u · oy in the plane's frame (``core.site.plane_frame``),
        u the ``axis`` joint (rad)."""
        import numpy as np
        from gyro_instrument.core.site import plane_frame
        R, _ = plane_frame(self.normal, self.site)
        u = np.asarray(position)[:, 0]
        return np.cos(u)[:, None] * R[:, 0] + np.sin(u)[:, None] * R[:, 1]

    def directing_model(self):
        """What an estimator may know of this instrument: K = (π/T0)² = gain · n ρ · sin ω(γ), with
        gain = μ (μ / sin ε on a cone) and sin ω from the plane normal (ENU) and the latitude."""
        gain = self.mu / (math.sin(self.eps) if self.is_cone else 1.0)
        # The exact equation adds (μ − 1) n² sin² ω to K (module docstring): K/(μρ) = y0 (1 + c2 y0 / ρ)
        # with y0 = n sin ω and c2 = (μ − 1)/μ. Derived for the plane only (ε = 90°).
        c2 = 0.0 if self.is_cone else (self.mu - 1.0) / self.mu
        return DirectingModel(gain=gain, second_order=c2, normal_enu=tuple(float(v) for v in self.normal),
                              label=self.plane, angle_channel="angle",
                              null_reason="a directing plane perpendicular to Earth's axis (horizontal at a pole) "
                                          "has no restoring torque (Quet sec. 4 §1 item 4)")

    def scales(self, duration_s):
        n = self.site.earth_rate_rad_s
        T0 = self._swing_duration_small_s(n)           # the scales of the rotating Earth (effect sizes)
        return {"earth_rate_rad_s": n, "gyro_rate_rad_s": abs(self.mu * self.spin_rate_rad_s) or None,
                "restoring_rate_rad_s": math.pi / T0 if math.isfinite(T0) else 0.0,
                "amplitude_rad": abs(self.u0), "duration_s": duration_s}

    # ---------------------------------------------------------------- models
    def reduced_rhs_scalar(self):
        """Right-hand side of the reduced model on floats, ``f(t, u, u̇, ρ) -> (u̇, ü, ρ̇)``; only
        listed effects::

            ü = −μ p ρ s − (μ − 1) p² cos u · s − d u̇     (eq. 2; O(n²) term: ``centrifugal``)
            ρ̇ = p sin u · u̇ − ρ / τ_s                       (eq. 3; spin decay: ``spin_decay``)

        with p = n sin ω, s = sin u (``finite_amplitude``; u for Quet's small-swing form) and d the
        ``pivot_damping`` rate. Absent effects enter as zero coefficients."""
        p = self.site.earth_rate_rad_s * self.sin_omega
        mu = self.mu
        rot = self.has("earth_rotation")
        a = mu * p if rot else 0.0                                       # eq. (2)
        pr = p if rot else 0.0                                           # eq. (3)
        b = (mu - 1.0) * p * p if self.has("centrifugal") else 0.0       # the dropped O(n²) term
        damp = self.effect("pivot_damping").rate() if self.has("pivot_damping") else 0.0
        tau_s = self.effect("spin_decay").time_constant_s if self.has("spin_decay") else 0.0
        decay = 1.0 / tau_s if tau_s else 0.0
        sin, cos = math.sin, math.cos

        if self.restoring_law() is not None:       # finite_amplitude: sin u
            def rhs(t, u, ud, rho):
                su = sin(u)
                return ud, -(a * rho + b * cos(u)) * su - damp * ud, pr * su * ud - decay * rho
        else:
            def rhs(t, u, ud, rho):
                return ud, -(a * rho + b * cos(u)) * u - damp * ud, pr * sin(u) * ud - decay * rho
        return rhs

    def reduced_rhs(self):
        """Right-hand side of the reduced model for y = [u, u̇, ρ] (array form of
        :meth:`reduced_rhs_scalar`, eqs. 2–3); only listed effects."""
        f = self.reduced_rhs_scalar()

        def rhs(t, y):
            u, ud, rho = y
            return np.array(f(t, u, ud, rho))
        return rhs

    def build_chain(self):
        """The same instrument as a hinge chain: swing hinge about the normal (massless frame),
        an optional fixed tilt to the cone, then the rotor's spin hinge."""
        links = [Link("frame", np.array([0.0, 0.0, 1.0]), np.zeros((3, 3)))]
        # Rotor axis along body x; tilt about y by (π/2 − ε) puts it at ε from the normal.
        tilt = axis_rotation([0.0, 1.0, 0.0], -(math.pi / 2 - self.eps)) if self.is_cone else np.eye(3)
        links[0].swing_inertia = self.A * (math.sin(self.eps) ** 2 if self.is_cone else 1.0)
        links.append(Link("rotor", np.array([1.0, 0.0, 0.0]), np.diag([self.C, self.A, self.A]),
                          pre_rotation=tilt, spin_inertia=self.C))
        g = np.array([0.0, 0.0, -self.site.gravity_m_s2])
        return HingeChain(links, self.frame, self.site.earth_rate_enu(), g, self.effects.values())

    #: The effects :meth:`reduced_rhs_scalar` is derived for by hand. With any other active effect
    #: (one registered later for a kind this instrument sums) the hinge chain, which sums every
    #: active effect's terms, is integrated instead, as for a cone.
    REDUCED_EFFECTS = frozenset({"earth_rotation", "centrifugal", "finite_amplitude", "spin_decay", "pivot_damping"})

    def simulate(self, t, model=None):
        """Integrate from rest relative to the Earth at u0 (with u̇0) and spin ρ0: the reduced model
        (scalar DOP853) or the hinge chain — always the chain on a cone or with an active effect
        outside :data:`REDUCED_EFFECTS` (``extra["model"]`` says which ran)."""
        model = "chain" if self.is_cone or not set(self.effects) <= self.REDUCED_EFFECTS else (model or self.model)
        t = np.asarray(t, dtype=float)
        if model == "reduced":
            if not self.has("finite_amplitude") and abs(self.u0) > 0.5:
                pass  # the linear model is what the scene asks for; the describe table shows its cost
            y0 = [self.u0, self.ud0, self.spin_rate_rad_s]
            if t.ndim == 1 and t.size and np.all(np.diff(t) >= 0.0):
                traj = integrate_dop853_scalar(self.reduced_rhs_scalar(), y0, t, rtol=self.rtol, atol=1e-13)
            else:   # unusual sample times: the generic driver (same method) validates or handles them
                traj = integrate(self.reduced_rhs(), y0, t, rtol=self.rtol, atol=1e-13)
            u, ud, rho = traj.y
            return Simulation(t, {"angle": u, "angle_rate": ud, "spin_rate": rho}, traj, extra={"model": model})
        chain = self.build_chain()
        # ρ = φ̇ + u̇ cos ε (the frame's rate has a component cos ε along a cone axis).
        cos_eps = math.cos(self.eps) if self.is_cone else 0.0
        phid0 = self.spin_rate_rad_s - self.ud0 * cos_eps
        traj = integrate(chain.rhs, [self.u0, 0.0, self.ud0, phid0], t, rtol=self.rtol, atol=1e-13)
        u, phi, ud, phid = traj.y
        rho = phid + ud * cos_eps
        return Simulation(t, {"angle": u, "angle_rate": ud, "spin_rate": rho}, traj,
                          extra={"rotor_angle": phi, "chain": chain, "model": model})
