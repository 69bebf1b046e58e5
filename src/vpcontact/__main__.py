"""``python -m vpcontact ARGS``: the same command line as ``vpcontact ARGS``."""

import sys

from .drivers.cli import main

sys.exit(main())
