"""A simulator's output as ordered, serialized messages, block by block (no rclpy): what the
simulator nodes publish and the suite delivers.

:class:`SimulatorStream` pulls one :class:`~gyro_instrument.recording.joints.JointBlock` at a time
(integrating a window of ``window_s`` simulated seconds only when the samples asked for go past the
current one), encodes each publication's messages with the CDR codec
(:mod:`gyro_instrument.recording.cdr`) and orders them: the clock first, then instrument by
instrument (scene order) each of its :func:`~gyro_instrument.recording.topics.publications`, each
topic's messages in sample order. The markers are handed out as geometry
(:mod:`gyro_instrument.recording.visual`) for the node to fill into messages.
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.memory import sample_count
from gyro_instrument.recording.cdr import CLOCK_LAYOUT, joint_state_layout, point_stamped_layout
from gyro_instrument.recording.joints import joint_blocks
from gyro_instrument.recording.topics import JOINT_STATE_TYPE, MARKER_TYPE, publications, visual_every
from gyro_instrument.recording.visual import AxisVisual, PendulumVisual

#: instruments stand this far apart along east in ``site_enu`` (m), in the scene's order
SPACING_M = 3.0


@dataclass
class Batch:
    """Messages of one :meth:`SimulatorStream.batch`, in publishing order.

    ``messages``: [(key, [bytes or marker geometry])], key ``"clock"`` or ``(instrument,
    publication key)``; ``stamps``: key -> the markers' stamps (ns from release); ``offsets``: key
    -> sample offsets in the batch of a sparse publication's messages; ``count``: samples covered.
    """

    messages: list
    stamps: dict
    offsets: dict
    count: int


class SimulatorStream:
    """The messages of the scene's instruments of the given types (and the clock when
    ``clock``), sample range by sample range.

    Parameters
    ----------
    scene : Scene
    insts : dict
        Every instrument of the scene (name -> Instrument); those of ``kinds`` are published.
    kinds : tuple of str
        Instrument types this simulator hosts.
    seed : int or None
        Sensor seed (None: the scene's).
    window_s : float
        Simulated seconds integrated per block.
    clock : bool
        Publish the clock (one tick per sample).
    frame_prefix : str
        Put before every frame id (``frame_prefix`` parameter, checked by the caller).

    Attribute ``stamp_offset_ns`` (default 0) shifts every stamp encoded (``stamp_epoch``).
    """

    def __init__(self, scene, insts, kinds, seed, window_s, clock, frame_prefix="") -> None:
        self.stamp_offset_ns = 0
        self.frame_prefix = frame_prefix
        self.chosen = {n: inst for n, inst in insts.items() if inst.type_name in kinds}
        self.samples = sample_count(scene) if self.chosen else 0
        self.step_ns = 1e9 / scene.sample_rate_hz
        self.clock = bool(clock)
        self.pubs = {name: publications(name, inst) for name, inst in self.chosen.items()}
        self.layouts = {(name, p.key): _layout(p, frame_prefix) for name, ps in self.pubs.items() for p in ps}
        self.blocks = joint_blocks(scene, kinds, seed, float(window_s), insts) if self.chosen else None
        self.block = None
        self.blocks_pulled = 0
        self.index = 0
        self.every = visual_every(scene.sample_rate_hz)
        self.visuals = _visuals(scene, insts, self.chosen, self.pubs, self.samples, self.step_ns, self.every)

    def block_ready(self, k) -> bool:
        """True when the next ``k`` samples (or the rest of the run) are already integrated."""
        b = self.block
        end = 0 if b is None else b.start + b.t_ns.size
        return self.index >= self.samples or min(self.index + k, self.samples) <= end

    def sample_index(self, t_ns) -> int:
        """How many samples have a stamp <= ``t_ns`` (ns from release): stamps are round(i · 1e9 / f)."""
        i = int(math.floor(t_ns / self.step_ns)) + 2
        while i > 0 and round((i - 1) * self.step_ns) > t_ns:
            i -= 1
        return min(i, self.samples)

    def _next_block(self):
        block = next(self.blocks, None) if self.blocks is not None else None
        if block is not None:
            self.blocks_pulled += 1
            t_s = block.t_ns / 1e9
            for name, vis in self.visuals.items():
                for v in vis.values():
                    v.push(block.start, t_s, block.streams[name])
        self.block = block
        return block

    def batch(self, k) -> Batch:
        """The messages of samples ``index`` .. ``index + k - 1`` (fewer at the end; none when the
        run is over), integrating blocks as needed; advances ``index``."""
        i0 = self.index
        i1 = min(i0 + max(int(k), 0), self.samples)
        out = Batch({}, {}, {}, 0)
        while self.index < i1:
            b = self.block
            if b is None or self.index >= b.start + b.t_ns.size:
                if self._next_block() is None:
                    break
                continue
            self._segment(self.index, min(i1, b.start + b.t_ns.size), i0, out)
        out.messages = list(out.messages.items())
        out.count = self.index - i0
        return out

    def _segment(self, a, z, i0, out):
        """Samples a .. z - 1 (all in the current block) into ``out``."""
        b = self.block
        ja, jz = a - b.start, z - b.start
        off = int(self.stamp_offset_ns or 0)
        t = b.t_ns[ja:jz] + off if off else b.t_ns[ja:jz]

        def add(key, datas):
            out.messages.setdefault(key, []).extend(datas)
        if self.clock:
            add("clock", CLOCK_LAYOUT.encode(t))
        marks = np.arange(-(-a // self.every) * self.every, z, self.every)
        local = marks - b.start
        for name, pubs in self.pubs.items():
            s = b.streams[name]
            vis = self.visuals.get(name, {})
            for p in pubs:
                key = (name, p.key)
                if not p.sparse:
                    add(key, self.layouts[key].encode(t, *_dense_rows(p.key, s, ja, jz)))
                    continue
                out.offsets.setdefault(key, []).extend((marks - i0).tolist())
                if p.type_name != MARKER_TYPE:
                    add(key, self.layouts[key].encode(b.t_ns[local] + off, *vis[p.key].rows(local)))
                    continue
                shown = vis.get("axis") or vis["plane"]
                add(key, [shown.markers(int(i), int(j), s) for i, j in zip(marks, local)])
                out.stamps.setdefault(key, []).extend(int(x) + off for x in b.t_ns[local])
        self.index = z


def _dense_rows(key, s, ja, jz):
    """The per-sample columns of publication ``key`` of a block's ``JointStream``."""
    if key == "joints":
        return s.position[ja:jz], s.velocity[ja:jz], s.effort[ja:jz]
    if key == "bob":
        return (s.bob_enu_m[ja:jz],)
    return (s.extra["contact_point_m"][ja:jz],)


def _layout(p, prefix=""):
    if p.type_name == MARKER_TYPE:
        return None
    if p.type_name == JOINT_STATE_TYPE:
        return joint_state_layout(p.names)
    return point_stamped_layout(prefix + p.frame_id)


def _visuals(scene, insts, chosen, pubs, n, step_ns, every):
    """{instrument: {"plane": PendulumVisual, "axis": AxisVisual}} of the instruments with markers."""
    order = list(insts)
    t_last = round((n - 1) * step_ns) / 1e9 if n else 0.0
    g = scene.site.gravity_m_s2
    out = {}
    for name, inst in chosen.items():
        origin = np.array([SPACING_M * order.index(name), 0.0, 0.0])
        keys = {p.key for p in pubs[name]}
        vis = {}
        if "plane" in keys:
            length = inst.observation().length_m
            vis["plane"] = PendulumVisual(origin, length, 2 * math.pi * math.sqrt(length / g), n, t_last, every)
        if "axis" in keys:
            vis["axis"] = AxisVisual(origin, inst)
        if vis:
            out[name] = vis
    return out
