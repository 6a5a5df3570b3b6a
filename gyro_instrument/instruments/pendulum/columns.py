"""The spherical pendulum's published columns from bob states (Quet 1853 sec. 2): deflection, the
swing-plane azimuth from the Fradkin tensor, their unwrapping across blocks.

:func:`pendulum_columns` is the numpy path; :func:`compiled_pendulum_columns` computes the same doubles
with its arithmetic (:func:`angle_arguments`) and unwrapping (:func:`unwrap_in_place`) compiled by
:mod:`gyro_instrument.core.jit` (the arctangents stay on numpy, whose values numba's do not match to the
last bit). Split from :mod:`~gyro_instrument.instruments.pendulum.dynamics`, which re-exports them.
"""

import functools

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.angles import Unwrapper


def pendulum_columns(pos, vel, omega0_sq, unwrappers=None, chunk=65536) -> dict:
    """Derived columns from bob positions/velocities (arrays (3, m), ENU).

    ``unwrappers``: a pair of :class:`~gyro_instrument.core.angles.Unwrapper` (azimuth, swing
    azimuth) carried from block to block of a streamed run; fresh ones by default (one block).
    The angles are computed ``chunk`` samples at a time into arrays allocated once: the same doubles
    (per sample; the unwrappers continue across chunks bit for bit), with temporaries of ``chunk``
    samples instead of the block's (a sidereal day at 20 Hz: 1.7 million samples, whose fresh pages
    cost the system more than the arithmetic)."""
    unwrappers = unwrappers if unwrappers is not None else (Unwrapper(), Unwrapper())
    x, y, z = pos
    size = np.shape(x)[0]
    out = {"deflection": np.empty(size), "azimuth": np.empty(size), "swing_azimuth": np.empty(size)}
    for a in range(0, size, chunk):
        part = _angle_columns(pos[:, a:a + chunk], vel[:, a:a + chunk], omega0_sq, unwrappers)
        for key, value in zip(("deflection", "azimuth", "swing_azimuth"), part):
            out[key][a:a + chunk] = value
    return {**out, "x_east": x, "y_north": y, "z_up": z}


def _angle_columns(pos, vel, omega0_sq, unwrappers) -> tuple:
    """(deflection, azimuth, swing azimuth) of :func:`pendulum_columns` for one chunk of samples."""
    unwrap_az, unwrap_swing = unwrappers
    x, y, z = pos
    vx, vy = vel[0], vel[1]
    rh = np.hypot(x, y)
    deflection = np.arctan2(rh, -z, out=rh)
    azimuth = unwrap_az(np.arctan2(x, y))
    # Fradkin tensor in (north, east) axes: its major axis is the swing plane. T_nn = ω0² n n + v_n v_n,
    # T_ee = ω0² e e + v_e v_e, T_ne = ω0² n e + v_n v_e; swing = atan2(2 T_ne, T_nn − T_ee) / 2, the
    # operations in place (the same doubles, fewer arrays)
    n, e, vn, ve = y, x, vy, vx
    tnn = omega0_sq * n
    tnn *= n
    w = vn * vn
    tnn += w
    tee = omega0_sq * e
    tee *= e
    tee += np.multiply(ve, ve, out=w)
    tne = omega0_sq * n
    tne *= e
    tne += np.multiply(vn, ve, out=w)
    tne *= 2.0
    tnn -= tee
    swing = unwrap_swing(np.arctan2(tne, tnn, out=tne))
    swing *= 0.5
    return deflection, azimuth, swing


