"""Instrument samples as ``sensor_msgs/JointState`` arrays, and back (no rclpy).

One layout, used by the simulator nodes to publish, by the estimator node to rebuild its input,
and by ``replay`` to read a bag — so all three feed the estimator bit-identical floats.

Per instrument, the joints its observation lays out (:class:`~gyro_instrument.instruments.observation.JointLayout`,
names ``Instrument.JOINTS`` prefixed ``<instrument>/``; msg_docs/topics.md lists them per type):
first one per measured channel (position = the measured angle); then the joints the observation
derives from them (a pendulum's ``deflection`` = hypot of the deflections x/l, y/l and ``azimuth``
= atan2(east, north), compass, rad); then, when it has a rotor, the rotor joint (position =
integrated true spin, velocity = measured spin ρ). The observation writes the rows
(:meth:`~gyro_instrument.instruments.observation.Observation.joint_rows`) and reads them back
(:meth:`~gyro_instrument.instruments.observation.Observation.joint_record`): one definition.

Velocities of measured angles are centred differences of the published positions; rotor angles
integrate the simulated spin; efforts are 0 (no torque sensor) — every array is filled, as
Fast-CDR and independent readers expect.
"""

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.core.memory import sample_count
from gyro_instrument.core.scene import DEFAULT_WINDOW_S, sample_blocks_ns, sample_times_ns
from gyro_instrument.estimators.measure import MeasureStream, measure, simulate_truth


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
        obs = inst.observation()
        rated, spin = obs.joint_rows(rec)
        vel_cols = [_rate(t, c) for c in rated]
        if spin is None:
            pos, vel = np.column_stack(rated), np.column_stack(vel_cols)
        else:
            true_spin = cols.get(obs.spin_channel, spin)
            pos = np.column_stack(rated + [_rotor_angle(t, np.nan_to_num(true_spin))])
            vel = np.column_stack(vel_cols + [spin])
        streams[name] = JointStream(name, inst.type_name, tuple(f"{name}/{j}" for j in obs.layout.names), pos, vel,
                                    np.zeros_like(pos), obs.bob_enu_m(rec))
        if inst.SHOWS_CONTACT_POINT:          # true (simulated) contact point, body frame, (m, 3)
            streams[name].extra["contact_point_m"] = inst.contact_point_body(cols)
    return t_ns, streams


def uniform_step_s(scene, window_s=DEFAULT_WINDOW_S) -> float | None:
    """The spacing of the run's sample times (s) when every difference of ``sample_times`` is the
    same float (``numpy.gradient`` then takes its uniform-spacing formula), else None. Read block by
    block; it stops at the first unequal difference (in the first block, for most rates)."""
    first, last = None, None
    for b in sample_blocks_ns(scene, window_s):
        t = b / 1e9
        d = np.diff(np.concatenate([[last], t])) if last is not None else np.diff(t)
        if d.size:
            first = d[0] if first is None else first
            if not np.all(d == first):
                return None
        last = t[-1]
    return None if first is None else float(first)


class GradientStream:
    """``numpy.gradient(y, t)`` (edge order 1) of a run that arrives block by block, bit for bit.

    Each :meth:`push` returns the derivative of every sample received except the last one (its
    centred difference needs the next sample); :meth:`finish` returns the last one. The formulas
    are numpy's: interior ``a f[i-1] + b f[i] + c f[i+1]`` from the two local spacings, or
    ``(f[i+1] - f[i-1]) / (2 dx)`` when the whole run is uniformly spaced (``uniform_dx``, from
    :func:`uniform_step_s`); first-order one-sided differences at the two ends.
    """

    def __init__(self, uniform_dx=None):
        self.dx = uniform_dx
        self.t = np.zeros(0)
        self.y = None          # the last two rows received, (<= 2, k)
        self.started = False

    def push(self, t, y) -> np.ndarray:
        """Rows ``y`` (m, k) at times ``t`` (m,); returns the derivatives of the rows before the newest."""
        y = np.asarray(y, dtype=float)
        if self.y is None:
            self.y = np.zeros((0, y.shape[1]))
        tt, yy = np.concatenate([self.t, t]), np.concatenate([self.y, y])
        out = []
        if not self.started and tt.size >= 2:
            out.append((yy[1] - yy[0]) / (tt[1] - tt[0]))
            self.started = True
        if tt.size >= 3:
            f0, f1, f2 = yy[:-2], yy[1:-1], yy[2:]
            if self.dx is not None:
                out.append((f2 - f0) / (2.0 * self.dx))
            else:
                dx = np.diff(tt)
                dx1, dx2 = dx[:-1, None], dx[1:, None]
                a = -(dx2) / (dx1 * (dx1 + dx2))
                b = (dx2 - dx1) / (dx1 * dx2)
                c = dx1 / (dx2 * (dx1 + dx2))
                out.append(a * f0 + b * f1 + c * f2)
        self.t, self.y = tt[-2:], yy[-2:]
        if not out:
            return np.zeros((0, yy.shape[1]))
        return np.vstack([np.atleast_2d(o) for o in out])

    def finish(self) -> np.ndarray:
        """The derivative of the last row: (f[-1] - f[-2]) / (t[-1] - t[-2]); 0 for a run of one sample."""
        if self.y is None or self.y.shape[0] == 0:
            return np.zeros((0, 0))
        if self.t.size < 2:
            return np.zeros((1, self.y.shape[1]))
        return ((self.y[1] - self.y[0]) / (self.t[1] - self.t[0]))[None, :]


