"""``python -m sindyship VERB ...`` runs the command line, as ``sindyship VERB ...`` does."""

import sys

from sindyship.cli import main

if __name__ == "__main__":
    sys.exit(main())