def angle_arguments(pos, vel, omega0_sq, args) -> None:
    """Kernel: the arguments of :func:`_angle_columns`' three arctangents, sample by sample, into ``args``
    (4, samples): the bob's horizontal distance hypot(x, y) (m) and −z (m) for the deflection, then
    2 T_ne and T_nn − T_ee of the Fradkin tensor (m²/s²) for the swing azimuth; the same operations in
    the same order as there, so the same doubles (``numpy.hypot``: compiled, the C library's ``hypot``
    as in numpy's loop; not ``math.hypot``, whose CPython algorithm differs in the last bit).
    ``pos``, ``vel`` (3, samples): ENU, m and m/s; ``omega0_sq`` = g / l (1/s²). Plain Python on
    floats and arrays, compiled by :func:`~gyro_instrument.core.jit.compiled`."""
    for i in range(pos.shape[1]):
        e, n, vn, ve = pos[0, i], pos[1, i], vel[1, i], vel[0, i]
        args[0, i] = np.hypot(e, n)
        args[1, i] = -pos[2, i]
        wn = omega0_sq * n
        args[2, i] = (wn * e + vn * ve) * 2.0
        args[3, i] = (wn * n + vn * vn) - (omega0_sq * e * e + ve * ve)


def unwrap_in_place(angle, state, factor) -> None:
    """Kernel: :class:`~gyro_instrument.core.angles.Unwrapper` on ``angle`` (rad, wrapped to (−π, π]) in
    place, then times ``factor``: each sample less 2π × the whole turns rint(Δ / 2π) summed over the
    differences Δ from the previous sample, the same doubles (the turns are integers, exact in their
    sum). ``state`` = [1 if a previous block's last sample is held else 0, that sample (rad), the turns
    so far], carried from call to call and updated. Plain Python, compiled by
    :func:`~gyro_instrument.core.jit.compiled`."""
    two_pi = 2.0 * np.pi
    held, prev, turns = state[0] != 0.0, state[1], state[2]
    for i in range(angle.size):
        a = angle[i]
        if held:
            turns += np.rint((a - prev) / two_pi)
        held, prev = True, a
        angle[i] = (a - two_pi * turns) * factor
    state[0], state[1], state[2] = 1.0 if held else 0.0, prev, turns


@functools.cache
def compiled_column_kernels() -> tuple:
    """(:func:`angle_arguments`, :func:`unwrap_in_place`) compiled (:func:`~gyro_instrument.core.jit.compiled`),
    or the plain functions when compilation is off."""
    return jit.compiled(angle_arguments), jit.compiled(unwrap_in_place)


def compiled_pendulum_columns(pos, vel, omega0_sq, unwrappers=None, chunk=16384) -> dict:
    """:func:`pendulum_columns` with its arithmetic and unwrapping in the kernels of
    :func:`compiled_column_kernels` and only the arctangents on numpy (its vectorised ``arctan2``): the
    same doubles, ``chunk`` samples at a time through a scratch of 4 × ``chunk`` (in cache); the
    ``unwrappers`` are carried and left as :func:`pendulum_columns` leaves them."""
    unwrappers = unwrappers if unwrappers is not None else (Unwrapper(), Unwrapper())
    arguments, unwrap = compiled_column_kernels()
    size = pos.shape[1]
    out = {"deflection": np.empty(size), "azimuth": np.empty(size), "swing_azimuth": np.empty(size)}
    states = [np.array([float(u.prev is not None), u.prev or 0.0, u.turns]) for u in unwrappers]
    scratch = np.empty((4, min(chunk, size)))
    for a in range(0, size, chunk):
        b = min(a + chunk, size)
        args = scratch[:, :b - a]
        arguments(pos[:, a:b], vel[:, a:b], omega0_sq, args)
        np.arctan2(args[0], args[1], out=out["deflection"][a:b])
        unwrap(np.arctan2(pos[0, a:b], pos[1, a:b], out=out["azimuth"][a:b]), states[0], 1.0)
        unwrap(np.arctan2(args[2], args[3], out=out["swing_azimuth"][a:b]), states[1], 0.5)
    for u, st in zip(unwrappers, states):
        if st[0]:
            u.prev, u.turns = float(st[1]), float(st[2])
    return {**out, "x_east": pos[0], "y_north": pos[1], "z_up": pos[2]}
