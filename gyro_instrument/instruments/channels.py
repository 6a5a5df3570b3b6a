"""Channels and joint layouts: what a record's channels are, and how joints carry them.

A :class:`Channel` carries its unit and meaning (an angle, a measured rate, a position): the table
reader converts units by asking it (:meth:`~.observation.Observation.table_channels`), never by a
list of channel names. A :class:`JointLayout` is the one definition that writes an instrument's
``sensor_msgs/JointState`` rows and reads them back. Both are re-exported by :mod:`.observation`.
"""

from dataclasses import dataclass

#: What a channel is (:attr:`Channel.meaning`): an angle (rad), a measured rate (rad/s: a rotor's
#: spin, a rate gyroscope's reading), a position (m).
ANGLE, RATE, POSITION = "angle", "rate", "position"


@dataclass(frozen=True)
class Channel:
    """One channel of a record: its key, unit and meaning (:data:`ANGLE` in ``rad``, :data:`RATE` in
    ``rad/s``, :data:`POSITION` in ``m``). A table reader converts units by asking it."""

    name: str
    unit: str
    meaning: str = ANGLE


@dataclass(frozen=True)
class JointLayout:
    """The ``sensor_msgs/JointState`` layout of an instrument: one definition to write and to read.

    Attributes
    ----------
    names : tuple of str
        Joint names in order (``Instrument.JOINTS``; prefixed ``<instrument>/`` on the wire).
    measured : tuple of str
        Record keys of the leading joints: position = the measured angle (rad), velocity = its
        centred difference.
    derived : tuple of str
        Joints after those, computed by the observation from the measured angles
        (:meth:`Observation.derived_positions`), velocity their centred difference.
    rotor : str or None
        The spin channel of a last, rotor joint (position = integrated true spin, rad; velocity =
        the measured spin, rad/s), or None (no rotor: a pendulum, a torsion pendulum).
    """

    names: tuple
    measured: tuple
    derived: tuple = ()
    rotor: str | None = None

    def __post_init__(self):
        need = len(self.measured) + len(self.derived) + (self.rotor is not None)
        if len(self.names) != need:
            parts = [f"{len(self.measured)} measured channels' joints"] + [", ".join(self.derived)] * bool(self.derived) \
                + ["one rotor joint"] * (self.rotor is not None)
            raise ValueError(f"JOINTS {self.names} must be {need}: the " + ", then ".join(parts))

    def record(self, position, velocity) -> dict:
        """The measured channels (and the spin) from joint arrays (m, len(names)): the reading half."""
        rec = {key: position[:, j].copy() for j, key in enumerate(self.measured)}
        if self.rotor is not None:
            rec[self.rotor] = velocity[:, -1].copy()
        return rec
