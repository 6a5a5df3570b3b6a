"""The shipped measurement kinds, each declared in one place (:mod:`gyro_instrument.instruments.measurement`).

* :class:`SwingKind` (``gyro``): a gyroscope's swing about a directing line, y = K/(gain ρ) = n s(γ)
  (Quet 1853 sec. 4 §1 eq. 9): the fit :func:`.swing.swing_estimate`, the probe and bound of
  :mod:`.bounds` (the fit's exact Fisher information on the sample grid).
* :class:`PlaneKind` (``pendulum``): a swing plane's precession, k = n sin γ (sec. 2 §III): the
  Foucault fit :func:`.foucault.estimate_foucault` and its bound
  (:func:`.foucault.foucault_crlb_small_swing_rad_s`).
* :class:`AzimuthKind` (``azimuth``): a horizontal gyroscope's swing centre is the meridian: the
  ``north`` block (:func:`.north.estimate.north_entry`), the joint fit's Cramér–Rao bound
  (:mod:`.north.bounds`), the Schuler mean as the swing goes (:mod:`.north.live`), published
  live as the instrument's heading.

Each is an entry point of ``gyro_instrument.measurements`` (setup.py); a package adds its own kind
the same way (docs/extending.md). The engines are imported when first called: registering the
kinds (every command line does, to report a refused plug-in) costs no estimator import.
"""

import math

from gyro_instrument.instruments.measurement import LiveTracker, MeasurementKind
from gyro_instrument.instruments.observation import ELLIPSE_CORRECTION, PLANE_RATE, SWING_RATE
from gyro_instrument.instruments.observation_azimuth import AZIMUTH, ROTOR_OFF


class SwingKind(MeasurementKind):
    """A swing about a directing line: y = n s(γ) from the swing duration and the spin (rad/s)."""

    name = SWING_RATE
    summary = "n sin(omega), rad/s"
    RATE = True
    UNIT = "rad/s"
    CLASSIC = "gyro"

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        from gyro_instrument.estimators.swing import swing_estimate
        return swing_estimate(obs, rec, corrections, checks, sensor)

    def probe(self, scene, obs) -> tuple:
        from gyro_instrument.estimators.bounds import swing_model
        return swing_model(scene, obs)

    def bound(self, model, T, sensor) -> tuple:
        from gyro_instrument.estimators.bounds import swing_sigma
        return swing_sigma(model, T, sensor)

    def tracker(self, obs, scene, companions) -> "NorthLive | None":
        return None

    def plan_entry(self, model) -> dict:
        """The plan's entry of the instrument (``plan --json``, ``instruments``)."""
        return {"kind": model.kind, "configuration": model.label, "measures": self.summary,
                "true_value_rad_s": model.value, "period_s": 2 * math.pi / model.omega,
                "min_record_s": model.min_record_s, "swing_duration_s": math.pi / model.omega,
                "amplitude_rad": math.hypot(model.coef[0], model.coef[1])}


class PlaneKind(MeasurementKind):
    """A swing plane's precession: the Foucault rate k = n sin γ (rad/s)."""

    name = PLANE_RATE
    summary = "Foucault rate k = n sin(latitude), rad/s"
    RATE = True
    UNIT = "rad/s"
    CLASSIC = "pendulum"

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        return plane_estimate(obs, rec, corrections, checks, sensor)

    def probe(self, scene, obs) -> tuple:
        from gyro_instrument.estimators.bounds import plane_model
        return plane_model(scene, obs)

    def bound(self, model, T, sensor) -> tuple:
        from gyro_instrument.estimators.bounds import plane_sigma
        return plane_sigma(model, T, sensor)

    def tracker(self, obs, scene, companions) -> "NorthLive | None":
        return None

    def plan_entry(self, model) -> dict:
        return {"kind": model.kind, "configuration": model.label, "measures": self.summary,
                "true_value_rad_s": model.value, "period_s": 2 * math.pi / model.omega,
                "min_record_s": model.min_record_s, "amplitude_rad": model.amplitude}


