"""A sweep: many runs, their outputs and their owner (``run_sweep``): where the runs
execute, the output folder and its lock, resume state, the comparison recording, what a
stopped sweep keeps, and the brief it prints.

May import ``runs``, ``recording``, ``figures``, ``sim`` and ``learning``; never
``studies``, ``bench`` or ``cli``.
"""
