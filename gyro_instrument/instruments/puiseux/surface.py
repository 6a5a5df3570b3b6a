"""The body's surface seen from its centre of mass (Puiseux 1852, sec. I and II).

The height of G above the plane is the support function h(n) of the surface, n the upward
vertical in body axes (see :mod:`.dynamics`). Sec. I: an ellipsoid with G at its centre.

General body (``shape: curvature``)
-----------------------------------
Only ρ, ρ', γ (and δ) enter the small-tilt theory (sec. II). For the simulation the surface is
modelled by the ellipsoid that osculates the body at A: semi-axis γ_e = √(ρ ρ') along Gz, and
in the tangent plane semi-axes √(ρ γ_e), √(ρ' γ_e) along the principal directions (at angle δ
from Gx), so that its curvature radii at the vertex are exactly ρ, ρ' (the curvature radius of
an ellipsoid at a vertex is (tangent semi-axis)²/(normal semi-axis)); its centre is offset
along Gz, c_z = γ_e − γ, so that G stands at height γ above A. For ρ = ρ' this is a sphere of
radius ρ with G at ρ − γ below its centre (the weighted ball). Any other smooth surface with
the same ρ, ρ' gives the same small-tilt motion; large tilts depend on the choice.
"""

import math

import numpy as np


class EllipsoidSurface:
    """Support function h(n) = √(nᵀ S n) − c_z n_z of an ellipsoid centred at (0, 0, c_z).

    Parameters
    ----------
    semi_axes_m : sequence of 3 float
        Semi-axes along the principal directions in the tangent plane and along Gz, m.
    centre_z_m : float
        Body z of the ellipsoid centre relative to G, m (0 for Puiseux sec. I).
    delta_rad : float
        Angle from Gx to the first tangent semi-axis, rad.
    """

    def __init__(self, semi_axes_m, centre_z_m=0.0, delta_rad=0.0) -> None:
        a, b, c = (float(x) for x in semi_axes_m)
        cd, sd = math.cos(delta_rad), math.sin(delta_rad)
        self.sxx = a * a * cd * cd + b * b * sd * sd
        self.syy = a * a * sd * sd + b * b * cd * cd
        self.sxy = (a * a - b * b) * sd * cd
        self.szz = c * c
        self.cz = float(centre_z_m)
        self.semi_axes_m = (a, b, c)
        self.delta_rad = float(delta_rad)

    @classmethod
    def osculating(cls, rho, rho_prime, gamma, delta_rad=0.0) -> "EllipsoidSurface":
        """The ellipsoid with curvature radii ρ, ρ' at its lowest vertex and G at height γ.

        Normal semi-axis γ_e = √(ρ ρ'), tangent semi-axes √(ρ γ_e), √(ρ' γ_e), centre at
        c_z = γ_e − γ above G (see the module docstring).
        """
        ge = math.sqrt(rho * rho_prime)
        return cls((math.sqrt(rho * ge), math.sqrt(rho_prime * ge), ge), ge - gamma, delta_rad)

    def height(self, nx, ny, nz) -> np.ndarray | float:
        """h(n): height of G above the plane, m, for the upward vertical n in body axes."""
        return np.sqrt(self.sxx * nx * nx + 2.0 * self.sxy * nx * ny + self.syy * ny * ny
                       + self.szz * nz * nz) - self.cz * nz

    def contact_point(self, n) -> np.ndarray:
        """Contact point x_P = −∇h(n) in body axes, m."""
        n = np.asarray(n, dtype=float)
        S = np.array([[self.sxx, self.sxy, 0.0], [self.sxy, self.syy, 0.0], [0.0, 0.0, self.szz]])
        Sn = S @ n
        return -(Sn / math.sqrt(n @ Sn) - np.array([0.0, 0.0, self.cz]))


class GeneralEllipsoidSurface:
    """Support function h(n) = √(nᵀ S n) − c·n of an ellipsoid of any orientation and centre c
    (body axes, from G): the surface of Puiseux's general body (sec. III) in its principal axes.

    Parameters
    ----------
    S : array (3, 3)
        Symmetric positive definite: the ellipsoid is {x : (x − c)ᵀ S⁻¹ (x − c) = 1}, m².
    centre_m : array (3,)
        Centre c, m.
    """

    def __init__(self, S, centre_m) -> None:
        S = np.asarray(S, dtype=float)
        self.S = 0.5 * (S + S.T)
        self.c = np.asarray(centre_m, dtype=float)
        (self.sxx, self.sxy, self.sxz), (_, self.syy, self.syz), (_, _, self.szz) = self.S
        self.cx, self.cy, self.cz = self.c

    @classmethod
    def osculating(cls, rho, rho_prime, gamma, P) -> "GeneralEllipsoidSurface":
        """The ellipsoid with curvature radii ρ (along Aξ), ρ' (along Aη) at A and G at distance γ
        from A along the normal, in principal axes (``P`` from
        :func:`~gyro_instrument.instruments.puiseux.general.normal_frame`).

        In the frame Aξηζ it is :meth:`EllipsoidSurface.osculating` (normal semi-axis
        γ_e = √(ρρ'), tangent semi-axes √(ργ_e), √(ρ'γ_e), centre γ_e − γ above G along the
        normal); S = Pᵀ diag(ργ_e, ρ'γ_e, γ_e²) P and c = (γ_e − γ) ζ̂ in principal axes.
        """
        P = np.asarray(P, dtype=float)
        ge = math.sqrt(rho * rho_prime)
        S = P.T @ np.diag([rho * ge, rho_prime * ge, ge * ge]) @ P
        return cls(S, (ge - gamma) * P[2])

    def height(self, nx, ny, nz) -> np.ndarray | float:
        """h(n): height of G above the plane, m, for the upward vertical n in body axes."""
        sx = self.sxx * nx + self.sxy * ny + self.sxz * nz
        sy = self.sxy * nx + self.syy * ny + self.syz * nz
        sz = self.sxz * nx + self.syz * ny + self.szz * nz
        return np.sqrt(nx * sx + ny * sy + nz * sz) - (self.cx * nx + self.cy * ny + self.cz * nz)

    def contact_point(self, n) -> np.ndarray:
        """Contact point x_P = −∇h(n) in body axes, m (n of shape (3,) or (3, m))."""
        n = np.asarray(n, dtype=float)
        Sn = np.tensordot(self.S, n, axes=1)
        s = np.sqrt(np.sum(n * Sn, axis=0))
        c = self.c if n.ndim == 1 else self.c[:, None]
        return -(Sn / s - c)
