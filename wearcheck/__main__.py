"""``python -m wearcheck``: the command line."""

import sys

from wearcheck.cli import main

sys.exit(main())
