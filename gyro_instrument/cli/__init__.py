"""``gyro-instrument``: command-line front end.

Subcommands: ``describe`` (instruments, active effects and every supported effect's
estimated size), ``simulate`` (CSV of every instrument channel), and the later stages.
Bad input exits with status 2 and one line naming the field, the value and the valid range;
Ctrl-C exits with status 130 and the one line ``gyro-instrument: interrupted``, leaving no
half-written output (see :func:`guarded`).

* :mod:`.parser`: the one argument parser (``run`` included) and the scene arguments;
* :mod:`.commands`: the subcommands and :func:`main`;
* :mod:`.simulate`: the ``simulate`` table, streamed;
* :mod:`.text`: what the commands print.

The work itself is :mod:`gyro_instrument.api`'s, shared with the ROS nodes and the tests.
"""

#: where each public name lives; imported on first use (PEP 562), so that ``python -m
#: gyro_instrument.cli`` imports nothing heavy before ``__main__``'s interrupt guard
_HOMES = {
    "gyro_instrument.api": ("describe", "replay_bag", "to_jsonable"),
    "gyro_instrument.cli.commands": ("COMMANDS", "closed_pipe", "guarded", "interrupted", "main", "one_line",
                                     "run_command"),
    "gyro_instrument.cli.parser": ("EXIT_BAD_INPUT", "EXIT_CLOSED_PIPE", "EXIT_INTEGRATION_FAILED",
                                   "EXIT_INTERRUPTED", "add_run_command", "add_scene_arguments", "add_scene_option",
                                   "build_parser", "scene_arg", "scene_from_args"),
    "gyro_instrument.cli.simulate": ("check_disk", "output_step", "simulate_scene", "simulate_to_file",
                                     "stream_scene", "terminal_progress", "write_csv"),
    "gyro_instrument.cli.text": ("print_description", "print_estimate", "print_plan"),
}
_HOME = {name: module for module, names in _HOMES.items() for name in names}


def __getattr__(name) -> object:
    """A public name of the CLI, imported from its module on first use."""
    import importlib
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_HOME[name]), name)
    globals()[name] = value
    return value


__all__ = ["COMMANDS", "EXIT_BAD_INPUT", "EXIT_CLOSED_PIPE", "EXIT_INTEGRATION_FAILED", "EXIT_INTERRUPTED",
           "add_run_command", "add_scene_arguments", "add_scene_option", "build_parser", "check_disk", "closed_pipe",
           "describe", "guarded", "interrupted", "main", "one_line", "output_step", "print_description",
           "print_estimate", "print_plan", "replay_bag", "run_command", "scene_arg", "scene_from_args",
           "simulate_scene", "simulate_to_file", "stream_scene", "terminal_progress", "to_jsonable", "write_csv"]
