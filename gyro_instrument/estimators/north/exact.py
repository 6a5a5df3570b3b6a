"""North by fitting the swing equation itself to the rotor-on and rotor-off records (issue 33).

Part of :mod:`gyro_instrument.estimators.north` (its docstring states the sign convention). In the
clockwise scale reading w (= −angle, azimuth less the mount) a horizontal gyroscope on a torsion
tape obeys (Quet 1853 sec. 4 §1 eq. 2 with the sine law and its O(n²) term, the tape of
:func:`.fit.tape_north`, viscous pivot damping)::

    ẅ = −(K e^(−λτ) + b cos e) s(e) − k_B (w − Z − Ż τ) − d ẇ,    e = w − N,   τ = t − t_ref

with s = sin (``finite_amplitude``; s(e) = e otherwise), K = μ n ρ0 cos γ the directing constant
per inertia (D_K/A), b = (μ − 1) n² cos² γ the dropped O(n²) term, λ the spin's decay rate, k_B the
tape's D_B/A, Z its zero (drifting at Ż) and d the damping rate. With the rotor off, K = 0 (the
tape alone: a torsion pendulum). N, the reading of true north, is the parameter sought; K, k_B,
Z, Ż, d and each record's initial reading and rate are fitted with it (what the scene declares
decides which: no tape, no k_B or Z; no drift, no Ż), b and λ are known from the scene (b is 1e-8
of K, λ zero unless the spin decays).

Least squares over both records jointly is the maximum-likelihood estimate in white Gaussian
noise; its Jacobian comes from the variational (sensitivity) equations integrated with the state,
so σ² (JᵀJ)⁻¹ is the inverse Fisher information of the whole problem (tape calibration included)
at the estimate: σ(N) is the Cramér–Rao bound (:func:`crlb`). Nothing is linearised: the
equilibrium off north (D_K sin(c − N) = D_B (Z − c)), the asymmetric swing about it, the
drifting tape zero and the damping are all in the equation fitted.
"""

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

from gyro_instrument.core import dop853_jit, jit
from gyro_instrument.core.errors import SceneError

#: global parameters, in order; each record adds its initial reading and rate
GLOBAL = ("north", "directing", "tape", "zero", "zero_rate", "damping")
RTOL = 1e-11


@dataclass(frozen=True)
class SwingEquation:
    """What the fit knows of the swing equation and which of its constants it fits.

    Attributes
    ----------
    sine_law : bool
        s(e) = sin e (``finite_amplitude``) or e.
    second_order_per_s2 : float
        b = (μ − 1) n² sin² ω (1/s², known; 0 without ``centrifugal``).
    spin_decay_per_s : float
        λ (1/s, known; 0 without ``spin_decay``).
    tape, drift, damping : bool
        Fit k_B and Z (a torsion tape), Ż (a drifting tape zero), d.
    t_ref_s : float
        The reference time τ = 0 of K, Z and the drift (s).
    """

    sine_law: bool = True
    second_order_per_s2: float = 0.0
    spin_decay_per_s: float = 0.0
    tape: bool = False
    drift: bool = False
    damping: bool = True
    t_ref_s: float = 0.0

    def names(self, records) -> list:
        """Names of the fitted parameters for ``records`` (a tuple of 'on'/'off' kinds)."""
        keep = {"north": True, "directing": "on" in records, "tape": self.tape, "zero": self.tape,
                "zero_rate": self.tape and self.drift, "damping": self.damping}
        out = [g for g in GLOBAL if keep[g]]
        for i, kind in enumerate(records):
            out += [f"{kind}{i}_w0", f"{kind}{i}_v0"]
        return out


@dataclass(frozen=True)
class Record:
    """One swing record in the clockwise reading: times (s), readings w (rad, unwrapped), kind."""

    t: np.ndarray
    w: np.ndarray
    kind: str        # "on" (rotor on) or "off" (rotor off: the tape alone)


#: the forcing codes of the sensitivity equations, by parameter (initial states: none)
_CODES = {"north": 0, "directing": 1, "tape": 2, "zero": 3, "zero_rate": 4, "damping": 5}
_HEAD = 12


