"""One run: :class:`~scenarios.runs.spec.RunSpec`, one run end to end (grid or physics, the
one physics training loop and its grading), and the ``results.json`` contract.

May import ``recording``, ``figures``, ``sim`` and ``learning``; never ``sweep``,
``studies``, ``bench`` or ``cli``.
"""
