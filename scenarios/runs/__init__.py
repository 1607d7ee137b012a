"""One run: :class:`~scenarios.runs.spec.RunSpec`, one run end to end (grid or physics, the
one physics training loop and its grading), and the ``results.json`` contract.

May import ``recording``, ``figures``, ``sim`` and ``learning``; never ``sweep``,
``studies``, ``bench`` or ``cli``.
"""

from scenarios.signals import hold_stop_signals_while_compiling

# every run compiles or loads numba kernels: a Ctrl-C (SIGTERM, SIGHUP) that arrives during
# a compile is acted on as it ends, not inside LLVM's callbacks (see scenarios.signals)
hold_stop_signals_while_compiling()