def _kernel(t, y, p, dy):
    """The swing equation (module docstring) and its sensitivities, ``f(t, y, p, dy)`` for
    :class:`~gyro_instrument.core.dop853_jit.CompiledRun`: y = [w, ẇ, (∂w/∂θ_j, ∂ẇ/∂θ_j) ...];
    p = [N, K, k_B, Z, Ż, d, b, λ, t_ref, sine law (1/0), rotor on (1/0), P, code_1 … code_P] with
    code_j the parameter's :data:`_CODES` entry (−1: an initial state, no forcing)."""
    N, K, kb, Z, Zd, d, b, lam, t_ref = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
    w, v = y[0], y[1]
    tau = t - t_ref
    e = w - N
    se, ce = math.sin(e), math.cos(e)
    if p[9] > 0.5:
        s, ds = se, ce
    else:
        s, ds = e, 1.0
    decay = math.exp(-lam * tau) * p[10]
    Kt = K * decay
    g = (Kt + b * ce) * s
    dg = Kt * ds + b * (ce * ds - se * s)
    stretch = w - Z - Zd * tau
    dy[0] = v
    dy[1] = -g - kb * stretch - d * v
    a = -dg - kb
    for j in range(int(p[11])):
        code = int(p[_HEAD + j])
        f = 0.0
        if code == 0:
            f = dg
        elif code == 1:
            f = -decay * s
        elif code == 2:
            f = -stretch
        elif code == 3:
            f = kb
        elif code == 4:
            f = kb * tau
        elif code == 5:
            f = -v
        dy[2 + 2 * j] = y[3 + 2 * j]
        dy[3 + 2 * j] = a * y[2 + 2 * j] - d * y[3 + 2 * j] + f


@functools.cache
def _compiled_kernel():
    return jit.compiled(_kernel, signature_or_function=dop853_jit.rhs_signature())


def warm() -> None:
    """Import numba and load the swing kernel and the DOP853 driver (numba's cache: 1-2 s of CPU in a
    new process, most of the estimator node's final estimate when it was paid there) with one swing
    over three samples; nothing without numba."""
    if jit.enabled():
        swing(SwingEquation(), dict.fromkeys(GLOBAL, 0.0), "on", np.array([0.0, 0.5, 1.0]), 0.01, 0.0,
              ("north", "on0_w0"))


def _kernel_params(eq, par, kind, idx) -> np.ndarray:
    head = [par.get(g, 0.0) for g in GLOBAL] + [eq.second_order_per_s2, eq.spin_decay_per_s, eq.t_ref_s,
                                                 1.0 if eq.sine_law else 0.0, 1.0 if kind == "on" else 0.0, len(idx)]
    return np.array(head + [_CODES.get(n, -1) for n in idx], dtype=float)


def swing(eq, par, rec_kind, t, reading0, rate0, idx=()) -> tuple:
    """Integrate one record from (reading0, rate0) at t[0]: (w (n,), ∂w/∂θ (n, len(idx))).

    ``par``: {name: value} of :data:`GLOBAL`; ``idx``: the parameter names whose sensitivities are
    wanted (a record's own initial reading and rate are named ``*_w0`` / ``*_v0``).
    """
    t = np.asarray(t, dtype=float)
    idx = list(idx)
    P = len(idx)
    y0 = np.zeros(2 + 2 * P)
    y0[0], y0[1] = reading0, rate0
    for j, name in enumerate(idx):
        if name.endswith("_w0"):
            y0[2 + 2 * j] = 1.0
        elif name.endswith("_v0"):
            y0[3 + 2 * j] = 1.0
    p = _kernel_params(eq, par, rec_kind, idx)
    if jit.enabled():
        run = dop853_jit.CompiledRun(_compiled_kernel(), p, y0, t[0], RTOL, 1e-15)
        y = run.advance(t).y
        return y[0], y[2::2].T
    dy = np.empty_like(y0)

    def rhs(tt, yy):
        _kernel(tt, yy, p, dy)
        return dy.copy()
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", t_eval=t, rtol=RTOL, atol=1e-15)
    if not sol.success:
        raise SceneError("record", f"{t.size} samples", f"the swing equation could not be integrated: {sol.message}")
    return sol.y[0], sol.y[2::2].T


def _split(names, x):
    return {n: float(v) for n, v in zip(names, x)}


def _evaluate(eq, records, names, x):
    """(residuals, Jacobian) of all records at parameters x."""
    par = _split(names, x)
    res, jac = [], []
    for i, rec in enumerate(records):
        own = [f"{rec.kind}{i}_w0", f"{rec.kind}{i}_v0"]
        idx = [n for n in names if not n.endswith(("_w0", "_v0")) or n in own]
        if rec.kind == "off":
            idx = [n for n in idx if n != "directing"]
        w, S = swing(eq, par, rec.kind, rec.t, par[own[0]], par[own[1]], idx)
        res.append(w - rec.w)
        J = np.zeros((rec.t.size, len(names)))
        for j, n in enumerate(idx):
            J[:, names.index(n)] = S[:, j]
        jac.append(J)
    return np.concatenate(res), np.vstack(jac)


