"""``python -m wearcheck``: the command line."""

import sys

from wearcheck.comparisons.cli import main

sys.exit(main())
