"""matplotlib for the views: pyplot on the Agg backend, and a configuration directory that can be written.

Its own module so that every view module (``views/__init__``, :mod:`.field_book_view`) reads it
without importing the package that imports them.
"""

import os

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import private_temp_dir, writable_dir


def pyplot() -> "object":
    """matplotlib.pyplot on the Agg backend.

    Raises
    ------
    SceneError
        matplotlib is not installed (says how to install it).
    """
    matplotlib_config_dir()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SceneError("plot", "matplotlib", "is not installed: pip install 'gyro_instrument[plot]' "
                                               "(or: pip install matplotlib)") from None
    return plt


def matplotlib_config_dir(environ=os.environ, stream=None) -> None:
    """Before matplotlib is first imported: when its configuration or cache directory under HOME
    cannot be written (a read-only or missing HOME) and ``MPLCONFIGDIR`` is not set, point it at a
    private temporary directory kept between runs (its font cache found again) with one note line;
    matplotlib itself printed two lines and made a new directory, and its font cache, every run."""
    import sys
    if environ.get("MPLCONFIGDIR") or "matplotlib" in sys.modules:
        return
    home = os.path.expanduser("~")
    dirs = [os.path.join(environ.get(xdg) or os.path.join(home, default), "matplotlib")
            for xdg, default in (("XDG_CONFIG_HOME", ".config"), ("XDG_CACHE_HOME", ".cache"))]
    if all(writable_dir(d) for d in dirs):
        return
    path = private_temp_dir("matplotlib")
    if path is not None:
        environ["MPLCONFIGDIR"] = path
        print(f"gyro-instrument: note: matplotlib's directories under HOME are not writable: using {path} "
              "(MPLCONFIGDIR)", file=stream or sys.stderr)