class _RotorStream:
    """:func:`_rotor_angle` carried across blocks (the running trapezoid sum, bit for bit)."""

    def __init__(self):
        self.t = self.spin = None
        self.total = 0.0

    def push(self, t, spin):
        if self.t is None:
            tt, ss, start = t, spin, [0.0]
        else:
            tt, ss, start = np.concatenate([[self.t], t]), np.concatenate([[self.spin], spin]), []
        inc = 0.5 * (ss[1:] + ss[:-1]) * np.diff(tt)
        ang = np.cumsum(np.concatenate([[self.total], inc]))
        ang = np.concatenate([start, ang[1:]]) if start else ang[1:]
        self.t, self.spin, self.total = t[-1], spin[-1], ang[-1]
        return np.mod(ang + np.pi, 2 * np.pi) - np.pi


@dataclass
class JointBlock:
    """One block of :func:`joint_blocks`: samples ``start`` .. ``start + len(t_ns) - 1`` of the run."""

    start: int
    t_ns: np.ndarray
    streams: dict


class _InstrumentJoints:
    """One instrument's joint layout, block by block (see :func:`joint_streams` for the layout)."""

    def __init__(self, scene, name, inst, n, seed, uniform_dx):
        self.name, self.inst = name, inst
        self.obs = inst.observation()
        self.names = tuple(f"{name}/{j}" for j in self.obs.layout.names)
        self.measure = MeasureStream(scene, inst, n, seed)
        self.grad = GradientStream(uniform_dx)
        self.rotor = None if self.obs.spin_channel is None else _RotorStream()
        self.held = None       # the newest block's last row (position, side columns), waiting for its rate

    def rows(self, t, columns):
        """(position (m, k), rated columns of position, side (m, s): the measured spin for a rotor,
        then the bob's ENU position (3 columns) when the observation shows one) of a block."""
        rec = self.measure.block(t, columns)
        rated, spin = self.obs.joint_rows(rec)
        side = []
        if spin is not None:
            true_spin = columns.get(self.obs.spin_channel, spin)
            pos = np.column_stack(rated + [self.rotor.push(t, np.nan_to_num(true_spin))])
            side.append(spin[:, None])
        else:
            pos = np.column_stack(rated)
        bob = self.obs.bob_enu_m(rec)
        if bob is not None:
            side.append(bob)
        return pos, np.column_stack(rated), np.concatenate(side, axis=1) if side else np.zeros((len(t), 0))

    def stream(self, pos, side, rates, contact=None):
        """A :class:`JointStream` from positions, their rates, and the side columns (:meth:`rows`);
        ``contact``: the true contact point (m, 3) of a body that shows it (``SHOWS_CONTACT_POINT``)."""
        k = 0 if self.rotor is None else 1
        vel = np.column_stack([rates, side[:, :k]]) if k else rates
        bob = side[:, k:k + 3] if self.obs.SHOWS_BOB_POSITION else None
        js = JointStream(self.name, self.inst.type_name, self.names, pos, vel, np.zeros_like(pos), bob)
        if contact is not None:
            js.extra["contact_point_m"] = contact
        return js


