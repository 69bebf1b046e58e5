"""``python -m vpcontact ARGS``: the same command line as ``vpcontact ARGS``."""

import sys

from .cli import main

sys.exit(main())
