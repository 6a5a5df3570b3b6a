"""North from the swing of a horizontal gyroscope: the oscillation centre is the meridian.

Quet 1853, sec. 4 §1, item 1: a body of revolution spinning about its axis, the axis free to turn
in a *horizontal* directing plane, is in relative equilibrium only along the meridian (stable when
the spin is in the Earth's sense), and item 6: away from it the axis swings about the meridian like
a pendulum (eq. 8, small swings of duration T = π/√(μ n ρ0 sin ω), eq. 9, sin ω = cos γ). A
surveyor's gyrotheodolite (Wild GAK1, Fennel KT1, DMT Gyromat) is this gyroscope hung on a torsion
tape; the centre of its swing, read on the instrument's scale, gives north.

Sign convention (the scale of issue 24, item 1)
-----------------------------------------------
* Azimuth: clockwise from true north seen from above (east = +90°), in [0, 2π).
* ``mount_azimuth``: the azimuth of the instrument's scale zero.
* The swing angle ``u`` read on the scale (rad) is the azimuth of the rotor axis's north-seeking
  end (the end that rests on the meridian's north when the spin is in the Earth's sense) *less*
  the mount azimuth: u = azimuth(axis) − mount_azimuth, wrapped to (−π, π]. So u grows clockwise,
  like the azimuth (Quet's own u of eq. 4 is measured from ``ox`` toward ``oy``, to the *left* of
  ``ox``: counter-clockwise; u_here = −u_Quet for a scale whose zero is on ``ox``).
* True north (azimuth 0) therefore reads u_N = −mount_azimuth on the scale, and the estimate
  sought is mount_azimuth = (−u_N) mod 2π (:func:`mount_azimuth_rad`).
* Without a torsion tape the swing centre c *is* u_N. With a tape (torsion constant D_B, tape zero
  Z on the scale) the centre is pulled toward Z: c = (D_K u_N + D_B Z)/(D_K + D_B), hence
  u_N = c + (D_B/D_K)(c − Z) near north; exactly, tan(c − u_N) = x (Z − c) with x the period ratio
  (:func:`tape_north`, :func:`tape_corrected`, where it is derived).

The package: the methods (:mod:`.base`, :mod:`.means`, :mod:`.timing`, :mod:`.fit`, all run on one
record by :func:`.methods.north_methods`); the estimate's ``north`` block (:mod:`.estimate`: the exact
fit :mod:`.exact` started by :mod:`.joint`); north as the swing goes (:mod:`.live`); the planner's bound
(:mod:`.bounds`); field books (:mod:`.field_book`, :mod:`.field_book_read`, :mod:`.field_book_report`);
the heading published (:mod:`.heading`); the rate gyro's north (:mod:`.rate_gyro`, :mod:`.rate_gyro_plan`,
:mod:`.rate_gyro_study`). Only public names are re-exported here.

The methods (issue 24, item 3), each returning a :class:`NorthEstimate`
------------------------------------------------------------------------
=========================  ====================================  ===========================================
method                     needs                                 bias (first order)
=========================  ====================================  ===========================================
:func:`schuler_mean`       ≥ 3 reversal points (≥ 4 for a σ      none for a linear decay of the amplitude;
                           from the scatter)                     exponential decay q per swing: second order,
                                                                 d1 (1−q)² (1 − (−q)^(ν−2)) / (4 (1+q)(ν−2))
                                                                 (:func:`schuler_bias`); a linear drift of the
                                                                 centre gives the centre at the weighted mean
                                                                 time (symmetric weights)
:func:`lavrov`             ≥ 3 consecutive reversal points       none for an exponential (geometric) decay:
                           (≥ 4 for a σ from the scatter)        exact; a linear decay: second order
:func:`transit_method`     ≥ 3 transits of a mark inside the     none at the mark = centre (the zeros of a
                           swing (one period) and the            damped sine are equally spaced); the sine
                           amplitude (from reversal points)      law x0 = A sin(π Δt / (2T)) is exact undamped
:func:`fit_record`         ≥ 2 reversal points to start (about   none for the model c + A e^(−δt) cos(ωt + φ)
                           one swing); σ at the Cramér–Rao       (+ drift); var(c) ≈ σ²/N for a long record
                           bound                                 (:func:`crlb_centre`)
=========================  ====================================  ===========================================

Tape torque biases every centre alike (the swing centre is not north); :func:`tape_corrected`
removes it with the ratio from the rotor-on and rotor-off periods (:func:`tape_ratio`) by the exact
relation N = c − atan(x (Z − c)) (:func:`tape_north`). The estimate's headline is none of these but
:mod:`.exact`: the swing equation itself fitted to both records (no linearisation, no bias for any
mount azimuth); :mod:`.joint` starts it and states each reduction's bias in the set-up at hand. Sources:
Quet 1853 sec. 4 §1 (items 1 and 6, eqs. 2, 8–10); the Schuler mean is Freiberger
Forschungshefte A 303 eq. 31b; the transit form N = N' + c·a·Δt with c ≈ π/(2T) is derived in
:func:`.timing.transit_offset`; the GAK1
procedures are described in K. P. Logan, *Determining an azimuth with a gyrotheodolite*, U.S. Army
ETL-0440 (1986). The derivations used here are written out in each function's docstring.
"""

from gyro_instrument.estimators.north.base import (  # noqa: F401
    TWO_PI, NorthEstimate, ReversalPoints, damped_swing, half_period, mount_azimuth_rad, reversal_points, wrap_pi)
from gyro_instrument.estimators.north.fit import (  # noqa: F401
    crlb_centre, crlb_centre_long, fit_record, tape_corrected, tape_north, tape_ratio, undamped_omega)
from gyro_instrument.estimators.north.means import lavrov, lavrov_triples, schuler_bias, schuler_mean, schuler_weights  # noqa: F401
from gyro_instrument.estimators.north.methods import north_methods  # noqa: F401
from gyro_instrument.estimators.north.timing import transit_method, transit_offset, transit_times  # noqa: F401
