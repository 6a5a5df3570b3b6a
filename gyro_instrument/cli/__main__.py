"""``python -m gyro_instrument.cli``: the CLI imported (numpy, scipy: about a second) inside the
interrupt guard, so a Ctrl-C during the imports is one line too."""

import sys

try:
    from gyro_instrument.cli import main
except KeyboardInterrupt:
    print("gyro-instrument: interrupted", file=sys.stderr)
    sys.exit(130)
sys.exit(main())
