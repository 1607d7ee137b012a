"""``python -m scenarios.cli``: the same as the ``rnhql`` console script."""

import sys

from scenarios.cli import main

sys.exit(main())
