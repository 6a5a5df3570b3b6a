"""What the ship's gyrocompass says about itself while it runs (issue 39 item 5): settled or settling,
its settle-point error, and the standard error of its reading (no rclpy; the node,
:mod:`gyro_instrument.ros.nodes.compass`, publishes them).

Settled (ISO 22090-1 §3.10, nippon.zaidan.info/seikabutsu/2000/00393/contents/003.htm): "stable
situation when any three readings taken at intervals of 30 min are within a band of 0.7°, with the
compass level and stationary"; the settling time runs from switch-on "to the third recording". A
reading here is the compass's *error*, its heading less the ship's true heading (the simulated
reference, as a test table knows its own heading): on a stationary compass the same band, on a
sailing one the ship's turns left out. The criterion is evaluated at every sample t on the errors at
t, t − 30 min and t − 60 min (linear interpolation between samples); the first t where their spread
is ≤ 0.7° is the settling time, and the state stays ``settled`` for the rest of the run.

Settle-point error (§3.11–3.12): the mean of ten readings taken at 20 min intervals after settling,
less the true heading: here the mean of the errors at settling + 20, + 40, … min, the readings taken
so far (up to the last ten: from the tenth on it is the standard's figure, then a running one).

Standard error of the reading, σ (the heading Imu's yaw covariance σ²)::

    σ(t)² = σ_env(t)² + σ_floor²
    σ_env(t) = |e0| exp(−λ t) / √(1 − ζ²)          (ζ < 1; |e0| exp(−λ t) otherwise)
    σ_floor = 0.75° sec φ / √3

- ``σ_env``: the envelope of the damped spiral from the switch-on error e0 (the error of the first
  reading: the initial heading error a settling test sets, ISO 22090-1 §3.10's note), decaying at the
  rate λ and damping ratio ζ of the compass's slowest mode (:func:`slowest_decay`: the eigenvalues of
  its equations of motion linearised about the settled state on a pier at the start latitude). It is
  the envelope of x(t) = e0 e^(−ζω0 t)(cos ωd t + ζ/√(1−ζ²) sin ωd t). Large while the compass
  settles, negligible hours later; a compass without damping (λ = 0) keeps it.
- ``σ_floor``: what a settled compass may still be off by and does not know: the settle-point error a
  type-approved compass is allowed, ±0.75° sec φ (ISO 22090-1 = ISO 8728's class A, IMO A.424(XI),
  A.821(19) §4.1.2: nippon.zaidan.info/seikabutsu/2000/00402/contents/006.htm,
  puc.overheid.nl/nsi/doc/PUC_2513_14/1/), taken as an error spread uniformly over that band
  (σ = half-width/√3); φ the compass's latitude input.

Measured on the shipped scene's compasses (6 h from 20° off north at 20 kn, and from 60° and 90°
off): the true error stays within 1.04 σ (Sperry, damped in tilt) and 1.32 σ (Anschütz, damped in
azimuth: its oil and tilt transients are not in the one-mode envelope).

No truth enters σ (only the first reading's error, the test's set-up); the state and the settle-point
error, like a type test's, read the reference heading.
"""

import math
from dataclasses import replace

import numpy as np

from gyro_instrument.core.motion import Piece
from gyro_instrument.instruments.marine_gyrocompass.compass import TRACK
from gyro_instrument.instruments.marine_gyrocompass.dynamics import right_hand_side

#: ISO 22090-1 §3.10: three readings 30 min apart within a band of 0.7°.
SETTLED_BAND_RAD = math.radians(0.7)
SETTLED_INTERVAL_S = 1800.0
SETTLED_READINGS = 3
#: ISO 22090-1 §3.11: the settle point is the mean of ten readings 20 min apart after settling.
SETTLE_POINT_INTERVAL_S = 1200.0
SETTLE_POINT_READINGS = 10
#: ISO 22090-1 / IMO A.424(XI): the settle-point error limit, ±0.75° sec φ.
SETTLE_POINT_LIMIT_RAD = math.radians(0.75)
SETTLING, SETTLED = "settling", "settled"


def slowest_decay(inst) -> tuple:
    """(λ, ζ): the decay rate (1/s, ≥ 0) and damping ratio of the slowest mode of compass ``inst``.

    The right-hand side of :func:`.dynamics.right_hand_side` on a pier at the ship's start latitude
    (no sway), its settled state found with ``scipy.optimize.fsolve`` and its Jacobian in (α, θ, β,
    β', and the oil's q with damping in azimuth) by central differences (step 1e-6); λ = −Re s and ζ = −Re s / |s| of the eigenvalue s
    with the largest real part (the mode that decays last). For damping in tilt this is the
    closed form ζ ω0 = (P_d/P_c)(P_c/H)/2 (:func:`.theory.damping_ratio_tilt`; tested).
    """
    from scipy.optimize import fsolve
    co = replace(inst.coefficients(), fwd_m_s2=0.0, stbd_m_s2=0.0)
    lat = inst.pieces()[0].lat0
    f = right_hand_side(co, Piece(0.0, math.inf, 0.0, 0.0, 0.0, 0.0, lat))

    n = 5 if co.oil_damping else 4         # without the oil its state q is idle (an eigenvalue 0)

    def g(x) -> np.ndarray:
        y = tuple(x) + (() if n == 5 else (0.0,))
        return np.array(f(0.0, *y, lat, 0.0)[:n])
    x0 = fsolve(g, np.zeros(n), xtol=1e-13)
    h = 1e-6
    jac = np.empty((n, n))
    for j in range(n):
        d = np.zeros(n)
        d[j] = h
        jac[:, j] = (g(x0 + d) - g(x0 - d)) / (2 * h)
    ev = np.linalg.eigvals(jac)
    s = ev[np.argmax(ev.real)]
    rate = max(-float(s.real), 0.0)
    return rate, float(rate / abs(s)) if abs(s) > 0 else 1.0


