"""Puiseux's heavy body on a smooth horizontal plane (Puiseux 1852, J. math. pures appl. 17, 1-30).

A heavy rigid body rests on a perfectly polished (frictionless) horizontal plane; one principal
axis Gz of its centre of mass G is normal to the surface at the contact point A, so the body is
in equilibrium when Gz is vertical. It is spun at r about Gz and slightly tilted. Puiseux finds
when Gz stays near the vertical (sec. I for an ellipsoid with G at its centre, sec. II for any
body, through the principal curvature radii ρ, ρ' of the surface at A). Sec. III drops the
principal axis: a body of any form, GA oblique to its principal axes, slightly displaced with
small velocities — two planes through GA swing with their own durations and the body turns
slowly about the vertical without bound. Sec. I also follows the contact point on the body
("stations et rétrogradations"): a channel of every shape here.

Earth rotation is ignored, as in the paper (``MECHANICS`` and so ``SUPPORTED_EFFECTS`` are
empty): the simulated model is the exact nonlinear rigid body on the frictionless plane, with no
small-angle or other approximation, so there is nothing to switch on or off.

Notation (the paper's)
----------------------
Body axes Gx, Gy, Gz (principal, moments A, B, C); mass M; gravity g. The upward vertical in
body axes is n = (a'', b'', c''), with a'' = θ sin ψ, b'' = θ cos ψ for small tilts θ; r the
body-axis spin. Ellipsoid semi-axes α, β, γ along x, y, z (γ along the axis that starts
vertical).

One module per job:

* :mod:`.theory` — the small-tilt analytic results: eq. (14)/(15), the three stability
  inequalities, the critical spins (sec. I and II);
* :mod:`.general` — sec. III: Puiseux's direction cosines (eq. 17), his ω equation, the planes
  Π', Π'', their perpendicularity, the slow turn and the first-order motion;
* :mod:`.surface` — the body's surface seen from G: the ellipsoid of sec. I and the osculating
  ellipsoid that stands for any body given by its curvature radii (sec. II, and in any
  orientation for sec. III);
* :mod:`.dynamics` — the exact rigid body on a frictionless plane (what ``simulate`` integrates);
* :mod:`.fixed_step`, :mod:`.kernels` — the compiled fixed-step runs (``integrator: axis_rk8``, the exact
  reduction of a body of revolution by its conserved spin; ``rk8``, the exact equations), picked by
  ``integrator: auto``; ``dop853`` is the adaptive reference;
* :mod:`.instrument` — :class:`PuiseuxBody`, the instrument (parameters, predictions, simulate).
"""

from gyro_instrument.instruments.puiseux.dynamics import contact_dynamics, contact_dynamics_general, reduced_rates
from gyro_instrument.instruments.puiseux.general import (GeneralModes, general_modes, inertia_conjugacy,
                                                         linear_rotation, normal_frame, puiseux_omega_quadratic)
from gyro_instrument.instruments.puiseux.instrument import PuiseuxBody
from gyro_instrument.instruments.puiseux.surface import EllipsoidSurface, GeneralEllipsoidSurface
from gyro_instrument.instruments.puiseux.theory import (StabilityVerdict, classify_coefficients, classify_stability,
                                                        classify_stability_curvature, critical_spin_general_rad_s,
                                                        critical_spin_rad_s, curvature_coefficients,
                                                        ellipsoid_coefficients, homogeneous_inertia,
                                                        stable_spin_intervals_rad_s)

__all__ = ["EllipsoidSurface", "GeneralEllipsoidSurface", "GeneralModes", "PuiseuxBody", "StabilityVerdict",
           "classify_coefficients", "classify_stability", "classify_stability_curvature", "contact_dynamics",
           "contact_dynamics_general", "critical_spin_general_rad_s", "critical_spin_rad_s", "curvature_coefficients",
           "ellipsoid_coefficients", "general_modes", "homogeneous_inertia", "inertia_conjugacy", "linear_rotation",
           "normal_frame", "puiseux_omega_quadratic", "reduced_rates", "stable_spin_intervals_rad_s"]
