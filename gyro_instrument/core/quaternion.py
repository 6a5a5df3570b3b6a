"""Quaternions (scalar first, Hamilton product) and rotations, shared by the instruments that
carry an orientation (free gyroscope, Puiseux's body).

A quaternion q = (w, x, y, z) rotates body vectors into world vectors: v_world = q ⊗ (0, v) ⊗ q*,
whose matrix is :func:`quat_to_matrix`; the kinematics is q̇ = ½ q ⊗ (0, ω_body).
"""

import math

import numpy as np


def quat_mul(a, b) -> np.ndarray:
    """Hamilton product a ⊗ b of quaternions (scalar first), broadcasting over leading axes."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def quat_from_rotvec(axis_unit, angle) -> np.ndarray:
    """Quaternions of rotations by ``angle`` (array, rad) about one unit ``axis_unit``."""
    half = 0.5 * np.asarray(angle, dtype=float)
    s = np.sin(half)
    return np.concatenate([np.cos(half)[..., None], s[..., None] * np.asarray(axis_unit, dtype=float)], axis=-1)


def quat_to_matrix(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of (not necessarily unit) quaternions (..., 4)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def rotation_matrix(q) -> np.ndarray:
    """Rotation matrix (body -> world) of one quaternion q = (w, x, y, z), normalised first.

    The same matrix as :func:`quat_to_matrix` for a single quaternion, normalised by
    ``numpy.linalg.norm(q)`` of the whole vector (Puiseux's body has always used this form; the
    two normalisations can differ in the last bit, so its initial state is kept bit-identical).
    """
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quat_from_matrix(R) -> np.ndarray:
    """Unit quaternion (scalar first) of one rotation matrix (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    tr = np.trace(R)
    cands = [tr, R[0, 0], R[1, 1], R[2, 2]]
    i = int(np.argmax(cands))
    if i == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        q = [w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)]
    elif i == 1:
        x = 0.5 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = [(R[2, 1] - R[1, 2]) / (4 * x), x, (R[0, 1] + R[1, 0]) / (4 * x), (R[0, 2] + R[2, 0]) / (4 * x)]
    elif i == 2:
        y = 0.5 * math.sqrt(1.0 - R[0, 0] + R[1, 1] - R[2, 2])
        q = [(R[0, 2] - R[2, 0]) / (4 * y), (R[0, 1] + R[1, 0]) / (4 * y), y, (R[1, 2] + R[2, 1]) / (4 * y)]
    else:
        z = 0.5 * math.sqrt(1.0 - R[0, 0] - R[1, 1] + R[2, 2])
        q = [(R[1, 0] - R[0, 1]) / (4 * z), (R[0, 2] + R[2, 0]) / (4 * z), (R[1, 2] + R[2, 1]) / (4 * z), z]
    q = np.array(q)
    return q / np.linalg.norm(q) * (1.0 if q[0] >= 0 else -1.0)


def rotate_about(v, axis_unit, angle) -> np.ndarray:
    """Rotate vectors ``v`` (..., 3) about a unit axis by ``angle`` (broadcast), Rodrigues'
    formula with 1 − cos φ written 2 sin²(φ/2) (no cancellation at small angles)."""
    v = np.asarray(v, dtype=float)
    a = np.asarray(axis_unit, dtype=float)
    ang = np.asarray(angle, dtype=float)[..., None]
    return (v * np.cos(ang) + np.cross(a, v) * np.sin(ang)
            + a * (v @ a)[..., None] * (2.0 * np.sin(0.5 * ang) ** 2))
