"""``python -m sim.cli``: the ``reform-sim`` command."""

import sys

from sim.cli import console_main

sys.exit(console_main())
