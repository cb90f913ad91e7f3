"""``python -m sindyship.cli``."""

import sys

from . import main

sys.exit(main())