class Readout:
    """The live state of one compass, fed its readings block by block (:meth:`push`).

    Parameters
    ----------
    inst : MarineGyrocompass
        The compass (its ship, ``motion``, gives the reference heading and latitude; None: a pier).
    """

    def __init__(self, inst) -> None:
        self.inst = inst
        self.decay_per_s, self.zeta = slowest_decay(inst)
        self.e0_rad = None
        self.t_hist = np.zeros(0)
        self.e_hist = np.zeros(0)            # unwrapped errors of the last hour (and a little)
        self.settled_s = None                # the settling time (s), None while settling
        self.readings = []                   # (t, error) taken every 20 min after settling

    def reference(self, t_s) -> tuple:
        """(true heading, latitude input) at times ``t_s`` (rad): the ship's course and the compass's
        latitude setting (the track's latitude with ``track``)."""
        mo, p = self.inst.motion, self.inst.p
        if mo is None:
            course, lat = np.zeros_like(t_s), np.full_like(t_s, self.inst.site.latitude_rad)
        else:
            tr = mo.track(t_s)
            course, lat = tr["course"], tr["latitude"]
        if p.latitude_setting_deg != TRACK:
            lat = np.full_like(t_s, math.radians(p.latitude_setting_deg))
        return course, lat

    def sigma_rad(self, t_s, latitude_rad) -> np.ndarray:
        """σ of the reading at times ``t_s`` (module docstring), rad."""
        floor = SETTLE_POINT_LIMIT_RAD / math.sqrt(3.0) / np.abs(np.cos(latitude_rad))
        e0 = abs(self.e0_rad or 0.0)
        lead = 1.0 / math.sqrt(1.0 - self.zeta ** 2) if self.zeta < 1.0 else 1.0
        env = e0 * lead * np.exp(-self.decay_per_s * np.asarray(t_s))
        return np.sqrt(env ** 2 + floor ** 2)

    def push(self, t_s, reading_rad) -> dict:
        """The readings ``reading_rad`` (rad) at times ``t_s`` (s, increasing, after the last pushed).

        Returns {``error``: wrapped to [−π, π), ``sigma``: rad, ``settled``: bool, ``latitude``: the
        latitude input (rad)}, one value per sample."""
        t = np.asarray(t_s, dtype=float)
        course, lat = self.reference(t)
        err = np.mod(np.asarray(reading_rad, dtype=float) - course + math.pi, 2 * math.pi) - math.pi
        if self.e0_rad is None and err.size:
            self.e0_rad = float(err[0])
        ref = self.e_hist[-1:] if self.e_hist.size else err[:1]
        unwrapped = np.unwrap(np.concatenate([ref, err]))[1:]
        t_all, e_all = np.concatenate([self.t_hist, t]), np.concatenate([self.e_hist, unwrapped])
        if self.settled_s is None and t.size:
            self._settle(t, unwrapped, t_all, e_all)
        if self.settled_s is not None:
            self._take_readings(t_all, e_all, t[-1] if t.size else -math.inf)
        keep = t_all >= (t_all[-1] if t_all.size else 0.0) - SETTLED_INTERVAL_S * (SETTLED_READINGS - 1) - 60.0
        self.t_hist, self.e_hist = t_all[keep], e_all[keep]
        settled = np.zeros(t.size, bool) if self.settled_s is None else t >= self.settled_s
        return {"error": err, "sigma": self.sigma_rad(t, lat), "settled": settled, "latitude": lat}

    def _settle(self, t, e, t_all, e_all) -> None:
        """The first sample of this block where the ISO 22090-1 §3.10 criterion holds, if any."""
        span = SETTLED_INTERVAL_S * (SETTLED_READINGS - 1)
        ok = t >= span + t_all[0] if t_all.size else np.zeros(t.size, bool)
        if not ok.any():
            return
        rows = [e] + [np.interp(t - k * SETTLED_INTERVAL_S, t_all, e_all) for k in range(1, SETTLED_READINGS)]
        band = np.max(rows, axis=0) - np.min(rows, axis=0)
        hit = np.flatnonzero(ok & (band <= SETTLED_BAND_RAD))
        if hit.size:
            self.settled_s = float(t[hit[0]])

    def _take_readings(self, t_all, e_all, t_last) -> None:
        """The settle-point readings due up to ``t_last`` (every 20 min after settling)."""
        while True:
            due = self.settled_s + SETTLE_POINT_INTERVAL_S * (len(self.readings) + 1)
            if due > t_last:
                return
            self.readings.append((due, float(np.interp(due, t_all, e_all))))

    def status(self, t_s) -> dict:
        """The state at time ``t_s`` (s; a sample already pushed): ``state``, ``settling_time_s``
        (None while settling), ``settle_point_error_rad`` (None until the first reading after
        settling; the mean of the last ten so far, wrapped) and ``settle_point_readings``."""
        settled = self.settled_s is not None and t_s >= self.settled_s
        taken = [e for t, e in self.readings if t <= t_s][-SETTLE_POINT_READINGS:]
        sp = None
        if settled and taken:
            sp = float(np.mod(np.mean(taken) + math.pi, 2 * math.pi) - math.pi)
        return {"state": SETTLED if settled else SETTLING, "settling_time_s": self.settled_s if settled else None,
                "settle_point_error_rad": sp, "settle_point_readings": len(taken) if settled else 0}