@dataclass(frozen=True)
class ExactFit:
    """The joint fit: parameters, their covariance, the noise σ used and the residual rms.

    ``north_rad`` is the clockwise reading of true north (the mount azimuth is (−N) mod 2π);
    ``sigma_rad`` its σ (the Cramér–Rao bound at the estimate); ``params``/``cov`` in the order
    of ``names`` (SI: rad, 1/s², 1/s).
    """

    names: tuple
    params: np.ndarray
    cov: np.ndarray
    noise_sigma_rad: float
    sigma_source: str
    residual_rms_rad: float
    n_samples: int
    nfev: int

    def value(self, name) -> float:
        return float(self.params[self.names.index(name)])

    def sigma(self, name) -> float:
        i = self.names.index(name)
        return float(math.sqrt(self.cov[i, i]))

    @property
    def north_rad(self) -> float:
        return self.value("north")

    @property
    def sigma_rad(self) -> float:
        return self.sigma("north")

    def par(self) -> dict:
        return _split(self.names, self.params)


class NotConverged(SceneError):
    """:func:`fit` stopped at its evaluation limit (a start too far from the optimum)."""


def fit(eq, records, start, noise_sigma_rad=None, max_nfev=60) -> ExactFit:
    """Least squares of the swing equation over ``records`` (each a :class:`Record`).

    ``start``: {name: value} for every name of ``eq.names(kinds)``. σ: ``noise_sigma_rad`` when given
    (the sensor's), else the residual rms with (samples − parameters) degrees of freedom.

    Raises
    ------
    NotConverged
        (a SceneError) when the fit does not converge.
    SceneError
        When its information matrix is singular (a parameter the records cannot determine).
    """
    kinds = tuple(r.kind for r in records)
    names = eq.names(kinds)
    x0 = np.array([start[n] for n in names], dtype=float)
    cache = {}

    def both(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = _evaluate(eq, records, names, x)
        return cache[key]

    sol = least_squares(lambda x: both(x)[0], x0, jac=lambda x: both(x)[1], method="lm", x_scale="jac",
                        xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=max_nfev)
    if sol.status <= 0:
        raise NotConverged("record", f"{sum(r.t.size for r in records)} samples", f"the swing equation's fit did not "
                         f"converge in {sol.nfev} evaluations ({sol.message}): no north from it")
    r, J = both(sol.x)
    n = r.size
    info = J.T @ J
    try:
        cov1 = np.linalg.inv(info)
    except np.linalg.LinAlgError:
        raise SceneError("record", f"{n} samples", "the swing equation's parameters are not all determined by "
                         "the records (singular information matrix): observe longer or give the rotor-off swing") from None
    rms = float(math.sqrt(r @ r / n))
    if noise_sigma_rad is not None:
        sigma, src = float(noise_sigma_rad), "inverse Fisher information of the joint fit (sensor σ given)"
    else:
        sigma = float(math.sqrt(r @ r / max(n - len(names), 1)))
        src = f"inverse Fisher information of the joint fit, σ from the residuals ({n - len(names)} dof)"
    return ExactFit(tuple(names), sol.x, sigma ** 2 * cov1, sigma, src, rms, n, int(sol.nfev))


def crlb(eq, par, records_t, kinds, initial, noise_sigma_rad) -> float:
    """Cramér–Rao bound on σ(N) (rad) for the true parameters ``par`` sampled at ``records_t``.

    ``initial``: per record (reading0, rate0) at its first time. The Fisher information of the joint
    problem is JᵀJ/σ² (J from the sensitivity equations at ``par``); the bound is √[I⁻¹]_NN.
    """
    names = eq.names(tuple(kinds))
    full = dict(par)
    for i, (kind, (w0, v0)) in enumerate(zip(kinds, initial)):
        full[f"{kind}{i}_w0"], full[f"{kind}{i}_v0"] = w0, v0
    x = np.array([full[n] for n in names], dtype=float)
    recs = [Record(np.asarray(t, dtype=float), np.zeros(len(t)), k) for t, k in zip(records_t, kinds)]
    _, J = _evaluate(eq, recs, names, x)
    cov = np.linalg.inv(J.T @ J)
    return float(noise_sigma_rad * math.sqrt(cov[0, 0]))
