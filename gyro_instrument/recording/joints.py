"""Instrument samples as ``sensor_msgs/JointState`` arrays, and back (no rclpy).

One layout, used by the simulator nodes to publish, by the estimator node to rebuild its input,
and by ``replay`` to read a bag — so all three feed the estimator bit-identical floats.

Per instrument, the joints its class declares (``Instrument.JOINTS``, prefixed ``<instrument>/``;
msg_docs/topics.md lists them per type): first one per measured channel (``MEASURED_CHANNELS``,
position = the measured angle); then, for a pendulum (``IS_PENDULUM``), ``deflection`` = hypot of
the measured deflections x/l, y/l and ``azimuth`` = atan2(east, north) (compass, rad); otherwise
one rotor joint (position = integrated true spin, velocity = measured spin ρ).

Velocities of measured angles are centred differences of the published positions; rotor angles
integrate the simulated spin; efforts are 0 (no torque sensor) — every array is filled, as
Fast-CDR and independent readers expect.
"""

from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.core.scene import sample_times_ns
from gyro_instrument.estimators.pipeline import measure, simulate_truth


@dataclass
class JointStream:
    """Arrays for one instrument: ``position``, ``velocity``, ``effort`` of shape (m, k)."""

    instrument: str
    type_name: str
    names: tuple
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    bob_enu_m: np.ndarray = None      # (m, 3) for pendulums
    extra: dict = field(default_factory=dict)


def _rotor_angle(t, spin):
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (spin[1:] + spin[:-1]) * np.diff(t))])
    return np.mod(ang + np.pi, 2 * np.pi) - np.pi


def _rate(t, y):
    return np.gradient(y, t) if y.size > 1 else np.zeros_like(y)


def joint_streams(scene, kinds=None, seed=None, truth=None) -> tuple:
    """Simulate, measure and lay out every instrument of ``scene`` (of the given types).

    Returns
    -------
    t_ns : ndarray of int64
        Stamps from release, ns (add ``EPOCH_NS`` for ROS time).
    streams : dict
        instrument name -> :class:`JointStream`.
    """
    truth = truth or simulate_truth(scene)
    t, insts, sims = truth
    records = measure(scene, truth, seed)
    t_ns = sample_times_ns(scene)
    streams = {}
    for name, inst in insts.items():
        if kinds is not None and inst.type_name not in kinds:
            continue
        rec, cols = records[name], sims[name].columns
        names = inst.JOINTS
        if inst.IS_PENDULUM:
            e, n = (rec[c] for c in inst.MEASURED_CHANNELS)
            pos = np.column_stack([e, n, np.hypot(e, n), np.arctan2(e, n)])
            vel = np.column_stack([_rate(t, pos[:, j]) for j in range(4)])
            l = inst.pendulum_length_m()
            x, y = l * e, l * n
            bob = np.column_stack([x, y, -np.sqrt(np.maximum(l * l - x * x - y * y, 0.0))])
        else:
            chans = inst.MEASURED_CHANNELS
            spin = rec.get("spin_rate", np.zeros_like(t))
            pos_cols = [rec[c] for c in chans]
            vel_cols = [_rate(t, c) for c in pos_cols]
            true_spin = cols.get("spin_rate", spin)
            pos = np.column_stack(pos_cols + [_rotor_angle(t, np.nan_to_num(true_spin))])
            vel = np.column_stack(vel_cols + [spin])
            bob = None
        streams[name] = JointStream(name, inst.type_name, tuple(f"{name}/{j}" for j in names), pos, vel,
                                    np.zeros_like(pos), bob)
        if inst.SHOWS_CONTACT_POINT:          # true (simulated) contact point, body frame, (m, 3)
            streams[name].extra["contact_point_m"] = inst.contact_point_body(cols)
    return t_ns, streams


def records_from_joints(insts, samples) -> dict:
    """Estimator records from joint samples.

    Parameters
    ----------
    insts : dict
        instrument name -> instrument (from ``build_instruments``).
    samples : dict
        instrument name -> (t_ns int array, position (m, k), velocity (m, k)), joints in
        ``Instrument.JOINTS`` order.
    """
    records = {}
    for name, (t_ns, pos, vel) in samples.items():
        inst = insts[name]
        t_ns = np.asarray(t_ns, dtype=np.int64)
        pos = np.asarray(pos, dtype=float).reshape(len(t_ns), -1)
        vel = np.asarray(vel, dtype=float).reshape(len(t_ns), -1)
        rec = {"t": t_ns / 1e9}
        for j, key in enumerate(inst.MEASURED_CHANNELS):
            rec[key] = pos[:, j].copy()
        if not inst.IS_PENDULUM:
            rec["spin_rate"] = vel[:, -1].copy()
            model = inst.directing_model()
            if model is not None:
                rec["angle"] = rec[model.angle_channel]
        records[name] = rec
    return records
