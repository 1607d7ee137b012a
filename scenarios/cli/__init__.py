"""The ``rnhql`` command: the parser (:mod:`~scenarios.cli.app`) and one module per subcommand.

The top of the stack: may import every other part of ``scenarios``, nothing imports it.
"""

from scenarios.cli.app import main

__all__ = ["main"]
