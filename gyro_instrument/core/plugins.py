"""Plug-ins: instruments, effects and measurement kinds found through entry points (issue 35 item 2).

A package adds to gyro_instrument by declaring entry points in one of :data:`GROUPS` (its
``setup.py`` / ``pyproject.toml``; a ``*.dist-info/entry_points.txt`` on ``sys.path`` is enough):

.. code-block:: ini

    [gyro_instrument.instruments]
    rate_table = my_package.rate_table:RateTable
    [gyro_instrument.effects]
    eddy_current = my_package.eddy:EddyCurrent
    [gyro_instrument.measurements]
    rate_difference = my_package.kind:RateDifference

Each entry point names the class; the name left of ``=`` is the class's registry key (an instrument's
``type_name``, an effect's or a kind's ``name``). The package's own instruments, effects and kinds are entry points of
the same groups (``setup.py``), so ``importlib.metadata.entry_points(group=...)`` lists them; each
registry also names them in its module (:func:`discover`'s ``shipped``), which fixes their order (the
order effects' terms are summed, so results do not depend on how the metadata lists them) and lets a
source checkout whose installed metadata predates an addition still find it.

A plug-in that cannot be loaded or is refused by its registry (an incomplete protocol, a name already
taken) is left out: the registry of the shipped ones is unchanged, and one line naming the plug-in
and what is wrong goes to :data:`REFUSED` (the CLI prints each on stderr before it runs).

Model: pytest's ``pytest11`` plug-ins; rosbags' storage plug-in dict.
"""

from importlib import import_module
from importlib.metadata import entry_points

#: The entry-point groups, by registry.
GROUPS = {"instruments": "gyro_instrument.instruments", "effects": "gyro_instrument.effects",
          "measurements": "gyro_instrument.measurements"}

#: One line per plug-in left out (load failure or refusal), in discovery order.
REFUSED = []


def load_object(spec) -> object:
    """The object a ``module:attribute`` string names (``module:Outer.attr`` works too)."""
    module, _, attr = spec.partition(":")
    obj = import_module(module.strip())
    for part in attr.strip().split(".") if attr.strip() else ():
        obj = getattr(obj, part)
    return obj


def _entry_points():
    """Every entry point of the environment, read once per process (a scan of every distribution's
    metadata, about 0.15 s with ROS installed)."""
    if not _SCANNED:
        _SCANNED.append(entry_points())
    return _SCANNED[0]


_SCANNED = []


def plugin_label(ep) -> str:
    """``'<dist> <name> = <value>'`` of an entry point: which plug-in, as its metadata names it."""
    dist = getattr(ep, "dist", None)
    owner = f"{dist.name} " if dist is not None and getattr(dist, "name", None) else ""
    return f"{owner}[{ep.group}] {ep.name} = {ep.value}"


def discover(kind, register, registered, shipped=(), key="name") -> list:
    """Register the shipped objects of registry ``kind`` (a key of :data:`GROUPS`), then every entry
    point of its group that is not one of them.

    Parameters
    ----------
    kind : str
        ``instruments``, ``effects`` or ``measurements``.
    register : callable
        The registry's ``register(obj)``; raises ValueError naming what is wrong.
    registered : callable
        ``registered(obj) -> bool``: True when ``obj`` itself is already in the registry (a shipped
        object listed again by the installed metadata).
    shipped : sequence
        The shipped objects (or their ``module:attribute``), in registry order.
    key : str
        The attribute holding an object's registry key (``type_name`` for instruments, ``name``
        otherwise); an entry point's name must be it.

    Returns
    -------
    list of str
        The lines of the plug-ins left out (also appended to :data:`REFUSED`).

    Raises
    ------
    ValueError
        When a shipped object is refused (a bug of the package, not of a plug-in).
    """
    for spec in shipped:
        register(load_object(spec) if isinstance(spec, str) else spec)
    refused = []
    for ep in _entry_points().select(group=GROUPS[kind]):
        try:
            obj = ep.load()
        except Exception as exc:          # noqa: BLE001 - any failure of a plug-in's import is reported
            refused.append(f"plug-in {plugin_label(ep)} cannot be loaded: {type(exc).__name__}: {exc}")
            continue
        if registered(obj):
            continue
        declared = getattr(obj, key, None)
        if declared != ep.name:
            refused.append(f"plug-in {plugin_label(ep)} refused: the entry point's name {ep.name!r} is not the "
                           f"{key} its object declares ({declared!r})")
            continue
        try:
            register(obj)
        except ValueError as exc:
            refused.append(f"plug-in {plugin_label(ep)} refused: {str(exc).removeprefix('register: ')}")
    REFUSED.extend(r for r in refused if r not in REFUSED)
    return refused