class AzimuthKind(MeasurementKind):
    """A horizontal gyroscope's swing centre on the meridian: the mount azimuth (the ``north`` block)."""

    name = AZIMUTH
    summary = "mount azimuth: the swing centre on the scale is true north"
    RATE = False
    BLOCK = "north"
    TARGET = "azimuth"
    UNIT = "rad"
    LIVE = "heading"

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        from gyro_instrument.estimators.north.estimate import north_entry
        return north_entry(obs, rec, corrections, checks, sensor)

    def probe(self, scene, obs) -> tuple:
        from gyro_instrument.estimators.north.bounds import azimuth_model
        return azimuth_model(scene, obs)

    def bound(self, model, T, sensor) -> tuple:
        from gyro_instrument.estimators.north.bounds import fit_bound
        return fit_bound(model, T, sensor), "Cramer-Rao bound of the whole joint fit"

    def warm(self) -> None:
        from gyro_instrument.estimators.north.exact import warm
        warm()

    def tracker(self, obs, scene, companions) -> "NorthLive | None":
        swing = obs.instrument.predictions().get("swing_duration_small_s", math.inf)
        if not (math.isfinite(swing) and swing > 0):
            return None
        off = companions.get(ROTOR_OFF)
        off_s = obs.instrument.tape_predictions()["rotor_off_swing_duration_s"] if off else None
        return NorthLive(obs.name, swing, scene.sensor.get("noise_rad") or None, off, off_s)

    def combine(self, blocks) -> dict | None:
        from gyro_instrument.estimators.north.estimate import best_block
        return best_block(blocks)

    def plan(self, scene_arg, overrides, models, skipped, sensor, name, value, si, floor=True) -> dict:
        """The plan of an azimuth target (:func:`.planner.plan_azimuth`)."""
        from gyro_instrument.estimators.planner import plan_azimuth
        return plan_azimuth(scene_arg, overrides, models, skipped, sensor, name, value, si, floor)

    def plan_entry(self, model) -> dict:
        from gyro_instrument.estimators.north.bounds import azimuth_entry
        return azimuth_entry(model)


class NorthLive(LiveTracker):
    """The live north of one horizontal gyroscope (and its rotor-off swing), from the first swing on
    (issue 37): per record a :class:`.north.live.SwingFit` of the record so far (the predicted
    frequency as a prior) every half swing of the gyroscope, and a :class:`.north.live.NorthTracker`
    of its reversal points every quarter swing of the record; the live north is whichever of
    :func:`.north.live.fit_north` and :func:`.north.live.live_north` (both tape-corrected where
    there is a rotor-off swing) has the smaller σ."""

    def __init__(self, name, swing_s, sigma, off_name=None, off_swing_s=None):
        from gyro_instrument.estimators.north.live import NorthTracker, SwingFit
        self.name = name
        self.trackers = {name: NorthTracker(swing_s, sigma)}
        self.fits = {name: SwingFit(swing_s, sigma)}
        if off_name is not None:
            self.trackers[off_name] = NorthTracker(off_swing_s, sigma)
            self.fits[off_name] = SwingFit(off_swing_s, sigma)
        self.reads = tuple(self.trackers)
        self.off = off_name
        # looks between two reversal-point searches / two fits of each record (a look every every_s_of)
        self._period = {n: (max(round(0.25 * tr.swing_s / self.every_s_of(n)), 1),
                            max(round(0.5 * swing_s / self.every_s_of(n)), 1)) for n, tr in self.trackers.items()}
        self._looks = {n: 0 for n in self.trackers}

    def every_s_of(self, name) -> float:
        """A quarter swing of ``name``'s record, at most half a swing of the gyroscope (a rotor-off
        swing is fitted as often as its rotor-on gyroscope's)."""
        return min(0.25 * self.trackers[name].swing_s, 0.5 * self.trackers[self.name].swing_s)

    def window_s_of(self, name) -> float:
        """The fit's span (:data:`.north.live.FIT_SWINGS` swings); the reversal points are searched
        in its last :meth:`.north.live.NorthTracker.window_s`."""
        return max(self.fits[name].window_s(), self.trackers[name].window_s())

    def update(self, name, rec) -> tuple | None:
        import numpy as np
        t, u = np.asarray(rec["t"], dtype=float), -np.asarray(rec["angle"], dtype=float)
        if t.size == 0:
            return None
        every_tr, every_fit = self._period[name]
        look = self._looks[name] = self._looks[name] + 1       # the first look is every_s_of in
        changed = False
        if look % every_fit == 0:          # the gyroscope's half swings: its first fit after one swing
            fit = self.fits[name].update(t, u, min_span_s=self.fits[self.name].swing_s)
            changed = fit is not None
        if look % every_tr == 0:
            k = max(int(np.searchsorted(t, t[-1] - self.trackers[name].window_s())) - 1, 0)
            changed = bool(self.trackers[name].update(t[k:], u[k:])) or changed
        if not changed:
            return None
        est = self.live()
        return None if est is None else (est.mount_azimuth_rad, est.sigma_rad)

    def live(self) -> "object | None":
        """The better (smaller σ) of the fit's and the reversal points' live north (a
        :class:`.north.NorthEstimate`), or None."""
        from gyro_instrument.estimators.north.live import fit_north, live_north
        off_fit = self.fits[self.off].summary if self.off else None
        cands = [fit_north(self.fits[self.name].summary, off_fit, tape=self.off is not None),
                 live_north(self.trackers[self.name], self.trackers.get(self.off))]
        cands = [c for c in cands if c is not None and c.sigma_rad is not None and math.isfinite(c.sigma_rad)]
        return min(cands, key=lambda c: c.sigma_rad, default=None)

    def final(self, entry) -> tuple:
        block = (entry or {}).get("north") or {}
        deg, sig = block.get("mount_azimuth_deg"), block.get("sigma_arcsec")
        return (None if deg is None else math.radians(deg),
                None if sig is None or deg is None else math.radians(sig / 3600.0))

    def restarted(self) -> "NorthLive":
        """A new tracker with the same settings (a new run)."""
        on = self.trackers[self.name]
        off = self.trackers.get(self.off)
        return NorthLive(self.name, on.swing_s, on.noise_sigma_rad, self.off, None if off is None else off.swing_s)


