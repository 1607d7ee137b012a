"""The parts methods are built of: tabular rules, traces, RBF and MLP approximators,
the move model, the free-space model and the walks over it, the tally.
"""
