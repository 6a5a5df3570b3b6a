"""``python -m gyro_instrument.cli``: the CLI imported (numpy, scipy: about a second) inside the
interrupt guard, so a Ctrl-C during the imports is one line too (:mod:`gyro_instrument.cli.interrupt`)."""

import importlib
import sys

from gyro_instrument.cli.interrupt import guarded_import, interrupted_while_importing

try:
    main = guarded_import(lambda: importlib.import_module("gyro_instrument.cli.commands").main)
except KeyboardInterrupt:
    interrupted_while_importing()
sys.exit(main())