def plane_estimate(obs, rec, corrections, checks, sensor) -> tuple:
    """The Foucault rate of one pendulum record (estimators/foucault.py) and its checks."""
    from gyro_instrument.estimators.adequacy import check_entry, check_period, halves_entry, plane_fit_entry
    from gyro_instrument.estimators.entries import PlaneEntry, PlaneNull, RestPoint
    from gyro_instrument.estimators.foucault import estimate_foucault
    from gyro_instrument.estimators.latitude import RateMeasurement
    from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, NoSignal
    name, inst = obs.name, obs.instrument
    east, north = obs.layout.measured
    try:
        f = estimate_foucault(rec["t"], rec[east], rec[north], correct_ellipse=ELLIPSE_CORRECTION in corrections,
                              noise_rad=sensor.effective_sigma_rad())
    except EstimationError as exc:
        if isinstance(exc, NoSignal):
            checks.append(check_entry(name, "signal", "no_signal", str(exc), expected=DETECTION_SNR))
        return PlaneNull(type=inst.type_name, foucault_rate_rad_s=None, reason=str(exc)), None
    est = PlaneEntry(type=inst.type_name, foucault_rate_rad_s=f.k_rad_s, foucault_rate_sigma_rad_s=f.k_sigma_rad_s,
                     crlb_foucault_rate_rad_s=f.crlb_k_rad_s, measured_plane_rate_rad_s=f.measured_rate_rad_s,
                     measured_plane_rate_sigma_rad_s=f.measured_rate_sigma_rad_s, sigma_basis=f.sigma_basis,
                     sigma_basis_detail=f.sigma_basis_text, ellipse_correction_rad_s=f.airy_correction_rad_s,
                     amplitude_rad=f.amplitude_rad, minor_axis_rad=f.minor_axis_rad, period_s=f.period_s,
                     period_sigma_s=f.period_sigma_s, rest_point=RestPoint(**f.rest_point), windows=f.windows,
                     notes=f.notes,
                     ellipse_scale=ellipse_scale(f.measured_rate_rad_s, f.airy_correction_rad_s, f.k_sigma_rad_s))
    checks.append(check_entry(name, "signal", "passed", f"swing detected (A^2 N / (4 sigma^2) >= {DETECTION_SNR:g}; "
                                                       "estimators/foucault.py)", expected=DETECTION_SNR))
    entry = check_period(name, inst, f.period_s)
    if entry:
        checks.append(entry)
    checks.append(plane_fit_entry(name, f.plane_chi2_per_dof, f.plane_dof, f.noise_rad))
    checks.append(halves_entry(name, f.plane_line))
    # a noise-free record's bound is 0; the combination weights it as exact (1/σ² finite)
    return est, RateMeasurement(name, PLANE_RATE, f.k_rad_s, f.k_sigma_rad_s, crlb_sigma=max(f.crlb_k_rad_s, 1e-150))


def ellipse_scale(measured_rad_s, correction_rad_s, sigma_rad_s) -> "EllipseScale":
    """How the ellipse (Airy) correction hangs on the position scale (an :class:`.entries.EllipseScale`): it is (3/8) a b / l² times the
    swing frequency (Airy 1851, Mem. R. Astron. Soc. 20; Quet 1853 sec. 2 §III–IV), a and b the axes read from the track, so
    a scale s times the assumed one multiplies it by s² while the measured turn is unchanged. ``matters``:
    halving the scale would move k by more than its σ (3/4 of the correction > σ) — then positions given
    in pixels (or a wrong length) decide the answer, and ``k_at_half_scale_rad_s`` /
    ``k_at_double_scale_rad_s`` say by how much."""
    from gyro_instrument.estimators.entries import EllipseScale
    m, c = float(measured_rad_s), float(correction_rad_s)
    return EllipseScale(exponent=2, share_of_measured_rate=c / m if m else None, k_without_correction_rad_s=m,
                        k_at_half_scale_rad_s=m - c / 4.0, k_at_double_scale_rad_s=m - 4.0 * c,
                        matters=bool(abs(0.75 * c) > float(sigma_rad_s or 0.0)))