def joint_blocks(scene, kinds=None, seed=None, window_s=DEFAULT_WINDOW_S, insts=None) -> Iterator:
    """:func:`joint_streams` block by block: integrate (``Instrument.stream``), measure
    (:class:`~gyro_instrument.estimators.pipeline.MeasureStream`) and lay out one window of
    ``window_s`` simulated seconds at a time; memory is a few blocks whatever the duration.

    A sample's velocity is a centred difference that needs the next sample, so every block but the
    last is yielded one sample short and that sample leads the next block. The concatenated blocks
    equal :func:`joint_streams` bit for bit (same draws, same formulas, running sums carried).

    Parameters
    ----------
    scene : Scene
    kinds : iterable of str, optional
        Instrument types to lay out (default: every instrument).
    seed : int, optional
        Sensor seed (default the scene's).
    window_s : float
        Simulated seconds per block (:func:`~gyro_instrument.core.scene.sample_blocks_ns`).
    insts : dict, optional
        Instruments already built (name -> Instrument), default ``build_instruments(scene)``.

    Yields
    ------
    JointBlock
        ``start`` (index of the first sample), ``t_ns`` (int64 stamps from release, ns) and
        ``streams`` (instrument name -> :class:`JointStream` of that block).

    Raises
    ------
    SceneError
        On ``window_s`` when it is not a positive finite number (before anything is integrated).
    """
    from gyro_instrument.core.scene import sample_blocks
    from gyro_instrument.scenes import build_instruments
    blocks_ns = sample_blocks_ns(scene, window_s)
    first = next(blocks_ns)                  # SceneError on window_s here, before any integration
    insts = build_instruments(scene) if insts is None else insts
    chosen = {n: i for n, i in insts.items() if kinds is None or i.type_name in kinds}
    if not chosen:
        return
    n_total = sample_count(scene)
    dx = uniform_step_s(scene, window_s)
    lay = {n: _InstrumentJoints(scene, n, inst, n_total, seed, dx) for n, inst in chosen.items()}
    gens = {n: inst.stream(sample_blocks(scene, window_s)) for n, inst in chosen.items()}
    held_t, start = None, 0
    for b_ns in _chain_first(first, blocks_ns):
        t = b_ns / 1e9
        parts = {}
        for name, j in lay.items():
            parts[name] = _block_part(j, t, next(gens[name]))
        t_all = b_ns if held_t is None else np.concatenate([held_t, b_ns])
        held_t = t_all[-1:]
        if t_all.size > 1:
            yield JointBlock(start, t_all[:-1], {n: lay[n].stream(*parts[n]) for n in lay})
            start += t_all.size - 1
    yield JointBlock(start, held_t, {n: j.stream(j.held[0], j.held[1], j.grad.finish(), j.held[2])
                                     for n, j in lay.items()})


def _block_part(j, t, sim):
    """Lay out one integrated block ``sim`` (at times ``t``, s) of one instrument's joints ``j``:
    positions, side channels and contact points with the sample held back from the previous block
    in front, the block's last sample held back for the next one (its velocity needs the sample
    after it). Returns ``(pos, side, rates, contact)`` of the samples this block completes."""
    pos, rated, side = j.rows(t, sim.columns)
    rates = j.grad.push(t, rated)
    contact = j.inst.contact_point_body(sim.columns) if j.inst.SHOWS_CONTACT_POINT else None
    if j.held is not None:
        pos, side = np.concatenate([j.held[0], pos]), np.concatenate([j.held[1], side])
        if contact is not None:
            contact = np.concatenate([j.held[2], contact])
    j.held = (pos[-1:], side[-1:], None if contact is None else contact[-1:])
    return pos[:-1], side[:-1], rates, None if contact is None else contact[:-1]


def _chain_first(first, rest):
    yield first
    yield from rest


def records_from_joints(insts, samples) -> dict:
    """Estimator records from joint samples.

    Parameters
    ----------
    insts : dict
        instrument name -> instrument (from ``build_instruments``).
    samples : dict
        instrument name -> (t_ns int array, position (m, k), velocity (m, k)), joints in the
        observation's layout order (``Instrument.JOINTS``).
    """
    records = {}
    for name, (t_ns, pos, vel) in samples.items():
        t_ns = np.asarray(t_ns, dtype=np.int64)
        pos = np.asarray(pos, dtype=float).reshape(len(t_ns), -1)
        vel = np.asarray(vel, dtype=float).reshape(len(t_ns), -1)
        records[name] = insts[name].observation().joint_record(t_ns / 1e9, pos, vel)
    return records
